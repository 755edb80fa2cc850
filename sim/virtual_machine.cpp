#include "sim/virtual_machine.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "gcode/probe_log.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "model/effects.hpp"
#include "sim/material_removal.hpp"
#include "sim/random_streams.hpp"
#include "sim/piece_truth.hpp"

namespace probeloop::sim {

using Eigen::Vector3d;
using gcode::MachinePosition;

namespace {

double poly(const std::vector<double>& c, double x) {
  double v = 0;
  for (std::size_t k = c.size(); k-- > 0;) v = v * x + c[k];
  return v;
}

// Closest distance between segments p0-p1 and q0-q1 (Ericson, Real-Time Collision
// Detection 5.1.9), with the parameter s on the first segment.
double segmentDistance(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0, const Vector3d& q1) {
  const Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-18 && e <= 1e-18) return r.norm();
  if (a <= 1e-18) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-18) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 1e-18 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

// Closest distance from point p to the arc of radius rho about c from angle lo over span
// (counterclockwise, rad), 2D.
double arcDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double rho, double lo, double span) {
  const Eigen::Vector2d w = p - c;
  if (span >= 2 * kPi - 1e-12) return std::fabs(w.norm() - rho);
  double ang = std::atan2(w.y(), w.x()) - lo;
  ang -= 2 * kPi * std::floor(ang / (2 * kPi));
  if (ang <= span) return std::fabs(w.norm() - rho);
  const Eigen::Vector2d e0 = c + rho * Eigen::Vector2d(std::cos(lo), std::sin(lo));
  const Eigen::Vector2d e1 = c + rho * Eigen::Vector2d(std::cos(lo + span), std::sin(lo + span));
  return std::min((p - e0).norm(), (p - e1).norm());
}

struct ProbeEvent {
  double time_s = 0;
  int log_stream = -1;  // which log of the run (index)
  long log_line = 0;  // 1-based line of the log written after this probe (0 = none)
  double c_deg = 0;
  Vector3d approach = Vector3d::Zero();
  std::array<double, 7> location{};  // table-side location errors at the event
  Vector3d tool_um = Vector3d::Zero();  // tool-side translation (thermal + static + ATC)
  Vector3d atc_um = Vector3d::Zero();
  double settling_um = 0;  // tool-change settling along Z (part of tool_um)
  double artifact_dT_K = 0;
  std::array<double, 7> apparent{};  // what a sphere evaluation sees (docs/simulator.md)
  double pretravel_um = 0, noise_um = 0;
  Vector3d reported_tip_mm = Vector3d::Zero();  // latched, machine coordinates of the tip
  // Workpiece probing: the tool-side error of the linear axes (geometric errors, squareness and
  // the still axes' held lost motion; not the drift, nor the approach's lag, which the stylus's
  // calibration holds) at the contact; what a CMM - probe comparison sees.
  std::optional<Vector3d> axes_um;
  Vector3d scale_um_per_mm = Vector3d::Zero();  // the axes' scale errors (static + thermal) then
};

class VirtualMachine : public gcode::MachineInterface {
 public:
  VirtualMachine(const parts::Machine& m, const SimulationPart& part, const MachineTruth& tr,
                 std::uint64_t seed)
      : m_(m), a_(part.artifact), w_(part.workpiece), tr_(tr), noise_rng_(streamSeed(seed, 1)), atc_rng_(streamSeed(seed, 2)),
        sensor_rng_(streamSeed(seed, 3)), duty_rng_(streamSeed(seed, 4)), duty_tc_rng_(streamSeed(seed, 5)),
        duty_atc_rng_(streamSeed(seed, 6)) {
    if (tr.thermal.present) {
      T0_ = tr.thermal.environment.at(0.0);
      net_ = ThermalNetwork(tr.thermal.nodes, tr.thermal.links, T0_);
      std::uniform_real_distribution<double> u(-0.5, 0.5);
      for (const auto& s : tr.thermal.sensors) sensor_offset_.push_back(s.offset_K ? *s.offset_K : u(sensor_rng_));
    }
    inputs_ << "# probeloop simulate: machine inputs sampled every " << formatNumber(tr.inputs_rate_s)
            << " s (sensors with noise and offset)\n";
    inputs_ << "time_s";
    for (const auto& s : tr.thermal.sensors) inputs_ << "," << s.column;
    inputs_ << ",c_rpm,spindle_rpm,feed_mm_per_min,mwf_on,tool_changes\n";
    if (w_) {
      stock_ = Stock(w_->stock_min_mm, w_->stock_max_mm, 0.25, w_->cylindrical);
      for (const auto& h : w_->holes) stock_.addHole(h.centre_mm, h.radius_mm, h.z_min_mm, h.z_max_mm);
    }
    if (tr.duty.tool_changes_per_hour > 0) next_duty_change_ = drawDutyGap();
    // At rest at the top of Z (the tool-change height region), X and Y at the C axis.
    pos_.xyz_mm = Vector3d(std::clamp(m_.c_axis_centre_mm.x(), m_.x.min_mm, m_.x.max_mm),
                           std::clamp(m_.c_axis_centre_mm.y(), m_.y.min_mm, m_.y.max_mm), m_.z.max_mm);
    sample();
  }

  MachinePosition start() const override { return pos_; }
  // The controller's clock (Fanuc #3011/#3012): Monday 2026-01-05 at the truth's start_clock
  // (the hall's time of day at t = 0; midnight without one), then the simulated time.
  double controllerClockS() const override { return 4 * 86400.0 + tr_.thermal.environment.start_clock_s + t_; }
  void atLine(int line) override { line_ = line; }

  // --- gcode::MachineInterface ---------------------------------------------------------
  void rapid(const MachinePosition& to) override {
    checkTravel(to);
    checkPath(to, "rapid (G0)");
    double t = 0;
    const Vector3d d = (to.xyz_mm - pos_.xyz_mm).cwiseAbs();
    t = std::max(t, d.maxCoeff() / m_.rapid_feed_mm_per_min * 60.0);
    t = std::max(t, rotaryTime(to.c_deg - pos_.c_deg, m_.c));
    t = std::max(t, rotaryTime(to.b_deg - pos_.b_deg, m_.b));
    const double t0 = t_;
    noteAxesMotion(to.xyz_mm, t);
    move(t, t > 0 ? (to.xyz_mm - pos_.xyz_mm).norm() / t * 60.0 : 0.0);
    traceRow("rapid", to, 0, t0);
    pos_ = to;
  }

  void feed(const MachinePosition& to, double F) override {
    checkTravel(to);
    // A move of rotary axes alone reads F in deg/min (LinuxCNC and Fanuc): the axis turns at
    // F / 360 rpm, limited by its turning speed, not by the XYZ feed.
    const bool rotary_only = to.xyz_mm == pos_.xyz_mm && (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg);
    if (rotary_only) checkRotaryFeed(to, F);
    else checkFeed(F);
    if (w_ && isCutter() && spindle_rpm_ != 0) {
      cutMove(to, F);
      return;
    }
    checkPath(to, spindle_rpm_ == 0 && isCutter() ? "feed move (G1/G2/G3) with the spindle stopped" : "feed move (G1/G2/G3)");
    const double len = (to.xyz_mm - pos_.xyz_mm).norm();
    const double rot = std::max(std::fabs(to.c_deg - pos_.c_deg), std::fabs(to.b_deg - pos_.b_deg));
    const double t0 = t_;
    const double dt = (len > 0 ? len : rot) / F * 60.0;
    c_move_rpm_ = cMoveRpm(to, dt);
    noteAxesMotion(to.xyz_mm, dt);
    move(dt, len > 0 ? F : 0.0);
    c_move_rpm_ = 0;
    traceRow("feed", to, F, t0);
    pos_ = to;
  }

  // The C axis's real speed during a feed move that turns it (a heat input, and the inputs
  // CSV's c_rpm). Rapid indexing (G0 C) at the positioning speed lasts < 1 s per quarter
  // turn and is left out, so the sphere campaigns' outputs stay as they were.
  double cMoveRpm(const MachinePosition& to, double dt_s) const {
    if (!(dt_s > 0) || to.c_deg == pos_.c_deg) return 0;
    return std::fabs(to.c_deg - pos_.c_deg) / 360.0 / (dt_s / 60.0);
  }

  gcode::ProbeOutcome probe(const MachinePosition& to, double F, gcode::ProbeMode mode) override {
    const double t0 = t_;
    const auto r = probeMove(to, F, mode);
    traceRow(r.contact ? "probe_contact" : "probe_no_contact", to, F, t0);
    return r;
  }

  gcode::ProbeOutcome probeMove(const MachinePosition& to, double F, gcode::ProbeMode mode) {
    checkTravel(to);
    checkFeed(F);
    if (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg)
      throw InputError("", 0, "a probe move with a rotary axis is not modelled");
    const Vector3d g0 = pos_.xyz_mm, g1 = to.xyz_mm;
    const double len = (g1 - g0).norm();
    if (len <= 0) throw InputError("", 0, "a probe move of zero length");
    noteAxesMotion(g1, len / F * 60.0);
    const Vector3d dir = (g1 - g0) / len;
    if (!a_) return probeWorkpiece(to, F, dir, len, mode);
    const Vector3d a = tipActual(g0), b = tipActual(g1);
    const Artifact art = artifact();
    // Stem and table first: a probe move may touch the sphere only.
    // LinuxCNC refuses to start a probe move with the probe tripped; Fanuc skips at once.
    if ((a - art.centre).norm() <= art.radius + tipRadius() && mode != gcode::ProbeMode::SkipToTarget)
      throw SafetyError("probe move starts with the probe already in contact (tripped)");
    const double s_contact = firstSphereContact(a, b, art);
    const double s_end = s_contact >= 0 ? s_contact : 1.0;
    checkStemAndTable(a, a + s_end * (b - a), art, "probe move");
    const double pre_um = pretravel(dir);
    const double extra_mm = pre_um * 1e-3 + F / 60.0 * tr_.probe.trigger_delay_s;
    const double s_trig = s_contact >= 0 ? s_contact + extra_mm / len : 2.0;
    if (s_contact < 0 || s_trig > 1.0) return noTrigger(to, len, F);
    // The clock runs while the tip approaches (~1 s): the tip meets the artifact where the
    // errors of the contact time put it, which matters for fast effects (a settling
    // transient of 10 min moves 0.15 % in that second). Move to the contact found with the
    // errors at the start, then find it again with the errors now: a nanometre correction,
    // forward or back along the line.
    const double approach_mm = s_contact * len;
    move(approach_mm / F * 60.0, F);
    pos_.xyz_mm = g0 + approach_mm * dir;
    const Artifact now = artifact();
    const double s_now = sphereEntryOnLine(tipActual(pos_.xyz_mm), tipActual(g1), now).value_or(0.0);
    const double travel_mm = s_now * (len - approach_mm) + extra_mm;
    if (approach_mm + travel_mm > len) return noTrigger(to, len - approach_mm, F);
    ProbeEvent ev = newEvent(dir, pre_um);
    fillTruth(ev, now);
    return latchTrigger(ev, dir, travel_mm, F);
  }

