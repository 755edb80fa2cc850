#include "planner/sphere_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/machine_chain.hpp"
#include "parts/machine_clock.hpp"
#include "planner/angles.hpp"

namespace probeloop::planner {

using Eigen::Vector3d;
using parts::Machine;
using parts::SphereArtifact;

namespace {

bool sameAngle(double a, double b) {
  const double d = std::fabs(wrapDeg360(a) - wrapDeg360(b));
  return d < 1e-9 || std::fabs(d - 360.0) < 1e-9;
}

// Walks the ops like a machine would, to time them and to check every target against the
// travel of the gauge line. Not planner/program_walker.hpp on purpose: this walker starts at
// the tool-change height above an unknown XY and times each cycle alone, the shared walker
// starts where the simulator does and runs the whole session. Its clock is the machine's
// (parts/machine_clock.hpp), the one the simulator and program_walker use (issue 29).
class Walker {
 public:
  Walker(const Machine& m, CycleTime& t) : m_(m), t_(&t) {
    gauge_ = Vector3d(0, 0, m.tool_change.z_mm);  // XY unknown at start: rapids from here
  }

  // Probing moves are timed to their nominal contact, which the op itself does not carry.
  void setNextContact(const Vector3d& c) { contact_ = c; }
  void run(const gcode::Op& op, const std::string& where) {
    std::visit([&](const auto& o) { step(o, where); }, op);
  }
  double time() const { return t_->total(); }
  // Where the time of the following ops goes (the ops before the loop, a cycle, …).
  void account(CycleTime& t) { t_ = &t; }
  Vector3d tip() const { return gauge_ - Vector3d(0, 0, length_); }

 private:
  void check(const Vector3d& gauge, const std::string& where, const std::string& what) {
    const parts::LinearAxis* ax[3] = {&m_.x, &m_.y, &m_.z};
    const char* names = "XYZ";
    for (int i = 0; i < 3; ++i) {
      if (gauge(i) < ax[i]->min_mm - 1e-9 || gauge(i) > ax[i]->max_mm + 1e-9) {
        std::ostringstream s;
        s << where << ": " << what << " needs " << names[i] << " = " << formatNumber(gauge(i), 3)
          << " mm (gauge line), outside the " << names[i] << " travel ["
          << formatNumber(ax[i]->min_mm, 3) << ", " << formatNumber(ax[i]->max_mm, 3)
          << "] of " << m_.file;
        throw SafetyError(s.str());
      }
    }
  }
  void rapidTo(const Vector3d& g, const std::string& where, const std::string& what) {
    check(g, where, what);
    t_->rapid_s += parts::rapidSeconds(m_, g - gauge_);
    gauge_ = g;
  }
  void step(const gcode::Comment&, const std::string&) {}
  void step(const gcode::Rapid& r, const std::string& where) {
    Vector3d t = tip();
    if (r.x) t.x() = *r.x;
    if (r.y) t.y() = *r.y;
    if (r.z) t.z() = *r.z;
    rapidTo(t + Vector3d(0, 0, length_), where, "rapid move");
  }
  void step(const gcode::RapidMachineZ& r, const std::string& where) {
    rapidTo(Vector3d(gauge_.x(), gauge_.y(), r.z_mm), where, "retract to tool-change height");
  }
  void step(const gcode::RotateC& r, const std::string& where) {
    if (!m_.c.continuous && (r.c_deg < m_.c.min_deg || r.c_deg > m_.c.max_deg))
      throw SafetyError(where + ": C = " + formatNumber(r.c_deg, 3) + " deg is outside the C travel");
    t_->c_index_s += parts::rotaryIndexSeconds(r.c_deg - c_, m_.c);
    c_ = r.c_deg;
  }
  void step(const gcode::RotateB& r, const std::string& where) {
    if (!m_.b.continuous && (r.b_deg < m_.b.min_deg || r.b_deg > m_.b.max_deg))
      throw SafetyError(where + ": B = " + formatNumber(r.b_deg, 3) + " deg is outside the B travel");
    t_->c_index_s += parts::rotaryIndexSeconds(r.b_deg - b_, m_.b);
    b_ = r.b_deg;
  }
  void step(const gcode::RotateA& r, const std::string& where) {
    if (!m_.a.continuous && (r.a_deg < m_.a.min_deg || r.a_deg > m_.a.max_deg))
      throw SafetyError(where + ": A = " + formatNumber(r.a_deg, 3) + " deg is outside the A travel");
    t_->c_index_s += parts::rotaryIndexSeconds(r.a_deg - a_, m_.a);
    a_ = r.a_deg;
  }
  void step(const gcode::ToolChange& tc, const std::string&) {
    t_->tool_change_s += m_.tool_change.time_s;
    length_ = tc.apply_length_offset ? m_.probe.length_mm : 0.0;
  }
  void step(const gcode::ProtectedMove& p, const std::string& where) {
    const Vector3d g(p.x, p.y, p.z + length_);
    check(g, where, "protected move");
    t_->protected_s += parts::linearFeedSeconds((g - gauge_).norm(), p.feed_mm_per_min);
    gauge_ = g;
  }
  void step(const gcode::ProbeMove& p, const std::string& where) {
    // Timed to the nominal contact (set by the planner); the end is checked for travel.
    const Vector3d g(p.x, p.y, p.z + length_);
    check(g, where, "probing move end (overtravel)");
    t_->probing_s += parts::linearFeedSeconds((contact_ + Vector3d(0, 0, length_) - gauge_).norm(), p.feed_mm_per_min);
    gauge_ = contact_ + Vector3d(0, 0, length_);
  }
  void step(const gcode::Dwell&, const std::string&) {}  // no dwell inside a cycle
  // Ops of machining programs (spindle, feeds, loops ...) the sphere cycle never emits.
  template <class T>
  void step(const T&, const std::string& where) {
    throw std::logic_error(where + ": an op the sphere-cycle walker does not time");
  }

