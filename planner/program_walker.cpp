#include "planner/program_walker.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::planner {

using Eigen::Vector3d;

double round4(double v) {
  const double r = std::round(v * 1e4) / 1e4;
  return r == 0 ? 0.0 : r;  // no negative zero
}
double round3(double v) {
  const double r = std::round(v * 1e3) / 1e3;
  return r == 0 ? 0.0 : r;
}

NotedProgram newNotedProgram(const parts::Machine& m, const std::string& role, const std::string& file, int number,
                             const std::string& title) {
  NotedProgram p;
  p.role = role;
  p.file = file;
  p.program.title = title;
  p.program.number = number;
  p.program.work_offset = m.work_offset;
  p.program.has_a_axis = m.a.present;
  p.program.has_b_axis = m.b.present;
  p.program.has_c_axis = m.c.present;
  return p;
}

void NotedProgram::add(gcode::Op op, OpNote note) {
  if (!gcode::allFinite(op))
    throw GeometryError(file + ": " + note.where + ": a coordinate, feed or time that is not a finite number " +
                        "(the description's layout gives none here)");
  program.ops.push_back(std::move(op));
  notes.push_back(std::move(note));
}

namespace {
template <class... Ts>
struct Overloaded : Ts... { using Ts::operator()...; };
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;
}  // namespace

ProgramWalker::ProgramWalker(const parts::Machine& m, std::vector<WalkerTool> tools) : m_(m), tools_(std::move(tools)) {
  // As the simulator: at rest at the top of Z, X and Y at the C axis.
  gauge_ = Vector3d(std::clamp(m.c_axis_centre_mm.x(), m.x.min_mm, m.x.max_mm),
                    std::clamp(m.c_axis_centre_mm.y(), m.y.min_mm, m.y.max_mm), m.z.max_mm);
  tool_.number = m.tool_change.empty_tool;
  WalkerTool empty;
  empty.number = m.tool_change.empty_tool;
  tools_.push_back(empty);
  WalkerTool probe;
  probe.number = m.probe.tool;
  probe.length_mm = m.probe.length_mm;
  probe.radius_mm = m.probe.tip_diameter_mm / 2;
  probe.probe = true;
  tools_.push_back(probe);
}

void ProgramWalker::fail(const OpNote& note, const std::string& message) const {
  throw SafetyError((program_ ? *program_ + ": " : std::string()) + note.where + ": " + message);
}

const WalkerTool& ProgramWalker::toolFor(int number, const OpNote& note) const {
  for (const auto& t : tools_)
    if (t.number == number) return t;
  fail(note, "tool T" + std::to_string(number) + " is neither one of the part's tools, the probe nor the empty spindle");
}

void ProgramWalker::checkTravel(const Vector3d& g, const OpNote& note, const char* what) const {
  const parts::LinearAxis* ax[3] = {&m_.x, &m_.y, &m_.z};
  const char* names = "XYZ";
  for (int i = 0; i < 3; ++i)
    if (!(g(i) >= ax[i]->min_mm - 1e-9 && g(i) <= ax[i]->max_mm + 1e-9)) {  // NaN fails too
      std::ostringstream s;
      s << what << " needs " << names[i] << " = " << formatNumber(g(i), 3) << " mm (gauge line = tip + tool length "
        << formatNumber(tool_.length_mm, 3) << " mm), outside the " << names[i] << " travel [" << formatNumber(ax[i]->min_mm, 3)
        << ", " << formatNumber(ax[i]->max_mm, 3) << "] of " << m_.file;
      fail(note, s.str());
    }
}

void ProgramWalker::checkCTravel(double c, const OpNote& note, const char* what) const {
  if (!m_.c.present) fail(note, std::string(what) + " on a machine without a C axis (" + m_.file + ")");
  if (!std::isfinite(c) || (!m_.c.continuous && !(c >= m_.c.min_deg - 1e-9 && c <= m_.c.max_deg + 1e-9)))
    fail(note, std::string(what) + " needs C = " + formatNumber(c, 3) + " deg, outside the C travel [" +
                   formatNumber(m_.c.min_deg, 3) + ", " + formatNumber(m_.c.max_deg, 3) + "] of " + m_.file);
}

void ProgramWalker::tilt(const parts::RotaryAxis& axis, const char* name, double deg, double& now, const OpNote& note) {
  const std::string n(name);
  if (!axis.present) fail(note, n + " move on a machine without a" + (n == "A" ? "n " : " ") + n + " axis (" + m_.file + ")");
  if (!axis.continuous && !(deg >= axis.min_deg - 1e-9 && deg <= axis.max_deg + 1e-9))
    fail(note, n + " = " + formatNumber(deg, 3) + " deg is outside the " + n + " travel of " + m_.file);
  const double dt = rotaryIndexSeconds(deg - now, axis);
  times_.rotary_index_s += dt;
  t_ += dt;
  now = deg;
}