  // No trigger within the move: G38.2/G38.3 and G31 all end at the target.
  gcode::ProbeOutcome noTrigger(const MachinePosition& to, double len, double F) {
    move(len / F * 60.0, F);
    pos_ = to;
    gcode::ProbeOutcome out;
    out.stop = to;
    return out;
  }
  ProbeEvent newEvent(const Vector3d& dir, double pretravel_um) const {
    ProbeEvent ev;
    ev.c_deg = pos_.c_deg;
    ev.approach = dir;
    ev.pretravel_um = pretravel_um;
    return ev;
  }

  // The controller latches the trigger: repeatability noise along the approach, the axes'
  // resolution, the clock at the trigger, the event for the truth and the next log line.
  gcode::ProbeOutcome latchTrigger(ProbeEvent ev, const Vector3d& dir, double travel_mm, double F) {
    ev.noise_um = tr_.probe.noise_um > 0 ? tr_.probe.noise_um * noise_normal_(noise_rng_) : 0.0;
    Vector3d latched = pos_.xyz_mm + travel_mm * dir + ev.noise_um * 1e-3 * dir;
    // The stylus is calibrated at the probing feed (as for its pre-travel): the lag of the axes
    // that move in the approach is in its effective radius; a still axis's held lag is not.
    for (int k = 0; k < 3; ++k)
      if (lost_motion_moving_[k]) latched(k) += lost_motion_um_(k) * 1e-3;
    if (tr_.probe.quantise) {
      const double q[3] = {m_.x.resolution_mm, m_.y.resolution_mm, m_.z.resolution_mm};
      for (int k = 0; k < 3; ++k) latched(k) = std::round(latched(k) / q[k]) * q[k];
    }
    move(travel_mm / F * 60.0, F);
    ev.time_s = t_;
    ev.reported_tip_mm = latched - Vector3d(0, 0, currentToolLength());
    events_.push_back(ev);
    pending_ = static_cast<long>(events_.size()) - 1;
    pos_.xyz_mm = latched;
    gcode::ProbeOutcome out;
    out.contact = true;
    out.stop = pos_;
    return out;
  }

  void dwell(double s) override {
    const double t0 = t_;
    dwelling_ = true;
    advance(s);
    dwelling_ = false;
    traceRow("dwell", pos_, 0, t0);
  }

  void toolChange(int tool) override {
    const bool probe = tool == m_.probe.tool;
    if (!probe && tool != m_.tool_change.empty_tool && !(w_ && w_->tool(tool)))
      throw InputError("", 0, "tool T" + std::to_string(tool) + " is not in the machine's tool table (the "
                              "simulator knows the probe T" + std::to_string(m_.probe.tool) +
                              " and the empty spindle T" + std::to_string(m_.tool_change.empty_tool) +
                              ", plus the workpiece's tools)");
    if (spindle_rpm_ != 0) throw SafetyError("tool change with the spindle turning (M5 first)");
    const double t0 = t_;
    advance(m_.tool_change.time_s);
    tool_ = tool;
    traceRow("tool_change", pos_, 0, t0);
    atc_um_.setZero();
    if (probe && tr_.atc_repeatability_um > 0)
      for (int k = 0; k < 3; ++k) atc_um_(k) = tr_.atc_repeatability_um * atc_normal_(atc_rng_);
    recordToolChange("program");
  }

  double toolLength(int tool) const override {
    if (tool == m_.probe.tool) return m_.probe.length_mm;
    if (tool == m_.tool_change.empty_tool) return 0.0;
    if (w_)
      if (const auto* t = w_->tool(tool)) return t->length_mm;
    throw InputError("", 0, "G43 H" + std::to_string(tool) + ": no such tool in the machine's tool table");
  }

  void spindle(double rpm) override {
    if (rpm != 0 && tool_ == m_.probe.tool)
      throw SafetyError("spindle start (M3/M4) with the touch probe in the spindle");
    spindle_rpm_ = rpm;
  }
  void coolant(bool on) override { coolant_ = on; }
  // Fanuc: every program's DPRNT goes to the one dprnt.txt (POPEN names no file). LinuxCNC:
  // the program's LOGOPEN file; a later LOGOPEN in the same program renames it (the last
  // name wins, as before); a name an earlier program of the run wrote is refused, because
  // LinuxCNC would overwrite that log.
  void openLog(const std::string& name) override {
    if (program_fanuc_) {
      streamFor("dprnt.txt");
      return;
    }
    for (std::size_t i = 0; i < logs_.size(); ++i)
      if (logs_[i]->name == name && logs_[i]->program != program_index_)
        throw InputError("", 0, "LOGOPEN," + name + ": an earlier program of this run (" + logs_[i]->program_file +
                                    ") wrote this log, and LinuxCNC would overwrite it; give each program its own log name");
    if (cur_log_ < 0) cur_log_ = newStream(name);
    else logs_[static_cast<std::size_t>(cur_log_)]->name = name;
  }
  void log(const std::string& line) override {
    if (cur_log_ < 0) {
      if (program_fanuc_) streamFor("dprnt.txt");
      else cur_log_ = newStream("");
    }
    LogStream& l = *logs_[static_cast<std::size_t>(cur_log_)];
    l.text << line << "\n";
    ++l.lines;
    if (pending_ >= 0) {
      events_[static_cast<std::size_t>(pending_)].log_stream = cur_log_;
      events_[static_cast<std::size_t>(pending_)].log_line = l.lines;
      pending_ = -1;
    }
  }
  void closeLog() override {}

  // --- programs -------------------------------------------------------------------------
  // A new program on the same machine. Its interpreter starts afresh (modal state, work
  // offsets); the machine keeps its clock, state, stock, tool and position. The previous
  // program's M2/M30 stopped the spindle and the coolant.
  void beginProgram(const std::string& file, bool fanuc) {
    if (program_index_ >= 0) {
      spindle_rpm_ = 0;
      coolant_ = false;
    }
    ++program_index_;
    program_file_ = file;
    program_fanuc_ = fanuc;
    cur_log_ = -1;
    if (fanuc)
      for (std::size_t i = 0; i < logs_.size(); ++i)
        if (logs_[i]->name == "dprnt.txt" && logs_[i]->fanuc) cur_log_ = static_cast<int>(i);
  }
  // A LinuxCNC log that was never named (not expected: the interpreter logs only after
  // LOGOPEN) is the controller's log.
  void endProgram() {
    for (auto& l : logs_)
      if (l->name.empty()) l->name = "controller.log";
  }
  // One program that wrote no log still has one (empty), as before.
  void ensureLog(bool fanuc) {
    if (logs_.empty()) {
      program_fanuc_ = fanuc;
      if (fanuc) streamFor("dprnt.txt");
      else newStream("controller.log");
    }
  }

  // The machine switched off for s seconds between programs (seed 000 L992: 3 h off before
  // machining and before probing): spindle, coolant (and the duty's coolant profile), axes, C
  // and constant heat sources off, the structure cooling toward the hall.
  void machineOff(double s) {
    spindle_rpm_ = 0;
    coolant_ = false;
    path_speed_mm_per_min_ = 0;
    const double t0 = t_;
    off_ = true;
    advance(s);
    off_ = false;
    traceRow("machine_off", pos_, 0, t0);
  }

  // --- results --------------------------------------------------------------------------
  double time() const { return t_; }
  std::vector<LogOutput> logs() const {
    std::vector<LogOutput> out;
    for (const auto& l : logs_) out.push_back({l->name, l->text.str()});
    return out;
  }
  std::string inputsText() const { return inputs_.str(); }
  const std::vector<ProbeEvent>& events() const { return events_; }
  void finish() {
    // A last sample at the end time, if the regular grid missed it.
    if (last_sample_t_ < t_ - 1e-9) sample();
  }

 private:
  const parts::Machine& m_;
  const parts::SphereArtifact* a_;
  const parts::Workpiece* w_;
  Stock stock_;
  nlohmann::ordered_json cuts_ = nlohmann::ordered_json::array();
  std::vector<CutState> cut_states_;  // parallel to cuts_: the machine when each cut started
  long motions_ = 0;                  // motions, dwells and tool changes so far
  long air_run_motion_ = -1;          // motions_ after the last cutting move in the air
  const MachineTruth& tr_;
  std::mt19937_64 noise_rng_, atc_rng_, sensor_rng_, duty_rng_;
  // One normal distribution per stream: std::normal_distribution keeps the second value of
  // each pair it draws, so a shared one would hand one stream's draw to another.
  std::normal_distribution<double> noise_normal_{0.0, 1.0}, atc_normal_{0.0, 1.0}, sensor_normal_{0.0, 1.0},
      duty_atc_normal_{0.0, 1.0};
  ThermalNetwork net_;
  double T0_ = 20;
  std::vector<double> sensor_offset_;
  double t_ = 0;
  long sample_index_ = 0;
  double last_sample_t_ = -1;
  MachinePosition pos_;
  int tool_ = 0;
  Vector3d atc_um_ = Vector3d::Zero();
  Vector3d lost_motion_um_ = Vector3d::Zero();  // the drives' wind-up held now (tool side)
  std::array<bool, 3> lost_motion_moving_{};     // the axes the last move moved (set it)
  double spindle_rpm_ = 0;
  double path_speed_mm_per_min_ = 0;
  bool off_ = false;  // machineOff: every heat input off
  double c_move_rpm_ = 0;  // C speed while a feed move turns it
  bool coolant_ = false, dwelling_ = false;
  int tool_changes_ = 0;
  std::vector<double> duty_levels_;  // random C levels per hold period, drawn as needed
  std::mt19937_64 duty_tc_rng_, duty_atc_rng_;  // duty tool changes: times, probe re-seating
  double dwell_clock_ = 0;                      // time spent dwelling so far
  double next_duty_change_ = -1;                // dwell-clock time of the next one (-1 = none)
  double settling_ = 0;                         // sum of the decaying unit jumps of the changes
  nlohmann::ordered_json tool_change_log_ = nlohmann::ordered_json::array();
  std::ostringstream inputs_;
  long pending_ = -1;
  struct LogStream {
    std::string name;
    bool fanuc = false;
    int program = 0;
    std::string program_file;
    std::ostringstream text;
    long lines = 0;
  };
  std::vector<std::unique_ptr<LogStream>> logs_;
  int cur_log_ = -1;
  int program_index_ = -1;
  std::string program_file_;
  bool program_fanuc_ = false;
  int newStream(const std::string& name) {
    auto l = std::make_unique<LogStream>();
    l->name = name;
    l->fanuc = program_fanuc_;
    l->program = program_index_;
    l->program_file = program_file_;
    logs_.push_back(std::move(l));
    return static_cast<int>(logs_.size()) - 1;
  }
  void streamFor(const std::string& name) {
    for (std::size_t i = 0; i < logs_.size(); ++i)
      if (logs_[i]->name == name) {
        if (!logs_[i]->fanuc)
          throw InputError("", 0, "POPEN: " + logs_[i]->program_file + " wrote a log named " + name +
                                      ", where this run's DPRNT output goes; give that log another name");
        cur_log_ = static_cast<int>(i);
        return;
      }
    cur_log_ = newStream(name);
  }
  std::vector<ProbeEvent> events_;
  int line_ = 0;
  bool trace_on_ = false, trace_program_ = false;
  std::ostringstream trace_;