  const Machine& m_;
  CycleTime* t_;
  Vector3d gauge_;
  double length_ = 0.0;
  double c_ = 0.0, b_ = 0.0, a_ = 0.0;
  Vector3d contact_ = Vector3d::Zero();
};

}  // namespace

SpherePlan planSphereCycle(const SphereArtifact& a, const Machine& m, const PlanFiles& files) {
  SpherePlan plan;
  auto& man = plan.manifest;
  const double r_tip = m.probe.tip_diameter_mm / 2;
  const double R = a.sphereRadius();
  const double Rt = R + r_tip;  // stylus-tip centre distance from the sphere centre at contact
  const double sense = parts::tableTurnSign(m.c.positive_is_clockwise);
  if (!m.c.present)
    throw InputError(m.file, 0, "axes.C: the sphere-artifact cycle needs a rotary table (C axis); this machine has none");

  if (a.stem_length_mm + R <= r_tip)
    throw SafetyError(a.file + ": sphere.stem_length: the stylus tip would touch the table when "
                      "probing the equator (stem_length + radius must exceed the tip radius)");
  for (double c : a.c_positions_deg) {
    const double steps = c / m.c.resolution_deg;
    if (std::fabs(steps - std::round(steps)) > 1e-6)
      throw InputError(a.file, 0, "c_positions: " + formatNumber(c) +
                                      " deg is not a multiple of the C resolution " +
                                      formatNumber(m.c.resolution_deg) + " deg");
  }

  // Sphere positions.
  for (size_t k = 0; k < a.c_positions_deg.size(); ++k) {
    parts::ManifestSphere s;
    s.position = static_cast<int>(k + 1);
    s.id = "S" + std::to_string(s.position);
    s.c_deg = a.c_positions_deg[k];
    s.angle_deg = wrapDeg360(a.angle_at_c0_deg + sense * s.c_deg);
    const double th = degToRad(s.angle_deg);
    s.nominal_centre_mm = Vector3d(m.c_axis_centre_mm.x() + a.radius_from_axis_mm * std::cos(th),
                                   m.c_axis_centre_mm.y() + a.radius_from_axis_mm * std::sin(th),
                                   m.table_surface_z_mm + a.centreHeightAboveTable());
    for (const auto& earlier : man.spheres)
      if (sameAngle(earlier.angle_deg, s.angle_deg) && earlier.repeat_of == 0) {
        s.repeat_of = earlier.position;
        break;
      }
    man.spheres.push_back(s);
  }
  // Tilted positions (issue 33): the sphere centre where the machine's chain puts it.
  if (!a.tilted_positions.empty()) {
    const std::string tilt(1, a.tilt_axis);
    if (parts::tiltAxisName(m) != tilt)
      throw InputError(a.file, a.tilted_positions.front().line,
                       "tilted_positions: tilt " + tilt + ", but " + m.file + " has " +
                           (parts::tiltAxisName(m).empty() ? std::string("no tilting axis") : "a " + parts::tiltAxisName(m) + " axis"));
    const parts::RotaryAxis& ax = tilt == "B" ? m.b : m.a;
    const auto chain = parts::machineChain(m, std::nullopt, true);
    const double th0 = degToRad(a.angle_at_c0_deg);
    const Vector3d at_zero(m.c_axis_centre_mm.x() + a.radius_from_axis_mm * std::cos(th0),
                           m.c_axis_centre_mm.y() + a.radius_from_axis_mm * std::sin(th0),
                           m.table_surface_z_mm + a.centreHeightAboveTable());
    for (const auto& tp : a.tilted_positions) {
      const double steps = tp.tilt_deg / ax.resolution_deg, c_steps = tp.c_deg / m.c.resolution_deg;
      if (std::fabs(steps - std::round(steps)) > 1e-6 || std::fabs(c_steps - std::round(c_steps)) > 1e-6)
        throw InputError(a.file, tp.line, "tilted_positions: " + tilt + " " + formatNumber(tp.tilt_deg) + ", C " +
                                              formatNumber(tp.c_deg) + " deg is not a multiple of the axes' resolution");
      if (!ax.continuous && (tp.tilt_deg < ax.min_deg || tp.tilt_deg > ax.max_deg))
        throw SafetyError(a.file + ":" + std::to_string(tp.line) + ": tilted_positions: " + tilt + " = " +
                          formatNumber(tp.tilt_deg) + " deg is outside the " + tilt + " travel of " + m.file);
      parts::ManifestSphere s;
      s.position = static_cast<int>(man.spheres.size() + 1);
      s.id = "S" + std::to_string(s.position);
      s.c_deg = tp.c_deg;
      s.tilt_deg = tp.tilt_deg;
      s.angle_deg = wrapDeg360(a.angle_at_c0_deg + sense * s.c_deg);
      geometry::ChainState st;
      st.positions = {{tilt, tp.tilt_deg}, {"C", tp.c_deg}};
      s.nominal_centre_mm = geometry::machineCoordinatesOf(chain, st, at_zero);
      man.spheres.push_back(s);
    }
    parts::ManifestTiltAxis t;
    t.name = tilt;
    t.centre_mm = tilt == "B" ? *m.b_axis_centre_xz_mm : *m.a_axis_centre_yz_mm;
    t.positive_is_clockwise = ax.positive_is_clockwise;
    man.tilt_axis = t;
  }
  // Seed 004 Eqs. 5.4-5.10 index k by the side of the C axis: the printed signs hold for
  // k = 1..4 at -X, +Y, +X, -Y (notes/seed004.md §2.3).
  const double formula_angle[4] = {180, 90, 0, 270};
  for (int f = 0; f < 4; ++f)
    for (auto& s : man.spheres)
      if (s.repeat_of == 0 && s.tilt_deg == 0 && sameAngle(s.angle_deg, formula_angle[f])) s.formula_index = f + 1;

  // Probing directions: equator at machine angles 0, 360/n, ... from +X, then the top.
  std::vector<Vector3d> outward;
  for (int j = 0; j < a.equator_points; ++j) {
    const double phi = 2 * kPi * j / a.equator_points;
    outward.emplace_back(std::cos(phi), std::sin(phi), 0.0);
  }
  if (a.top_point) outward.emplace_back(0, 0, 1);

  const double tc_z = m.tool_change.z_mm;

  gcode::ProbeProgram& prog = plan.program;
  prog.title = "probeloop sphere-artifact cycle [seed 004 Ch. 5] - generated, do not edit";
  prog.work_offset = m.work_offset;
  prog.has_b_axis = m.b.present;
  prog.has_a_axis = m.a.present;
  prog.log_file = files.log_file;
  prog.gap_s = a.gap_s;
  prog.live_interval = a.live_interval;

  std::vector<gcode::Op>& body = prog.cycle_body;
  std::vector<gcode::Op> before, after;
  std::vector<std::pair<gcode::Op, std::string>> timed;  // op + where, for the walker
  std::vector<int> contact_of;                            // manifest point index per op, -1
  std::vector<int> part_of;                               // 0 before the loop, 1 the cycle, 2 after
  auto emit = [&](std::vector<gcode::Op>& into, gcode::Op op, const std::string& where, int pt = -1) {
    into.push_back(op);
    timed.emplace_back(op, where);
    contact_of.push_back(pt);
    part_of.push_back(&into == &before ? 0 : &into == &body ? 1 : 2);
  };
  auto& tc_in = a.tool_change_each_cycle ? body : before;
  emit(tc_in, gcode::RapidMachineZ{tc_z}, "probe in");
  emit(tc_in, gcode::ToolChange{m.probe.tool, true}, "probe in");

  const bool tilt_a = man.tilt_axis && man.tilt_axis->name == "A";
  auto tiltOp = [&](double deg) -> gcode::Op { return tilt_a ? gcode::Op(gcode::RotateA{deg}) : gcode::Op(gcode::RotateB{deg}); };
  double tilt_now = 0;
  for (const auto& s : man.spheres) {
    const std::string tilt = man.tilt_axis ? man.tilt_axis->name : "";
    const std::string pos = "position " + std::to_string(s.position) + " (" +
                            (s.tilt_deg != 0 ? tilt + " " + formatNumber(s.tilt_deg) + ", " : "") + "C " +
                            formatNumber(s.c_deg) + ")";
    const double z_clear_here = s.nominal_centre_mm.z() + Rt + a.clearance_mm;
    emit(body, gcode::Comment{pos + ", sphere " + s.id}, pos);
    if (s.tilt_deg != 0 || tilt_now != 0) {
      // A tilted table swings and turns only with the tool at the tool-change height, far
      // above what it carries (on a tilted table C lifts the sphere as it turns); then the tip
      // comes down above this position's sphere.
      emit(body, gcode::RapidMachineZ{tc_z}, pos + ": up before the " + tilt + " and C axes move");
      if (s.tilt_deg != tilt_now) emit(body, tiltOp(s.tilt_deg), pos);
      emit(body, gcode::RotateC{s.c_deg}, pos);
      emit(body, gcode::Rapid{s.nominal_centre_mm.x(), s.nominal_centre_mm.y(), std::nullopt}, pos + ": above the sphere");
      emit(body, gcode::Rapid{std::nullopt, std::nullopt, z_clear_here}, pos + ": clearance plane");
      tilt_now = s.tilt_deg;
    } else {
      emit(body, gcode::Rapid{std::nullopt, std::nullopt, z_clear_here}, pos + ": clearance plane");
      emit(body, gcode::RotateC{s.c_deg}, pos);
    }
    for (size_t j = 0; j < outward.size(); ++j) {
      const Vector3d& u = outward[j];
      const Vector3d c = s.nominal_centre_mm;
      const Vector3d start = c + (Rt + a.approach_mm) * u;
      const Vector3d end = c + (Rt - a.overtravel_mm) * u;
      parts::ManifestPoint p;
      p.feature = s.id;
      p.position = s.position;
      p.point = static_cast<int>(j + 1);
      p.contact_mm = c + Rt * u;
      p.approach = -u;
      const int idx = static_cast<int>(man.points.size());
      man.points.push_back(p);
      const std::string where = pos + " point " + std::to_string(j + 1);
      emit(body, gcode::Rapid{start.x(), start.y(), std::nullopt}, where);
      emit(body, gcode::ProtectedMove{start.x(), start.y(), start.z(), a.positioning_feed_mm_per_min}, where);
      emit(body, gcode::ProbeMove{end.x(), end.y(), end.z(), a.probing_feed_mm_per_min, s.position, p.point},
           where, idx);
      emit(body, gcode::Rapid{start.x(), start.y(), start.z()}, where + ": retract");
      emit(body, gcode::Rapid{std::nullopt, std::nullopt, z_clear_here}, where + ": clearance plane");
    }
  }
  if (tilt_now != 0) {
    emit(body, gcode::RapidMachineZ{tc_z}, "level the table: up before the swing");
    emit(body, tiltOp(0), "level the table");
  }
  auto& tc_out = a.tool_change_each_cycle ? body : after;
  emit(tc_out, gcode::RapidMachineZ{tc_z}, "probe out");
  if (a.tool_change_each_cycle) emit(tc_out, gcode::ToolChange{m.tool_change.empty_tool, false}, "probe out");
  if (!a.tool_change_each_cycle) {
    emit(body, gcode::RapidMachineZ{tc_z}, "end of cycle");  // park high during the gap
    emit(after, gcode::ToolChange{m.tool_change.empty_tool, false}, "probe out");
  }
  prog.before_cycles = before;
  prog.after_cycles = after;

  // Time the ops before the loop, the first cycle, a later cycle (it starts by turning C back
  // from the last position to the first) and the ops after the loop, checking every target.
  // Tool changes count in a cycle only when they are in it (tool_change_each_cycle); the
  // thesis's 95 s has two.
  CycleTime before_t, first_t, after_t;
  Walker w(m, before_t);
  auto walk = [&](int part, bool record) {
    for (size_t i = 0; i < timed.size(); ++i) {
      if (part_of[i] != part) continue;
      if (contact_of[i] >= 0) w.setNextContact(man.points[contact_of[i]].contact_mm);
      w.run(timed[i].first, timed[i].second);
      if (record && contact_of[i] >= 0) man.points[contact_of[i]].time_in_cycle_s = before_t.total() + w.time();
    }
  };
  walk(0, false);
  w.account(first_t);
  walk(1, true);
  w.account(plan.cycle_time);
  walk(1, false);
  w.account(after_t);
  walk(2, false);
  const double t_before = before_t.total(), T1 = first_t.total();
  const double T = plan.cycle_time.total();  // a cycle after the first

  int cycles = a.cycle_count;
  if (cycles == 0) cycles = std::max(1, static_cast<int>(std::floor((a.duration_s - T) / (T + a.gap_s))) + 1);
  prog.cycles = cycles;

  man.dialect = parts::dialectName(m.dialect);
  parts::ManifestProgram program;
  program.file = files.program_file;
  program.dialect = man.dialect;
  program.log_file = files.log_file;
  man.programs.push_back(program);
  man.machine_name = m.name;
  man.c_axis_centre_mm = m.c_axis_centre_mm;
  man.c_positive_is_clockwise = m.c.positive_is_clockwise;
  man.table_surface_z_mm = m.table_surface_z_mm;
  man.coordinate_resolution_mm = std::max({m.x.resolution_mm, m.y.resolution_mm, m.z.resolution_mm});
  man.probe_tool = m.probe.tool;
  man.tip_radius_mm = r_tip;
  man.probe_repeatability_2sigma_um = m.probe.repeatability_2sigma_um;
  man.sphere_radius_mm = R;
  man.sphere_form_error_um = a.sphere_form_error_um;
  man.radius_from_axis_mm = a.radius_from_axis_mm;
  man.probe_tool_change_repeatability_2sigma_um = m.probe.tool_change_repeatability_2sigma_um;
  man.sphere_centre_height_mm = a.centreHeightAboveTable();
  man.radius_from_axis_u_mm = a.radius_from_axis_u_mm;
  man.artifact_alpha_um_per_m_K = a.alpha_um_per_m_K;
  man.artifact_temperature_change_half_width_K = a.temperature_change_half_width_K;
  man.tool_change_each_cycle = a.tool_change_each_cycle;
  man.cycles = cycles;
  man.gap_s = a.gap_s;
  man.cycle_time_s = T;
  // Each cycle's start on the clock its points' time_in_cycle_s count from (the first cycle's,
  // which holds the ops before the loop and no C return): a later cycle's body starts after the
  // previous one and its gap, and its points come T - T1 (the C return) later in it.
  man.cycle_start_s.push_back(0.0);
  double body_start = t_before + T1 + a.gap_s;
  for (int i = 1; i < cycles; ++i) {
    man.cycle_start_s.push_back(body_start + (T - T1) - t_before);
    body_start += T + a.gap_s;
  }

  // With the live interval the gap is the plan's assumption, not what the program does: the
  // writer adds where the wait comes from (gcode/probe_program.hpp).
  prog.header = {
      "machine: " + m.name,
      "sphere d = " + formatNumber(a.sphere_diameter_mm) + " mm at d/2 = " +
          formatNumber(a.radius_from_axis_mm) + " mm from C; tip d = " +
          formatNumber(m.probe.tip_diameter_mm) + " mm",
      "cycles: " + std::to_string(cycles) + (a.live_interval ? ", nominal gap " : ", gap ") + formatNumber(a.gap_s) +
          " s, estimated cycle time " + formatNumber(T, 1) + " s",
      "coordinates: G" + std::to_string(53 + prog.work_offset) +
          " zeroed = machine coordinates of the stylus-tip centre with G43",
  };
  return plan;
}

std::string programText(const SpherePlan& plan, parts::Dialect dialect) {
  return dialect == parts::Dialect::LinuxCnc ? gcode::writeLinuxCnc(plan.program)
                                              : gcode::writeFanucMacroB(plan.program);
}

}  // namespace probeloop::planner