void ProgramWalker::checkLinearFeed(double F, const OpNote& note, const char* what) const {
  const double fmax = std::min({m_.x.max_feed_mm_per_min, m_.y.max_feed_mm_per_min, m_.z.max_feed_mm_per_min});
  if (!(F > 0)) fail(note, std::string(what) + " without a feed rate");
  if (F > fmax + 1e-9)
    fail(note, std::string(what) + " at F" + formatNumber(F, 3) + " mm/min exceeds the machine's maximum feed " +
                   formatNumber(fmax, 3) + " mm/min (slowest axis, " + m_.file + ")");
}

void ProgramWalker::motion(MotionKind kind, const char* what, const Vector3d& to_tip, double to_c, const OpNote& note) const {
  if (!check_) return;
  Motion mo;
  mo.program = program_;
  mo.note = &note;
  mo.kind = kind;
  mo.what = what;
  mo.from_tip = tip();
  mo.to_tip = to_tip;
  mo.from_c = c_;
  mo.to_c = to_c;
  mo.tool = tool_;
  check_(mo);
}

void ProgramWalker::run(const NotedProgram& p, const OpCallback& on_op) {
  program_ = &p.file;
  const auto& ops = p.program.ops;
  // Loops: run the body `count` times (nested loops by recursion on the index range).
  std::function<void(std::size_t, std::size_t)> range = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (const auto* l = std::get_if<gcode::LoopBegin>(&ops[i])) {
        int depth = 1;
        std::size_t j = i + 1;
        for (; j < end; ++j) {
          if (std::holds_alternative<gcode::LoopBegin>(ops[j])) ++depth;
          if (std::holds_alternative<gcode::LoopEnd>(ops[j]) && --depth == 0) break;
        }
        if (j >= end) fail(p.notes[i], "a loop without its end");
        if (l->count < 0) fail(p.notes[i], "a loop with a negative count");
        for (int k = 0; k < l->count; ++k) range(i + 1, j);
        i = j;
        continue;
      }
      const double t0 = t_;
      step(ops[i], p.notes[i]);
      if (on_op) on_op(i, t0, t_);
    }
  };
  range(0, ops.size());
  program_ = nullptr;
}