  struct Artifact {
    Vector3d centre;      // actual sphere centre (tip coordinates)
    double radius = 0;    // actual sphere radius
    double stem_radius = 0;
    double table_z = 0;
    double dT = 0;
    std::array<double, 7> location{};
  };

  // --- clock and thermal state ----------------------------------------------------------
  static double rotaryTime(double delta_deg, const parts::RotaryAxis& ax) {
    if (delta_deg == 0) return 0;
    if (!ax.present || !(ax.max_speed_rpm > 0)) throw InputError("", 0, "move of a rotary axis the machine does not have");
    return std::fabs(delta_deg) / (ax.max_speed_rpm * 360.0) * 60.0;
  }

  double cRpm(double t) {
    if (off_) return 0;
    if (c_move_rpm_ > 0) return c_move_rpm_;  // a feed move turns C (the test's load)
    if (!dwelling_) return 0;
    const auto& d = tr_.duty;
    if (!d.c_profile.empty()) {
      double v = 0;
      for (const auto& [at, rpm] : d.c_profile)
        if (t >= at) v = rpm;
      return v;
    }
    if (!d.c_levels_rpm.empty()) {
      const auto k = static_cast<std::size_t>(std::floor(t / d.hold_s));
      std::uniform_int_distribution<std::size_t> pick(0, d.c_levels_rpm.size() - 1);
      while (duty_levels_.size() <= k) duty_levels_.push_back(d.c_levels_rpm[pick(duty_rng_)]);
      return duty_levels_[k];
    }
    return 0;
  }
  bool mwfOn(double t) const {
    if (off_) return false;
    bool on = coolant_;
    for (const auto& [at, v] : tr_.duty.mwf_profile)
      if (t >= at) on = v;
    return on;
  }

  Eigen::VectorXd heat(double t) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(net_.size());
    for (const auto& s : tr_.thermal.sources) {
      double v = 0;
      switch (s.input) {
        case HeatInput::CAxisRpm: v = std::fabs(cRpm(t)) * s.gain; break;
        case HeatInput::SpindleRpm: v = std::fabs(spindle_rpm_) * s.gain; break;
        case HeatInput::AxisSpeed: v = path_speed_mm_per_min_ / 1000.0 * s.gain; break;
        case HeatInput::Mwf: v = mwfOn(t) ? s.gain : 0.0; break;
        case HeatInput::Constant: v = off_ ? 0.0 : s.gain; break;
      }
      q(s.node) += v;
    }
    return q;
  }

  // One row of the motion trace: what the controller commanded, when, from which line.
  void traceRow(const char* kind, const MachinePosition& to, double feed, double t_start) {
    ++motions_;  // every motion, dwell and tool change ends here
    if (!trace_on_) return;
    trace_ << formatNumber(t_start, 3) << "," << formatNumber(t_ - t_start, 3) << "," << line_ << "," << kind << ","
           << formatNumber(to.xyz_mm.x(), 6) << "," << formatNumber(to.xyz_mm.y(), 6) << ","
           << formatNumber(to.xyz_mm.z(), 6) << "," << formatNumber(to.b_deg, 6) << "," << formatNumber(to.c_deg, 6)
           << "," << formatNumber(feed, 3) << "," << tool_;
    if (trace_program_) trace_ << "," << std::filesystem::path(program_file_).filename().string();
    trace_ << "\n";
  }

  // Time passes while X/Y/Z move at this path speed (a heat input, and a column of the
  // inputs CSV).
  void move(double dt, double speed_mm_per_min) {
    path_speed_mm_per_min_ = speed_mm_per_min;
    advance(dt);
    path_speed_mm_per_min_ = 0;
  }

  void advance(double dt) {
    const double rate = tr_.inputs_rate_s;
    while (dt > 1e-12) {
      const double next_sample = static_cast<double>(sample_index_) * rate;
      double h = std::min(dt, tr_.thermal.max_step_s);
      if (next_sample > t_ + 1e-9) h = std::min(h, next_sample - t_);
      // A duty tool change ends the step, so it happens at its own time.
      const bool duty_change_due = dwelling_ && next_duty_change_ >= 0;
      if (duty_change_due) h = std::min(h, std::max(0.0, next_duty_change_ - dwell_clock_));
      if (tr_.thermal.present) net_.advance(h, tr_.thermal.environment.at(t_ + h / 2), heat(t_ + h / 2));
      if (tr_.settling_tau_s > 0) settling_ = model::decayStep(settling_, h, tr_.settling_tau_s);
      t_ += h;
      dt -= h;
      if (dwelling_) dwell_clock_ += h;
      while (duty_change_due && dwell_clock_ >= next_duty_change_ - 1e-9) dutyToolChange();
      if (std::fabs(t_ - next_sample) <= 1e-9 || t_ > next_sample) sample();
    }
  }

  // Tool changes as a Poisson process on the dwell clock: exponential gaps (mean 1/rate).
  double drawDutyGap() {
    std::exponential_distribution<double> gap(tr_.duty.tool_changes_per_hour / 3600.0);
    return dwell_clock_ + gap(duty_tc_rng_);
  }

  // Production work while the program waits: the probe goes to the magazine, another tool
  // cuts, and the probe is seated again. One change is counted (the probe's return, the one
  // that moves its tip): a new ATC step and a new settling jump. Instantaneous on the
  // program's clock (the dwell's length is the program's).
  void dutyToolChange() {
    next_duty_change_ = drawDutyGap();
    if (tool_ == m_.probe.tool && tr_.atc_repeatability_um > 0)
      for (int k = 0; k < 3; ++k) atc_um_(k) = tr_.atc_repeatability_um * duty_atc_normal_(duty_atc_rng_);
    recordToolChange("duty");
  }

  // Counted in the inputs CSV's next row; a holder seated in the warm spindle starts a unit
  // settling jump. The jumps add: the spindle nose's heat deficit obeys a linear heat
  // equation, so the responses to successive cold holders superpose (model/effects.hpp
  // `transient`, the same primitive). The empty spindle seats no holder.
  void recordToolChange(const char* source) {
    ++tool_changes_;
    const bool holder = tool_ != m_.tool_change.empty_tool;
    if (holder && tr_.settling_tau_s > 0) settling_ += 1.0;
    tool_change_log_.push_back({{"time_s", t_}, {"tool", tool_}, {"source", source}});
  }

  void sample() {
    inputs_ << formatNumber(t_, 3);
    for (std::size_t i = 0; i < tr_.thermal.sensors.size(); ++i) {
      const auto& s = tr_.thermal.sensors[i];
      const double T = s.node < 0 ? tr_.thermal.environment.at(t_) : net_.temperatures_C()(s.node);
      const double noisy = T + sensor_offset_[i] + (s.noise_K > 0 ? s.noise_K * sensor_normal_(sensor_rng_) : 0.0);
      inputs_ << "," << formatNumber(noisy, 3);
    }
    inputs_ << "," << formatNumber(cRpm(t_), 3) << "," << formatNumber(spindle_rpm_, 3) << ","
            << formatNumber(path_speed_mm_per_min_, 3) << ","
            << (mwfOn(t_) ? 1 : 0) << "," << tool_changes_ << "\n";
    tool_changes_ = 0;
    last_sample_t_ = t_;
    ++sample_index_;
  }

  double settlingUm() const { return tr_.settling_tool_Z_um * settling_; }

  double nodeRise(int node) const {
    return node < 0 || !tr_.thermal.present ? 0.0 : net_.temperatures_C()(node) - T0_;
  }

  // --- where things really are ----------------------------------------------------------
  Vector3d toolDriftUm() const {
    Vector3d d(tr_.static_errors.tool_um[0], tr_.static_errors.tool_um[1], tr_.static_errors.tool_um[2]);
    if (tr_.thermal.present)
      for (int i = 0; i < net_.size(); ++i)
        for (int k = 0; k < 3; ++k) d(k) += tr_.thermal.per_node_K[i].tool_um[k] * nodeRise(i);
    d.z() += settlingUm();
    return d + atc_um_;
  }

  // A move from pos_ to `to` lasting dt_s winds each moving axis's drive up against its
  // direction, in proportion to the axis's speed (capped); a still axis keeps what its last
  // move left (MachineTruth::lost_motion_um_per_m_per_min).
  void noteAxesMotion(const Vector3d& to, double dt_s) {
    if (tr_.lost_motion_um_per_m_per_min == Vector3d::Zero() || !(dt_s > 0)) return;
    for (int k = 0; k < 3; ++k) {
      const double dk = to(k) - pos_.xyz_mm(k);
      lost_motion_moving_[k] = std::fabs(dk) >= 1e-9;
      if (!lost_motion_moving_[k]) continue;
      const double v_m_per_min = std::fabs(dk) / dt_s * 60.0 / 1000.0;
      const double lag = std::min(tr_.lost_motion_um_per_m_per_min(k) * v_m_per_min, tr_.lost_motion_max_um);
      lost_motion_um_(k) = dk > 0 ? -lag : lag;
    }
  }

  // The axes' scale errors now: static plus each node's per kelvin of its rise (um per mm).
  Vector3d scaleUmPerMm() const {
    Vector3d s(tr_.static_errors.scale_um_per_mm[0], tr_.static_errors.scale_um_per_mm[1],
               tr_.static_errors.scale_um_per_mm[2]);
    if (tr_.thermal.present)
      for (int i = 0; i < net_.size(); ++i)
        for (int k = 0; k < 3; ++k) s(k) += tr_.thermal.per_node_K[i].scale_um_per_mm[k] * nodeRise(i);
    return s;
  }

  std::array<double, 7> locationErrors() const {
    auto v = tr_.static_errors.location;
    const auto kf = tr_.keyframeAt(t_).values();
    for (int j = 0; j < 7; ++j) v[j] += kf[j];
    if (tr_.thermal.present)
      for (int i = 0; i < net_.size(); ++i)
        for (int j = 0; j < 7; ++j) v[j] += tr_.thermal.per_node_K[i].location[j] * nodeRise(i);
    return v;
  }

  double currentToolLength() const { return toolLength(tool_); }
  double tipRadius() const {
    // A piece may name its own stylus (the stepped workpiece's d2 ball); else the machine's.
    if (tool_ == m_.probe.tool)
      return (w_ && w_->probe_tip_diameter_mm > 0 ? w_->probe_tip_diameter_mm : m_.probe.tip_diameter_mm) / 2;
    if (const auto* t = cutter()) return t->diameter_mm / 2;
    return 0.0;
  }
  const parts::CuttingTool* cutter() const { return w_ ? w_->tool(tool_) : nullptr; }
  bool isCutter() const { return cutter() != nullptr; }

  // Tool-side error of the tip (mm) at a commanded gauge-line position.
  Vector3d toolError(const Vector3d& g) const {
    Vector3d d = toolDriftUm() * 1e-3;
    if (tr_.axes.any) {
      // Abbe levers: a tool-side axis's angular error turns the tool about the gauge line
      // (lever gauge line -> tip); a workpiece-side axis's turns the table about its surface
      // under the tip (lever table -> tip). Errors are tool-relative-to-workpiece (ISO 230-1).
      const double tip_z = g.z() - currentToolLength();
      const Vector3d tool_lever(0, 0, -currentToolLength()), table_lever(0, 0, tip_z - m_.table_surface_z_mm);
      for (int ax = 0; ax < 3; ++ax) {
        const auto& c = tr_.axes.coeff[ax];
        const double p = g(ax);
        Vector3d trans(poly(c[0], p), poly(c[1], p), poly(c[2], p));
        Vector3d rot(poly(c[3], p), poly(c[4], p), poly(c[5], p));
        d += trans * 1e-3 + (rot * 1e-6).cross(m_.workpiece_side[ax] ? table_lever : tool_lever);
      }
    }
    // Scale errors (static and thermal): EXX = s x at the machine coordinate.
    d += scaleUmPerMm().cwiseProduct(g) * 1e-3;
    d += lost_motion_um_ * 1e-3;
    // Squareness as right-hand rotations of the Y and Z axes (docs/simulator.md).
    d.x() += -tr_.EC0Y_urad * 1e-6 * g.y() + tr_.EB0Z_urad * 1e-6 * g.z();
    d.y() += -tr_.EA0Z_urad * 1e-6 * g.z();
    return d;
  }

  // The part of toolError that the linear axes' geometric errors and squareness make (um).
  Vector3d axesErrorUm(const Vector3d& gauge) const { return toolError(gauge) * 1e3 - toolDriftUm(); }

  Vector3d tipActual(const Vector3d& gauge) const {
    return gauge - Vector3d(0, 0, currentToolLength()) + toolError(gauge);
  }

  Artifact artifact() const {
    Artifact art;
    art.dT = nodeRise(tr_.artifact.node);
    const double grow = 1.0 + partAlpha() * art.dT;
    const double th = degToRad(a_->angle_at_c0_deg + cSense() * pos_.c_deg);
    const Vector3d& pe = tr_.artifact.placement_error_mm;
    const Eigen::Vector2d pe_turned = parts::turnedByTable(pe.head<2>(), pos_.c_deg, m_.c.positive_is_clockwise);
    const Vector3d placement(pe_turned.x(), pe_turned.y(), pe.z());
    const Vector3d nominal(m_.c_axis_centre_mm.x() + a_->radius_from_axis_mm * grow * std::cos(th),
                           m_.c_axis_centre_mm.y() + a_->radius_from_axis_mm * grow * std::sin(th),
                           m_.table_surface_z_mm + a_->centreHeightAboveTable() * grow);
    art.location = locationErrors();
    art.centre = geometry::displacedOnTable(nominal + placement, m_.c_axis_centre_mm,
                                            geometry::LocationErrors::fromValues(art.location));
    art.radius = a_->sphereRadius() * grow;
    art.stem_radius = a_->stem_diameter_mm / 2;
    art.table_z = m_.table_surface_z_mm;
    return art;
  }

  // Smallest s in [0,1] where the tip sphere touches the artifact sphere while moving in;
  // -1 if it does not.
  double firstSphereContact(const Vector3d& a, const Vector3d& b, const Artifact& art) const {
    const double Rt = art.radius + tipRadius();
    const Vector3d d = b - a, w = a - art.centre;
    const double A = d.squaredNorm(), B = d.dot(w), C = w.squaredNorm() - Rt * Rt;
    if (C <= 0) return 0.0;  // already in contact at the start
    const double disc = B * B - A * C;
    if (disc < 0 || A == 0) return -1.0;
    const double s = (-B - std::sqrt(disc)) / A;
    return s >= 0 && s <= 1 ? s : -1.0;
  }

  // Where the tip sphere enters the artifact sphere on the whole line through a and b
  // (parameter s, negative = behind a); none if the line misses it.
  std::optional<double> sphereEntryOnLine(const Vector3d& a, const Vector3d& b, const Artifact& art) const {
    const double Rt = art.radius + tipRadius();
    const Vector3d d = b - a, w = a - art.centre;
    const double A = d.squaredNorm(), B = d.dot(w), C = w.squaredNorm() - Rt * Rt;
    const double disc = B * B - A * C;
    if (disc < 0 || A == 0) return std::nullopt;
    return (-B - std::sqrt(disc)) / A;
  }

  void checkStemAndTable(const Vector3d& a, const Vector3d& b, const Artifact& art, const std::string& what) const {
    const double r = tipRadius();
    const Vector3d stem_top(art.centre.x(), art.centre.y(), art.centre.z() - art.radius);
    const Vector3d stem_bottom(art.centre.x(), art.centre.y(), art.table_z);
    if (segmentDistance(a, b, stem_bottom, stem_top) < art.stem_radius + r - 1e-9)
      throw SafetyError(what + " would hit the artifact's stem");
    if (std::min(a.z(), b.z()) - r < art.table_z - 1e-9)
      throw SafetyError(what + " would hit the table: tip at Z " + formatNumber(std::min(a.z(), b.z()), 4) +
                        " mm, radius " + formatNumber(r, 4) + " mm, table surface Z " + formatNumber(art.table_z, 4));
  }

  // A non-probing move must not touch anything.
  void checkPath(const MachinePosition& to, const std::string& what) const {
    if (w_) return checkWorkpiecePath(to, what);
    if (!a_) return;
    const Artifact art = artifact();
    if (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg) {
      // The table turns under a still tip: it must be clear of the sphere's circle.
      const Vector3d tip = tipActual(pos_.xyz_mm);
      if (tip.z() - tipRadius() < art.centre.z() + art.radius + 1e-9) {
        const double r_tip = std::hypot(tip.x() - m_.c_axis_centre_mm.x(), tip.y() - m_.c_axis_centre_mm.y());
        const double r_art = std::hypot(art.centre.x() - m_.c_axis_centre_mm.x(), art.centre.y() - m_.c_axis_centre_mm.y());
        if (std::fabs(r_tip - r_art) < art.radius + tipRadius())
          throw SafetyError(what + " turns the table while the tip is below the top of the sphere at its radius");
      }
      if (to.xyz_mm == pos_.xyz_mm) return;
    }
    const Vector3d a = tipActual(pos_.xyz_mm), b = tipActual(to.xyz_mm);
    const double Rt = art.radius + tipRadius();
    // After a trigger the stylus is deflected into the surface by pre-travel, delay and
    // overshoot (< 0.5 mm); a move that leaves from there outward is the retract.
    const bool retract = (a - art.centre).norm() > Rt - 0.5 && (a - art.centre).dot(b - a) >= 0;
    if (!retract && segmentDistance(a, b, art.centre, art.centre) < Rt - 1e-9)
      throw SafetyError(what + " would pass through the sphere artifact");
    checkStemAndTable(a, b, art, what);
  }

  void checkFeed(double F) const {
    const double fmax = std::min({m_.x.max_feed_mm_per_min, m_.y.max_feed_mm_per_min, m_.z.max_feed_mm_per_min});
    if (F > fmax + 1e-9)
      throw SafetyError("feed F" + formatNumber(F) + " exceeds the machine's maximum feed " + formatNumber(fmax) + " mm/min");
  }

  void checkRotaryFeed(const MachinePosition& to, double F_deg_per_min) const {
    const double rpm = F_deg_per_min / 360.0;
    auto check = [&](const parts::RotaryAxis& ax, const char* name, double delta) {
      if (delta == 0) return;
      const double limit = ax.max_turning_speed_rpm > 0 ? ax.max_turning_speed_rpm : ax.max_speed_rpm;
      if (rpm > limit + 1e-9)
        throw SafetyError(std::string("rotary feed F") + formatNumber(F_deg_per_min) + " deg/min (" + formatNumber(rpm) +
                          " rpm) exceeds the " + name + " axis's maximum turning speed " + formatNumber(limit) + " rpm");
    };
    check(m_.c, "C", to.c_deg - pos_.c_deg);
    check(m_.b, "B", to.b_deg - pos_.b_deg);
  }

  void checkTravel(const MachinePosition& to) const {
    const parts::LinearAxis* ax[] = {&m_.x, &m_.y, &m_.z};
    const char* names[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; ++k)
      if (!(to.xyz_mm(k) >= ax[k]->min_mm - 1e-9 && to.xyz_mm(k) <= ax[k]->max_mm + 1e-9))
        throw SafetyError(std::string("move outside travel: ") + names[k] + " " + formatNumber(to.xyz_mm(k)) +
                          " mm (gauge line, machine coordinates) is outside [" + formatNumber(ax[k]->min_mm) +
                          ", " + formatNumber(ax[k]->max_mm) + "]");
    if (to.b_deg != 0 && !m_.b.present) throw SafetyError("move of B on a machine without a B axis");
    if (!std::isfinite(to.b_deg) || !std::isfinite(to.c_deg)) throw SafetyError("a rotary target that is not a number");
    if (m_.b.present && !m_.b.continuous && !(to.b_deg >= m_.b.min_deg - 1e-9 && to.b_deg <= m_.b.max_deg + 1e-9))
      throw SafetyError("move outside travel: B " + formatNumber(to.b_deg) + " deg");
    if (to.c_deg != 0 && !m_.c.present) throw SafetyError("move of C on a machine without a C axis");
    if (m_.c.present && !m_.c.continuous && !(to.c_deg >= m_.c.min_deg - 1e-9 && to.c_deg <= m_.c.max_deg + 1e-9))
      throw SafetyError("move outside travel: C " + formatNumber(to.c_deg) + " deg");
  }

  double pretravel(const Vector3d& dir) const {
    const auto& p = tr_.probe;
    const double h = std::hypot(dir.x(), dir.y());
    const double phi = std::atan2(dir.y(), dir.x());
    const double lateral = p.pretravel_um + p.lobe_amplitude_um * std::cos(p.lobes * (phi - degToRad(p.lobe_phase_deg)));
    return h * lateral + std::fabs(dir.z()) * p.pretravel_vertical_um;
  }


  // --- the workpiece --------------------------------------------------------------------
  // Machine coordinates of a point (tip coordinates) -> the part frame at 20 °C: undo the
  // table's location errors (a rigid motion), turn back to C = 0, then tableToPart.
  Vector3d toWorkpiece(const Vector3d& q) const {
    // The table's location errors as a rigid motion about the C axis at the table surface
    // (a clamped workpiece moves with the table as one body; ER0T, a radial growth of the
    // table, does not move it).
    const auto e = locationErrors();
    const Vector3d pivot(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), m_.table_surface_z_mm);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(e[4] * 1e-6, Vector3d::UnitX()) *
                               Eigen::AngleAxisd(e[5] * 1e-6, Vector3d::UnitY()) *
                               Eigen::AngleAxisd(-e[6] * 1e-6, Vector3d::UnitZ())).toRotationMatrix();
    const Vector3d t(e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3);
    Vector3d p = pivot + R.transpose() * (q - t - pivot);
    const Eigen::Vector2d c = m_.c_axis_centre_mm;
    p.head<2>() = c + parts::unturnedByTable(p.head<2>() - c, pos_.c_deg, m_.c.positive_is_clockwise);
    return tableToPart(p);
  }
  // A point on the table at C = 0 (machine coordinates, the table's errors undone) -> the
  // part frame at 20 °C: less `artifact.placement_error`, less the part frame's origin
  // (machine coordinates at C = 0), less the lift of a warm support (adapter and washers of
  // the part's alloy at its temperature: alpha dT support_height; kind: workpiece has none),
  // and the part's own expansion about its datum (the blank's bottom centre) undone.
  Vector3d tableToPart(Vector3d p) const {
    const double e = partAlpha() * workpieceAbove20K();
    p -= tr_.artifact.placement_error_mm;  // where the part really sits on the table
    p -= w_->frame_origin_mm;              // machine at C = 0 -> part frame
    if (w_->support_height_mm != 0) p.z() -= e * w_->support_height_mm;
    return w_->datum() + (p - w_->datum()) / (1.0 + e);
  }
  // Where the C axis is in the part frame (at 20 °C); the tool circles about it when C
  // turns. For the thermal test piece it is the origin.
  Eigen::Vector2d cAxisInPart() const {
    return tableToPart(Vector3d(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), 0)).head<2>();
  }
  // A part angle th appears in the machine at th + s C: s = -1 when +C turns the table clockwise.
  double cSense() const { return parts::tableTurnSign(m_.c.positive_is_clockwise); }
  // The part's expansion coefficient: the truth's when it states one, else the material's.
  double partAlpha() const {
    if (tr_.artifact.alpha_per_K) return *tr_.artifact.alpha_per_K;
    return w_ ? w_->material.alpha_per_K : 0.0;
  }
  // The workpiece's temperature above 20 °C, where the CMM measures it.
  double workpieceAbove20K() const {
    return tr_.artifact.node >= 0 && tr_.thermal.present ? net_.temperatures_C()(tr_.artifact.node) - 20.0 : 0.0;
  }
  // A direction in the workpiece frame -> machine frame (rotation by C only).
  Vector3d workpieceDirToMachine(const Vector3d& v) const {
    const Eigen::Vector2d m = parts::turnedByTable(v.head<2>(), pos_.c_deg, m_.c.positive_is_clockwise);
    return Vector3d(m.x(), m.y(), v.z());
  }

  // Does the tool at gauge position g sit in material (height field)? For a flat end mill
  // the bottom disk; for the probe the tip ball's lower part (reach r/2, 0.866 r below).
  bool inMaterial(const Vector3d& g, double tolerance_mm = 1e-6) const {
    const Vector3d w = toWorkpiece(tipActual(g));
    const double r = tipRadius();
    const bool ball = tool_ == m_.probe.tool;
    const double reach = ball ? 0.5 * r : std::max(0.0, r - 0.2);
    const double bottom = ball ? w.z() - 0.866 * r : w.z();
    if (bottom + 1e-6 >= stock_.max().z()) return false;  // above the stock: no cell can be higher
    return stock_.topUnder(w.head<2>(), reach) > bottom + tolerance_mm;
  }

  // The lowest point of what is in the spindle, below the tip (the probe's ball reaches r
  // below its centre; a flat end mill's tip is its bottom).
  double bottomBelowTip() const { return tool_ == m_.probe.tool ? tipRadius() : 0.0; }

  // Obstacles (adapter, washers, clamps) must not be touched. The tool is a vertical
  // cylinder of its radius (the probe: of its ball's radius) from its bottom upward; it
  // touches an obstacle where its axis comes closer than the two radii while its bottom is
  // below the obstacle's top. Exact for a straight move in the part frame: the stretch of the
  // move within reach (a disk interval) and the lowest bottom there (linear in the move).
  void checkObstacles(const Vector3d& w0, const Vector3d& w1, const std::string& what) const {
    if (!w_ || w_->obstacles.empty()) return;
    const double r = tipRadius(), below = bottomBelowTip();
    for (const auto& o : w_->obstacles) {
      const double reach = o.radius_mm + r - 1e-9;
      const Eigen::Vector2d u = w0.head<2>(), v = (w1 - w0).head<2>(), d = u - o.centre_mm;
      double lo = 0, hi = 1;
      const double A = v.squaredNorm(), B = v.dot(d), C = d.squaredNorm() - reach * reach;
      if (A < 1e-18) {
        if (C >= 0) continue;
      } else {
        const double disc = B * B - A * C;
        if (disc <= 0) continue;
        lo = std::max(0.0, (-B - std::sqrt(disc)) / A);
        hi = std::min(1.0, (-B + std::sqrt(disc)) / A);
        if (lo > hi) continue;
      }
      const double z_lo = w0.z() + lo * (w1.z() - w0.z()), z_hi = w0.z() + hi * (w1.z() - w0.z());
      const double s = z_lo <= z_hi ? lo : hi;
      if (std::min(z_lo, z_hi) - below < o.z_max_mm - 1e-9) {
        const Vector3d at = w0 + s * (w1 - w0);
        throw SafetyError(what + " would touch the " + o.name + " (an obstacle) at X " + formatNumber(at.x(), 3) + " Y " +
                          formatNumber(at.y(), 3) + " Z " + formatNumber(at.z(), 3) + " (part frame)");
      }
    }
  }
  // The same while C turns: the tool circles about the axis in the part frame.
  void checkObstaclesArc(const Eigen::Vector2d& axis, double rho, double lo, double span, double z_tip,
                         const std::string& what) const {
    if (!w_ || w_->obstacles.empty()) return;
    const double r = tipRadius(), below = bottomBelowTip();
    for (const auto& o : w_->obstacles)
      if (z_tip - below < o.z_max_mm - 1e-9 && arcDistance(o.centre_mm, axis, rho, lo, span) < o.radius_mm + r - 1e-9)
        throw SafetyError(what + " turns the table so that the tool would touch the " + o.name +
                          " (an obstacle): tool at radius " + formatNumber(rho, 3) + " mm from the C axis, Z " +
                          formatNumber(z_tip, 3) + " (part frame)");
  }

  // Turning the table under a still tool: allowed above the stock, and below its top when
  // the tool stays clear of all material it could meet: its edge outside the largest radius
  // (about the C axis) of material higher than the tool's bottom, plus a clearance of 0.5 mm
  // (the height field's cells are 0.25 mm). The test waits at r = 130 mm, z = -12.1 mm while
  // the table turns ~1500 times; the radius is cached until a cut changes the stock.
  void checkTurn(const MachinePosition& to, const std::string& what) const {
    const Vector3d w = toWorkpiece(tipActual(pos_.xyz_mm));
    const double r = tipRadius(), bottom = w.z() - bottomBelowTip();
    const Eigen::Vector2d axis = cAxisInPart();
    const double rho = (w.head<2>() - axis).norm();
    if (bottom < stock_.max().z() + 1e-9) {
      const double material = stock_.maxMaterialRadius(axis, bottom);
      if (!(rho - r > material + kTurnClearance_mm))
        throw SafetyError(what + " turns the table with the tool below the top of the stock and within reach of its "
                          "material (tool edge " + formatNumber(rho - r, 3) + " mm from the C axis; material up to " +
                          formatNumber(material, 3) + " mm, plus " + formatNumber(kTurnClearance_mm) + " mm clearance)");
    }
    const TurnArc arc = turnArc(w, axis, to.c_deg - pos_.c_deg);
    checkObstaclesArc(axis, rho, arc.ccw.lo, arc.ccw.span, w.z(), what);
  }
  static constexpr double kTurnClearance_mm = 0.5;

  // The arc a still tool at part position w describes when C changes by dc_deg: it starts at
  // its angle about the axis and sweeps -s dC (counterclockwise positive); `ccw` is the same
  // as a counterclockwise [lo, lo + span] of at most one turn.
  struct TurnArc {
    double start = 0, sweep = 0;
    CcwArc ccw;
  };
  TurnArc turnArc(const Vector3d& w, const Eigen::Vector2d& axis, double dc_deg) const {
    TurnArc a;
    a.start = std::atan2(w.y() - axis.y(), w.x() - axis.x());
    a.sweep = -cSense() * degToRad(dc_deg);
    a.ccw = ccwArc(a.start, a.sweep);
    return a;
  }

  void checkWorkpiecePath(const MachinePosition& to, const std::string& what) const {
    const Vector3d a = pos_.xyz_mm, b = to.xyz_mm;
    if (to.c_deg != pos_.c_deg && a != b) checkTogetherWithC(to, what);
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.5)));
    // Straight up from where the tool stands: it rests on the floor the last feed move cut and,
    // where the axes' Z errors vary along X/Y, sits a fraction of a micrometre in the floor
    // that neighbouring passes cut: the start tolerates 2 um of it (a tool 0.3 mm too long
    // after a tool change is still caught); rising, the same footprint only leaves material.
    const bool straight_up = b.z() > a.z() && b.head<2>() == a.head<2>() && to.c_deg == pos_.c_deg;
    for (int k = 0; k <= n; ++k) {
      const Vector3d g = a + (b - a) * (static_cast<double>(k) / n);
      const Vector3d tip = tipActual(g);
      if (tip.z() - (tool_ == m_.probe.tool ? tipRadius() : 0.0) < m_.table_surface_z_mm - 1e-9)
        throw SafetyError(what + " would hit the table at tip Z " + formatNumber(tip.z(), 4) + " mm");
      if (inMaterial(g, straight_up && k == 0 ? 2e-3 : 1e-6)) {
        const Vector3d w = toWorkpiece(tip);
        throw SafetyError(what + " would move through the workpiece's material at X " + formatNumber(w.x(), 3) +
                          " Y " + formatNumber(w.y(), 3) + " Z " + formatNumber(w.z(), 3) + " (workpiece frame)");
      }
    }
    if (!w_->obstacles.empty() && a != b) checkObstacles(toWorkpiece(tipActual(a)), toWorkpiece(tipActual(b)), what);
    if (to.c_deg != pos_.c_deg) checkTurn(to, what);
  }

  // X/Y/Z moving together with C: in the part frame the tool follows a curve (the line
  // turned by the changing C), which the path checks (the straight line at the start's C,
  // then the turn at the start's X/Y/Z) do not follow. Above the top of the part and of every
  // obstacle nothing can be met, so it is allowed there; below it, refused as not modelled
  // (the planner never moves them together: it turns C alone, or above the part).
  void checkTogetherWithC(const MachinePosition& to, const std::string& what) const {
    double top = stock_.max().z();
    for (const auto& o : w_->obstacles) top = std::max(top, o.z_max_mm);
    const double bottom = std::min(toWorkpiece(tipActual(pos_.xyz_mm)).z(), toWorkpiece(tipActual(to.xyz_mm)).z()) -
                          bottomBelowTip();
    if (bottom < top + 1e-9)
      throw SafetyError(what + " moves X/Y/Z and C together below the top of the part: not modelled (the tool's bottom "
                        "reaches Z " + formatNumber(bottom, 3) + ", the part and its obstacles Z " + formatNumber(top, 3) +
                        ", part frame); turn C alone, or move above the top");
  }

  // Seed 000 Eq. 3.16 with I1 = I2 = I (the printed E*I^2 is read as E*I, notes §4.8):
  // deflection per newton of a cantilevered end mill, mm/N.
  static double toolCompliance(const parts::CuttingTool& t) {
    const double L1 = t.flute_length_mm, L2 = t.stickout_mm, E = t.youngs_modulus_N_per_mm2;
    const double I = kPi * std::pow(t.diameter_mm, 4) / 64.0;
    return (L1 * L1 * L1 / 3.0 + L1 * (L2 - L1) * (L2 + L1) / 6.0 + L2 * (L2 - L1) * (2 * L2 + L1) / 6.0) / (E * I);
  }

  // Compliance of tool and structure along a machine direction (unit, XY).
  double compliance(const parts::CuttingTool& t, const Vector3d& away_m) const {
    double c = toolCompliance(t);
    const auto& k = tr_.stiffness_N_per_um;
    for (int i = 0; i < 2; ++i)
      if (k(i) > 0) c += away_m(i) * away_m(i) * 1e-3 / k(i);
    return c;
  }

  // The machine's state when a cut starts (truth.json relates the as-cut surfaces to it).
  void recordCutState(const Vector3d& deflection_mm = Vector3d::Zero(), const Vector3d* from = nullptr,
                      const Vector3d* to = nullptr, double feed = 0) {
    CutState s;
    s.deflection_um = deflection_mm * 1e3;
    if (from && to) {
      s.axes_start_um = axesErrorUm(*from);
      s.axes_end_um = axesErrorUm(*to);
    }
    s.feed_mm_per_min = feed;
    s.spindle_rpm = spindle_rpm_;
    s.time_s = t_;
    s.tool = tool_;
    s.location = locationErrors();
    s.tool_um = toolDriftUm();
    s.part_above_20C_K = workpieceAbove20K();
    s.scale_um_per_mm = scaleUmPerMm();
    s.lost_motion_um = lost_motion_um_;
    cut_states_.push_back(s);
  }

  // A cutting feed move: material removed along the real tool path; the mean cutting force
  // from the removal rate (P = k_c Q, F_t = P / v_c); the radial force K_r F_t pushes the
  // tool away from the material, which bends (Eq. 3.16) and the structure yields (F/k); the
  // surface cut is the swept volume of the displaced path.
  void cutMove(const MachinePosition& to, double F) {
    const parts::CuttingTool& t = *cutter();
    const double r = t.diameter_mm / 2;
    if (to.b_deg != pos_.b_deg || (to.c_deg != pos_.c_deg && to.xyz_mm != pos_.xyz_mm))
      throw InputError("", 0, "cutting with a rotary axis moving together with X/Y/Z (or B) is not modelled");
    if (to.c_deg != pos_.c_deg) return arcCut(to, F);
    const double len_cut = (to.xyz_mm - pos_.xyz_mm).norm();
    noteAxesMotion(to.xyz_mm, len_cut / F * 60.0);
    const Vector3d w0 = toWorkpiece(tipActual(pos_.xyz_mm)), w1 = toWorkpiece(tipActual(to.xyz_mm));
    const double table_z = m_.table_surface_z_mm - w_->frame_origin_mm.z();
    if (w0.z() < table_z - 1e-9 || w1.z() < table_z - 1e-9)
      throw SafetyError("feed move (G1/G2/G3) would cut into the table");
    checkObstacles(w0, w1, "feed move (G1/G2/G3)");
    const double len = (to.xyz_mm - pos_.xyz_mm).norm();
    const double dt = len / F * 60.0;
    // A chord of a ring around the part cannot reach the blank: nothing to remove (the hot
    // path of the test's moves around the part).
    const Removal rem = stock_.segmentReachesBlank(w0, w1, r) ? stock_.removeHeightField(w0, w1, r) : Removal{};
    Vector3d defl = Vector3d::Zero();
    double Ft = 0, Fn = 0;
    if (rem.volume_mm3 > 0 && dt > 0) {
      const double vc = kPi * t.diameter_mm * std::fabs(spindle_rpm_) / 60.0;  // mm/s
      Ft = w_->material.specific_cutting_force_N_per_mm2 * (rem.volume_mm3 / dt) / vc;
      // Lateral offset of the removed material from the path, in the workpiece frame.
      const Eigen::Vector2d a = w0.head<2>(), ab = w1.head<2>() - a;
      Eigen::Vector2d lateral = rem.centroid.head<2>() - a;
      if (ab.norm() > 1e-12) {
        const Eigen::Vector2d e = ab.normalized();
        lateral -= lateral.dot(e) * e;
      }
      if (lateral.norm() > 0.05 * r) {
        Fn = w_->material.radial_force_ratio * Ft;
        const Vector3d away_w(-lateral.x() / lateral.norm(), -lateral.y() / lateral.norm(), 0);
        const Vector3d away_m = workpieceDirToMachine(away_w);
        defl = away_w * (Fn * compliance(t, away_m));
      }
    }
    // The cut is made warm; in the 20 °C frame the tool's radius shrinks with the part.
    const double r_w = r / (1.0 + partAlpha() * workpieceAbove20K());
    const int tag = static_cast<int>(cut_states_.size());
    const bool stored = stock_.recordCut(w0 + defl, w1 + defl, r_w, t_, tag);
    // A run of cutting moves that cannot touch the blank (a ring around the part, which the
    // controller follows as thousands of chords) is one entry in cuts.json; a single such
    // move keeps its full entry.
    const bool air = rem.volume_mm3 == 0 && !stored;
    if (air && air_run_motion_ == motions_ && !cuts_.empty()) {
      auto& e = cuts_.back();
      if (!e.contains("kind")) e = {{"time_s", e["time_s"]}, {"tool", e["tool"]}, {"kind", "air"}, {"moves", 1}};
      e["moves"] = e["moves"].get<long>() + 1;
      e["until_s"] = t_ + dt;
    } else {
      recordCutState(defl, &pos_.xyz_mm, &to.xyz_mm, F);
      const Vector3d drift = toolDriftUm();
      cuts_.push_back({{"time_s", t_}, {"tool", tool_},
                       {"p0_mm", {w0.x() + defl.x(), w0.y() + defl.y(), w0.z()}},
                       {"p1_mm", {w1.x() + defl.x(), w1.y() + defl.y(), w1.z()}},
                       {"radius_mm", r_w}, {"removed_mm3", rem.volume_mm3}, {"Ft_N", Ft}, {"Fn_N", Fn},
                       {"deflection_um", {defl.x() * 1e3, defl.y() * 1e3}},
                       {"tool_drift_um", {drift.x(), drift.y(), drift.z()}}});
      if (tr_.axes.any || tr_.EC0Y_urad != 0 || tr_.EB0Z_urad != 0 || tr_.EA0Z_urad != 0 || scaleUmPerMm() != Vector3d::Zero()) {
        const Vector3d a0 = axesErrorUm(pos_.xyz_mm), a1 = axesErrorUm(to.xyz_mm);
        cuts_.back()["axes_um"] = {{a0.x(), a0.y(), a0.z()}, {a1.x(), a1.y(), a1.z()}};
      }
    }
    const double t0 = t_;
    move(dt, F);
    traceRow("cut", to, F, t0);
    if (air) air_run_motion_ = motions_;
    pos_ = to;
  }

  // Cutting while C turns (pre-machining step 1, seed 004 L2006: "circular milled by turning
  // the rotary table; no linear axis is moved"): in the part frame the still tool circles
  // the C axis. Removal and force as for a line (force from the removal rate over the first
  // turn, which removes all there is); the radial force pushes the tool away from the
  // material: outward when the removed material lies inside the circle. A turn whose swept
  // annulus cannot reach the material is no cut (the test's load turns the table a thousand
  // times with the tool waiting outside the part): timed and checked only.
  void arcCut(const MachinePosition& to, double F_deg_per_min) {
    const parts::CuttingTool& t = *cutter();
    const double r = t.diameter_mm / 2;
    const Vector3d q = tipActual(pos_.xyz_mm);
    const Vector3d w0 = toWorkpiece(q);
    const double table_z = m_.table_surface_z_mm - w_->frame_origin_mm.z();
    if (w0.z() < table_z - 1e-9) throw SafetyError("feed move (G1) would cut into the table");
    const Eigen::Vector2d axis = cAxisInPart();
    const double rho = (w0.head<2>() - axis).norm();
    const double dc = to.c_deg - pos_.c_deg;
    const TurnArc arc = turnArc(w0, axis, dc);
    const double start = arc.start, sweep = arc.sweep;
    checkObstaclesArc(axis, rho, arc.ccw.lo, arc.ccw.span, w0.z(), "feed move (G1)");
    const double dt = std::fabs(dc) / F_deg_per_min * 60.0;
    const double turns = std::fabs(sweep) / (2 * kPi);
    const double cut_sweep = std::clamp(sweep, -2 * kPi, 2 * kPi);
    const bool reaches = w0.z() < stock_.max().z() && rho - r <= stock_.maxMaterialRadius(axis, w0.z()) + kTurnClearance_mm;
    const double t0 = t_;
    if (reaches) {
      const Removal rem = stock_.removeHeightFieldArc(axis, rho, start, cut_sweep, w0.z(), r);
      double Ft = 0, Fn = 0, defl_mm = 0;  // radial, outward positive
      const double dt_cut = dt / std::max(1.0, turns);  // the first turn removes it all
      Vector3d away_m = Vector3d::Zero();
      if (rem.volume_mm3 > 0 && dt_cut > 0) {
        const double vc = kPi * t.diameter_mm * std::fabs(spindle_rpm_) / 60.0;  // mm/s
        Ft = w_->material.specific_cutting_force_N_per_mm2 * (rem.volume_mm3 / dt_cut) / vc;
        const double lateral = rem.mean_radius_mm - rho;  // > 0: the material lay outside the circle
        if (std::fabs(lateral) > 0.05 * r && rho > 1e-9) {
          Fn = w_->material.radial_force_ratio * Ft;
          const double sign = lateral > 0 ? -1.0 : 1.0;
          // Radial in the machine: from the axis to the still tool.
          const Eigen::Vector2d radial_m = (q.head<2>() - m_.c_axis_centre_mm).normalized();
          away_m = Vector3d(sign * radial_m.x(), sign * radial_m.y(), 0);
          defl_mm = sign * Fn * compliance(t, away_m);
        }
      }
      const double r_w = r / (1.0 + partAlpha() * workpieceAbove20K());
      const int tag = static_cast<int>(cut_states_.size());
      recordCutState();
      stock_.recordArc(axis, rho + defl_mm, start, cut_sweep, w0.z(), r_w, t_, tag);
      const Vector3d drift = toolDriftUm();
      const Eigen::Vector2d e0(std::cos(start), std::sin(start));
      cuts_.push_back({{"time_s", t_}, {"tool", tool_}, {"kind", "arc"},
                       {"centre_mm", {axis.x(), axis.y()}}, {"path_radius_mm", rho + defl_mm}, {"z_mm", w0.z()},
                       {"start_deg", radToDeg(start)}, {"sweep_deg", radToDeg(cut_sweep)}, {"turns", turns},
                       {"radius_mm", r_w}, {"removed_mm3", rem.volume_mm3}, {"Ft_N", Ft}, {"Fn_N", Fn},
                       {"deflection_um", {e0.x() * defl_mm * 1e3, e0.y() * defl_mm * 1e3}},
                       {"radial_deflection_um", defl_mm * 1e3},
                       {"tool_drift_um", {drift.x(), drift.y(), drift.z()}}});
    }
    c_move_rpm_ = cMoveRpm(to, dt);
    move(dt, 0.0);
    c_move_rpm_ = 0;
    traceRow(reaches ? "cut" : "feed", to, F_deg_per_min, t0);
    pos_ = to;
  }

  gcode::ProbeOutcome probeWorkpiece(const MachinePosition& to, double F, const Vector3d& dir, double len,
                                     gcode::ProbeMode mode) {
    double s_contact = -1;
    if (w_) {
      const double r = tipRadius();
      const Vector3d a = toWorkpiece(tipActual(pos_.xyz_mm)), b = toWorkpiece(tipActual(to.xyz_mm));
      const Vector3d d = (b - a).normalized();
      // Distances in the workpiece frame (20 °C) -> machine travel.
      const double to_machine = len / (b - a).norm();
      // The ball touches a surface square to the approach when its centre is r from it, in the
      // workpiece frame (where the axes' errors stretch the path): (s - r) of real travel.
      if (const auto s = stock_.firstMaterial(a, d, (b - a).norm() + r / to_machine)) {
        s_contact = (*s - r) * to_machine;
        if (s_contact < 0) {
          if (mode != gcode::ProbeMode::SkipToTarget)
            throw SafetyError("probe move starts with the probe already in contact (tripped)");
          s_contact = 0;
        }
      }
      if (s_contact > len) s_contact = -1;
      // Nothing else in the way before the contact (height field).
      MachinePosition until = to;
      if (s_contact >= 0) until.xyz_mm = pos_.xyz_mm + dir * std::max(0.0, s_contact - 0.01);
      checkWorkpiecePath(until, "probe move");
    }
    const double pre_um = pretravel(dir);
    const double s_trig = s_contact >= 0 ? s_contact + pre_um * 1e-3 + F / 60.0 * tr_.probe.trigger_delay_s : 2 * len;
    if (s_contact < 0 || s_trig > len) return noTrigger(to, len, F);
    ProbeEvent ev = newEvent(dir, pre_um);
    ev.location = locationErrors();
    ev.tool_um = toolDriftUm();
    ev.axes_um = axesErrorUm(pos_.xyz_mm + dir * s_contact);
    for (int k = 0; k < 3; ++k)  // what the calibrated stylus takes out (latchTrigger)
      if (lost_motion_moving_[k]) (*ev.axes_um)(k) -= lost_motion_um_(k);
    ev.scale_um_per_mm = scaleUmPerMm();
    ev.atc_um = atc_um_;
    ev.settling_um = settlingUm();
    ev.artifact_dT_K = nodeRise(tr_.artifact.node);
    ev.apparent = ev.location;
    return latchTrigger(ev, dir, s_trig, F);
  }

 public:
  const Stock& stock() const { return stock_; }
  const std::vector<CutState>& cutStates() const { return cut_states_; }
  double partAlphaPerK() const { return partAlpha(); }
  // With several programs a last column names the program each line belongs to.
  void enableTrace(bool with_program) {
    trace_on_ = true;
    trace_program_ = with_program;
    trace_ << "time_s,duration_s,line,kind,x_mm,y_mm,z_mm,b_deg,c_deg,feed_mm_per_min,tool"
           << (with_program ? ",program" : "") << "\n";
  }
  std::string traceText() const { return trace_.str(); }
  std::string cutsJson() const { return cuts_.dump(1) + "\n"; }
  const nlohmann::ordered_json& toolChangeLog() const { return tool_change_log_; }

 private:
  void fillTruth(ProbeEvent& ev, const Artifact& art) const {
    ev.location = art.location;
    ev.tool_um = toolDriftUm();
    ev.atc_um = atc_um_;
    ev.settling_um = settlingUm();
    ev.artifact_dT_K = art.dT;
    // What a sphere campaign evaluation sees: table errors minus the tool's translation,
    // plus the artifact's own growth (radius from the axis and height).
    ev.apparent = art.location;
    const double alpha_um_per_m_K = partAlpha() * 1e6;
    ev.apparent[0] -= ev.tool_um.x();
    ev.apparent[1] -= ev.tool_um.y();
    ev.apparent[2] -= ev.tool_um.z();
    // The ball grows too; the known-radius fit reads that as a lift of the centre by the
    // radius change, because only the top point sees Z (docs/simulator.md). The same
    // alpha L dT as the model's `expansion` effect.
    ev.apparent[2] += model::expansion_um(alpha_um_per_m_K, a_->centreHeightAboveTable() + a_->sphereRadius(), art.dT);
    ev.apparent[3] += model::expansion_um(alpha_um_per_m_K, a_->radius_from_axis_mm, art.dT);
  }
};

}  // namespace