void ProgramWalker::step(const gcode::Op& op, const OpNote& note) {
  if (!gcode::allFinite(op)) fail(note, "a coordinate, feed or time that is not a finite number");
  const double L = tool_.length_mm;
  std::visit(
      Overloaded{
          [&](const gcode::Comment&) {},
          [&](const gcode::LoopBegin&) {},
          [&](const gcode::LoopEnd&) {},
          [&](const gcode::Rapid& r) {
            Vector3d to = tip();
            if (r.x) to.x() = *r.x;
            if (r.y) to.y() = *r.y;
            if (r.z) to.z() = *r.z;
            const Vector3d g = to + Vector3d(0, 0, L);
            checkTravel(g, note, "rapid move");
            motion(MotionKind::Rapid, "rapid move", to, c_, note);
            const double dt = rapidSeconds(m_, g - gauge_);
            times_.rapid_s += dt;
            t_ += dt;
            gauge_ = g;
          },
          [&](const gcode::RapidMachineZ& r) {
            const Vector3d g(gauge_.x(), gauge_.y(), r.z_mm);
            checkTravel(g, note, "retract to the tool-change height");
            motion(MotionKind::MachineZ, "retract to the tool-change height", g - Vector3d(0, 0, L), c_, note);
            const double dt = rapidSeconds(m_, g - gauge_);
            times_.rapid_s += dt;
            t_ += dt;
            gauge_ = g;
          },
          [&](const gcode::RotateC& r) {
            checkCTravel(r.c_deg, note, "C index");
            motion(MotionKind::CIndex, "C index", tip(), r.c_deg, note);
            const double dt = rotaryIndexSeconds(r.c_deg - c_, m_.c);
            times_.rotary_index_s += dt;
            t_ += dt;
            c_ = r.c_deg;
          },
          [&](const gcode::RotateB& r) { tilt(m_.b, "B", r.b_deg, b_, note); },
          [&](const gcode::RotateA& r) { tilt(m_.a, "A", r.a_deg, a_, note); },
          [&](const gcode::ToolChange& tc) {
            if (spindle_rpm_ != 0) fail(note, "tool change T" + std::to_string(tc.tool) + " with the spindle turning (M5 first)");
            if (std::fabs(gauge_.z() - m_.tool_change.z_mm) > 1e-9)
              fail(note, "tool change T" + std::to_string(tc.tool) + " with the gauge line at Z " + formatNumber(gauge_.z(), 3) +
                             " mm, not at the tool-change height " + formatNumber(m_.tool_change.z_mm, 3) + " mm (G53 first)");
            const WalkerTool& t = toolFor(tc.tool, note);
            if (tc.apply_length_offset == (t.number == m_.tool_change.empty_tool))
              fail(note, "T" + std::to_string(tc.tool) + (tc.apply_length_offset ? ": the empty spindle has no length offset (G49)"
                                                                                   : ": a tool needs its length offset (G43)"));
            times_.tool_change_s += m_.tool_change.time_s;
            t_ += m_.tool_change.time_s;
            tool_ = t;
          },
          [&](const gcode::Spindle& s) {
            if (s.rpm < 0) fail(note, "a negative spindle speed");
            if (s.rpm > 0 && !tool_.cutter)
              fail(note, "spindle start with " + std::string(tool_.probe ? "the touch probe" : "no cutter") + " in the spindle");
            spindle_rpm_ = s.rpm;
          },
          [&](const gcode::Coolant&) {},
          [&](const gcode::Dwell& d) {
            if (d.seconds < 0) fail(note, "a negative dwell");
            times_.dwell_s += d.seconds;
            t_ += d.seconds;
          },
          [&](const gcode::Feed& f) {
            Vector3d to = tip();
            if (f.x) to.x() = *f.x;
            if (f.y) to.y() = *f.y;
            if (f.z) to.z() = *f.z;
            const Vector3d g = to + Vector3d(0, 0, L);
            if (note.cut && !tool_.cutter) fail(note, "a cut without a cutter in the spindle");
            if (note.cut && spindle_rpm_ == 0) fail(note, "a cut with the spindle stopped");
            checkTravel(g, note, "feed move");
            checkLinearFeed(f.feed, note, note.cut ? "cut" : "feed move");
            motion(MotionKind::Feed, note.cut ? "cut" : "feed move", to, c_, note);
            const double dt = linearFeedSeconds((g - gauge_).norm(), f.feed);
            times_.feed_s += dt;
            t_ += dt;
            gauge_ = g;
          },
          [&](const gcode::TurnC& r) {
            if (note.cut && !tool_.cutter) fail(note, "a cut without a cutter in the spindle");
            if (note.cut && spindle_rpm_ == 0) fail(note, "a cut with the spindle stopped");
            const double c_to = c_ + r.delta_deg;
            checkCTravel(c_to, note, "C feed move");
            const double F = r.feed_deg_per_min, turning = m_.c.max_turning_speed_rpm;
            if (!(F > 0)) fail(note, "a C feed move without a feed rate");
            if (F / 360.0 > turning + 1e-9)
              fail(note, "C feed F" + formatNumber(F, 3) + " deg/min = " + formatNumber(F / 360.0, 3) +
                             " rpm exceeds C's max_turning_speed " + formatNumber(turning, 3) + " rpm of " + m_.file);
            motion(MotionKind::CFeed, "C feed move", tip(), c_to, note);
            const double dt = rotaryFeedSeconds(r.delta_deg, F);
            times_.rotary_feed_s += dt;
            t_ += dt;
            c_ = c_to;
          },
          [&](const gcode::ProtectedMove& pm) {
            if (!tool_.probe) fail(note, "a protected probe move without the probe in the spindle");
            if (spindle_rpm_ != 0) fail(note, "probing with the spindle turning");
            const Vector3d to(pm.x, pm.y, pm.z), g = to + Vector3d(0, 0, L);
            checkTravel(g, note, "protected move");
            checkLinearFeed(pm.feed_mm_per_min, note, "protected move");
            motion(MotionKind::Protected, "protected move", to, c_, note);
            const double dt = linearFeedSeconds((g - gauge_).norm(), pm.feed_mm_per_min);
            times_.protected_s += dt;
            t_ += dt;
            gauge_ = g;
          },
          [&](const gcode::ProbeMove& pm) {
            if (!tool_.probe) fail(note, "a probe move without the probe in the spindle");
            if (spindle_rpm_ != 0) fail(note, "probing with the spindle turning");
            if (note.point_index < 0) throw std::logic_error(note.where + ": a probe move without its planned contact");
            const Vector3d to(pm.x, pm.y, pm.z), g = to + Vector3d(0, 0, L);
            checkTravel(g, note, "probing move end (overtravel)");
            checkLinearFeed(pm.feed_mm_per_min, note, "probing move");
            motion(MotionKind::Measuring, "probe move", to, c_, note);
            // Timed to the nominal contact, where the controller latches and stops.
            const Vector3d gc = note.contact_mm + Vector3d(0, 0, L);
            const double dt = linearFeedSeconds((gc - gauge_).norm(), pm.feed_mm_per_min);
            times_.probing_s += dt;
            t_ += dt;
            gauge_ = gc;
          },
      },
      op);
}

}  // namespace probeloop::planner