parts::Workpiece placeOnMachine(const parts::TestPiece& piece, const parts::Machine& machine) {
  if (const auto* t = piece.thermalTestPiece()) {
    if (!machine.c.present)
      throw InputError(machine.file, 0, "the thermal test piece is cut and indexed on a C axis, and this machine has none");
    parts::Workpiece w = *piece.stock;
    w.frame_origin_mm = parts::partOriginOnMachine(*t, machine.c_axis_centre_mm, machine.table_surface_z_mm);
    return w;
  }
  if (const auto* sw = piece.steppedWorkpiece()) {
    // The blank on its fixture on the table, the steps' centre where the planner put it.
    parts::Workpiece w = *piece.stock;
    w.frame_origin_mm = parts::steppedWorkpieceOrigin(*sw, machine);
    return w;
  }
  if (!piece.stock)
    throw InputError(piece.file, 0, "kind: " + piece.kind + " is not machined: it stands on the table as it is, not as a workpiece");
  return *piece.stock;
}

namespace {

gcode::ProgramDialect dialectOf(const std::string& program_file, const parts::Machine& machine) {
  const std::string ext = std::filesystem::path(program_file).extension().string();
  gcode::ProgramDialect dialect = machine.dialect == parts::Dialect::LinuxCnc ? gcode::ProgramDialect::LinuxCnc
                                                                              : gcode::ProgramDialect::FanucMacroB;
  if (ext == ".ngc") dialect = gcode::ProgramDialect::LinuxCnc;
  if (ext == ".nc" || ext == ".tap") dialect = gcode::ProgramDialect::FanucMacroB;
  return dialect;
}

}  // namespace

SimulationOutputs simulateProgram(const std::string& program_file, const std::string& text,
                                  const parts::Machine& machine, const SimulationPart& part,
                                  const MachineTruth& truth, std::uint64_t seed) {
  return simulatePrograms({{program_file, text, std::nullopt}}, machine, part, truth, seed);
}

SimulationOutputs simulatePrograms(const std::vector<ProgramSource>& programs, const parts::Machine& machine,
                                   const SimulationPart& given, const MachineTruth& truth, std::uint64_t seed) {
  if (programs.empty()) throw InputError("", 0, "simulate needs at least one program");
  SimulationPart part = given;
  std::optional<parts::Workpiece> placed;
  if (given.test_piece) {
    if (given.artifact || given.workpiece)
      throw InputError("", 0, "simulate needs exactly one part on the table: a test piece, or an artifact or workpiece, not both");
    if (const auto* a = given.test_piece->sphereArtifact()) {
      part.artifact = a;
    } else {
      placed = placeOnMachine(*given.test_piece, machine);
      part.workpiece = &*placed;
    }
  }
  if (part.artifact && !machine.c.present)
    throw InputError(machine.file, 0, "the sphere artifact stands on a rotary table, and this machine has no C axis");
  if (part.artifact && truth.artifact.node >= 0 && !truth.artifact.alpha_per_K)
    throw InputError(truth.file, 0, "artifact.alpha_um_per_m_K: a sphere artifact on a thermal node needs its expansion coefficient");
  if ((part.artifact != nullptr) == (part.workpiece != nullptr))
    throw InputError("", 0, "simulate needs exactly one part on the table: a sphere artifact or a workpiece");
  if (!part.cmm_points.empty() && !part.workpiece)
    throw InputError("", 0, "CMM points need a workpiece (kind: workpiece) as the part");
  const bool multi = programs.size() > 1;
  if (multi && part.trace)
    for (const auto& p : programs)
      if (std::filesystem::path(p.file).filename().string().find(',') != std::string::npos)
        throw InputError(p.file, 0, "a program file name with a comma cannot be named in trace.csv's program column");

  VirtualMachine vm(machine, part, truth, seed);
  if (part.trace) vm.enableTrace(multi);
  SimulationOutputs out;
  bool last_fanuc = false;
  std::optional<double> last_start;
  for (const auto& p : programs) {
    if (p.start_s && last_start && *p.start_s < *last_start)
      throw InputError(p.file, 0, "planned to start at " + formatNumber(*p.start_s, 1) + " s, before the program given before it (" +
                                      formatNumber(*last_start, 1) + " s): give the programs in their planned order");
    if (p.start_s) last_start = p.start_s;
    const gcode::ProgramDialect dialect = dialectOf(p.file, machine);
    last_fanuc = dialect == gcode::ProgramDialect::FanucMacroB;
    gcode::Interpreter interp(dialect, p.file, p.text);
    if (p.start_s && *p.start_s > vm.time()) vm.machineOff(*p.start_s - vm.time());
    vm.beginProgram(p.file, last_fanuc);
    const auto run = interp.run(vm);
    vm.endProgram();
    out.blocks += run.blocks_executed;
  }
  vm.finish();
  if (!multi) vm.ensureLog(last_fanuc);

  out.end_time_s = vm.time();
  out.logs = vm.logs();
  if (!out.logs.empty()) {
    out.log_name = out.logs.front().name;
    out.log_text = out.logs.front().text;
  }
  out.trace_csv = vm.traceText();
  if (part.workpiece) {
    out.cuts_json = vm.cutsJson();
    if (!part.cmm_points.empty()) {
      std::vector<Eigen::Vector3d> measured;
      if (part.cmm_plan) checkCmmMoves(vm.stock(), *part.cmm_plan);
      out.cmm_csv = measureOnCmm(vm.stock(), *part.workpiece, part.cmm_points, part.cmm_points_file, seed, vm.partAlphaPerK(), 5.0,
                                 &measured);
      if (part.cmm_plan) {
        const auto results = cmmResultsDocument(*part.cmm_plan, measured);
        out.cmm_qif = interop::qifResults(results);
        out.cmm_dmo = interop::dmisOutput(results, "PROBELOOP SIMULATED CMM");
      }
    }
  }

  out.inputs_csv = vm.inputsText();
  const auto& events = vm.events();
  out.probe_events = static_cast<long>(events.size());

  // Canonical points: the logged points (as reported) joined with the event behind each.
  std::map<std::pair<int, long>, const ProbeEvent*> by_line;
  for (const auto& e : events)
    if (e.log_line > 0) by_line[{e.log_stream, e.log_line}] = &e;
  // The points CSV needs the planner's log convention ("PT cycle position point x y z").
  struct Logged {
    int stream;
    gcode::LoggedProbePoint p;
  };
  std::vector<Logged> logged;
  std::vector<std::string> not_pt;
  for (std::size_t i = 0; i < out.logs.size(); ++i) {
    try {
      for (const auto& p : gcode::parseProbeLog(out.logs[i].text, out.logs[i].name)) logged.push_back({static_cast<int>(i), p});
    } catch (const InputError&) {
      not_pt.push_back(out.logs[i].name);
    }
  }
  std::string files;
  for (const auto& p : programs) files += (files.empty() ? "" : " ") + p.file;
  // A sphere artifact's positions are spheres (S<position>); any other part's are points of
  // its features, which the evaluation maps through the plan manifest (P<position>).
  const std::string feature_prefix = part.artifact ? "S" : "P";
  std::ostringstream csv;
  csv << "# probeloop simulate " << files << ", seed " << seed << "\n";
  if (!multi && !not_pt.empty()) csv << "# the log does not follow the planner's PT convention: no points\n";
  if (multi)
    for (const auto& n : not_pt) csv << "# the log " << n << " does not follow the planner's PT convention: no points from it\n";
  csv << "time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  nlohmann::ordered_json jt;
  jt["format"] = "probeloop-truth";
  jt["generator"] = "probeloop simulate";
  jt["seed"] = seed;
  jt["relative_to_cycle"] = 1;
  jt["note"] = "apparent_* = table-side location errors minus the tool-side translation plus the artifact's "
               "growth: what a sphere-artifact evaluation measures (docs/simulator.md)";
  // Quantised reports are whole resolution steps: print them as the decimals they are (6
  // for 1 um); unquantised ones at full precision (shortest round trip).
  const int decimals = truth.probe.quantise ? 6 : -1;
  std::map<int, std::pair<int, std::array<double, 7>>> per_cycle;  // cycle -> (n, sum)
  std::map<int, double> cycle_time;
  const auto& names = geometry::LocationErrors::names();
  for (const auto& [stream, p] : logged) {
    const auto it = by_line.find({stream, p.line});
    const std::string& log_name = out.logs[static_cast<std::size_t>(stream)].name;
    if (it == by_line.end())
      throw InputError(log_name, p.line, "log line without a probe event (the program logged without probing)");
    const ProbeEvent& e = *it->second;
    csv << formatNumber(e.time_s, 3) << "," << p.cycle << "," << formatNumber(e.c_deg) << "," << feature_prefix
        << p.position << "," << p.point << "," << formatNumber(e.reported_tip_mm.x(), decimals) << ","
        << formatNumber(e.reported_tip_mm.y(), decimals) << "," << formatNumber(e.reported_tip_mm.z(), decimals) << ","
        << formatNumber(e.approach.x(), 6) << "," << formatNumber(e.approach.y(), 6) << ","
        << formatNumber(e.approach.z(), 6) << "\n";
    nlohmann::ordered_json je{{"time_s", e.time_s}, {"log_line", e.log_line}};
    if (multi) je["log"] = log_name;
    je["cycle"] = p.cycle;
    je["position"] = p.position;
    je["point"] = p.point;
    je["c_deg"] = e.c_deg;
    for (int j = 0; j < 7; ++j) je[names[j]] = e.location[j];
    je["tool_um"] = {e.tool_um.x(), e.tool_um.y(), e.tool_um.z()};
    je["atc_um"] = {e.atc_um.x(), e.atc_um.y(), e.atc_um.z()};
    je["settling_um"] = e.settling_um;
    je["artifact_dT_K"] = e.artifact_dT_K;
    je["pretravel_um"] = e.pretravel_um;
    je["noise_um"] = e.noise_um;
    if (e.axes_um) je["axes_um"] = {e.axes_um->x(), e.axes_um->y(), e.axes_um->z()};
    if (e.scale_um_per_mm != Vector3d::Zero())
      je["scale_um_per_mm"] = {e.scale_um_per_mm.x(), e.scale_um_per_mm.y(), e.scale_um_per_mm.z()};
    for (int j = 0; j < 7; ++j) je[std::string("apparent_") + names[j]] = e.apparent[j];
    jt["events"].push_back(je);
    auto& acc = per_cycle[p.cycle];
    if (acc.first == 0) cycle_time[p.cycle] = e.time_s;
    ++acc.first;
    for (int j = 0; j < 7; ++j) acc.second[j] += e.apparent[j];
  }
  if (!per_cycle.empty()) {
    const auto& ref = per_cycle.begin()->second;
    for (const auto& [cyc, acc] : per_cycle) {
      nlohmann::ordered_json jc{{"cycle", cyc}, {"time_s", cycle_time[cyc]}};
      for (int j = 0; j < 7; ++j) jc[names[j]] = acc.second[j] / acc.first - ref.second[j] / ref.first;
      jt["cycles"].push_back(jc);
    }
  }
  jt["tool_changes"] = vm.toolChangeLog();
  // A machined test piece with measurement features: what a perfect CMM at 20 °C finds on
  // the surfaces as cut, and the errors the evaluation should find from them.
  if (given.test_piece && given.test_piece->thermalTestPiece() && part.workpiece) {
    const auto t = testPieceTruth(*given.test_piece, vm.stock(), vm.cutStates());
    writeTestPieceTruth(t, jt);
  } else if (given.test_piece && part.workpiece) {
    writeAsCutFeatures(asCutFeatures(*given.test_piece, vm.stock()), vm.cutStates(), jt);
  }
  out.points_csv = csv.str();
  out.truth_json = jt.dump(1) + "\n";
  return out;
}

}  // namespace probeloop::sim
