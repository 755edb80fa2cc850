// The virtual machine as the interpreter sees it (gcode::MachineInterface): rapid and feed
// moves (checked, timed and traced; cutting moves go to machine_cutting.cpp), the probe
// move (its physics in machine_probing.cpp), dwell, tool change, spindle, and the
// controller's logs (LinuxCNC LOGOPEN files, the one Fanuc dprnt.txt). The class:
// sim/virtual_machine_detail.hpp.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "parts/machine_clock.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim::detail {

void VirtualMachine::atLine(int line) {
  line_ = line;
  ++lines_started_;
  if (until_s_ && t_ >= *until_s_) throw TimeLimitReached{};
}

void VirtualMachine::refreshOffsets() {
  if (!live_) return;
  const Vector3d tip = pos_.xyz_mm - Vector3d(0, 0, currentToolLength());
  offset_mm_ = live_->offsetsUm(t_, tip, pos_.b_deg) * 1e-3;
}

void VirtualMachine::rapid(const MachinePosition& to) {
  refreshOffsets();
  checkTravel(to);
  checkAxisA(to);
  checkPath(to, "rapid (G0)");
  const double t = parts::rapidSeconds(m_, to.xyz_mm - pos_.xyz_mm, to.b_deg - pos_.b_deg, to.c_deg - pos_.c_deg,
                                       to.a_deg - pos_.a_deg);
  const double t0 = t_;
  noteAxesMotion(to.xyz_mm, t);
  move(t, t > 0 ? (to.xyz_mm - pos_.xyz_mm).norm() / t * 60.0 : 0.0);
  traceRow("rapid", to, 0, t0);
  pos_ = to;
}

void VirtualMachine::feed(const MachinePosition& to, double F) {
  refreshOffsets();
  checkTravel(to);
  // A move of rotary axes alone reads F in deg/min (LinuxCNC and Fanuc): the axis turns at
  // F / 360 rpm, limited by its turning speed, not by the XYZ feed.
  const bool rotary_only =
      to.xyz_mm == pos_.xyz_mm && (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg || to.a_deg != pos_.a_deg);
  checkAxisA(to, rotary_only ? F : 0.0);
  if (rotary_only) checkRotaryFeed(to, F);
  else checkFeed(F);
  if (w_ && isCutter() && spindle_rpm_ != 0) {
    cutMove(to, F);
    return;
  }
  checkPath(to, spindle_rpm_ == 0 && isCutter() ? "feed move (G1/G2/G3) with the spindle stopped" : "feed move (G1/G2/G3)");
  const double len = (to.xyz_mm - pos_.xyz_mm).norm();
  const double rot = std::max({std::fabs(to.c_deg - pos_.c_deg), std::fabs(to.b_deg - pos_.b_deg),
                               std::fabs(to.a_deg - pos_.a_deg)});
  const double t0 = t_;
  const double dt = len > 0 ? parts::linearFeedSeconds(len, F) : parts::rotaryFeedSeconds(rot, F);
  c_move_rpm_ = cMoveRpm(to, dt);
  noteAxesMotion(to.xyz_mm, dt);
  move(dt, len > 0 ? F : 0.0);
  c_move_rpm_ = 0;
  traceRow("feed", to, F, t0);
  pos_ = to;
}

// The A axis (a cradle about X): its travel, and its turning speed in a move of the rotary axes
// alone at F deg/min (rotary_feed > 0). machine_kinematics.cpp's checkTravel and
// checkRotaryFeed cover X, Y, Z, B and C.
void VirtualMachine::checkAxisA(const MachinePosition& to, double rotary_feed_deg_per_min) const {
  if (!std::isfinite(to.a_deg)) throw SafetyError("a rotary target that is not a number");
  if (to.a_deg != pos_.a_deg && !m_.a.present) throw SafetyError("move of A on a machine without an A axis");
  if (!m_.a.present) return;
  if (!m_.a.continuous && !(to.a_deg >= m_.a.min_deg - 1e-9 && to.a_deg <= m_.a.max_deg + 1e-9))
    throw SafetyError("move outside travel: A " + formatNumber(to.a_deg) + " deg");
  if (rotary_feed_deg_per_min > 0 && to.a_deg != pos_.a_deg) {
    const double rpm = rotary_feed_deg_per_min / 360.0;
    const double limit = m_.a.max_turning_speed_rpm > 0 ? m_.a.max_turning_speed_rpm : m_.a.max_speed_rpm;
    if (rpm > limit + 1e-9)
      throw SafetyError("rotary feed F" + formatNumber(rotary_feed_deg_per_min) + " deg/min (" + formatNumber(rpm) +
                        " rpm) exceeds the A axis's maximum turning speed " + formatNumber(limit) + " rpm");
  }
}

// The C axis's real speed during a feed move that turns it (a heat input, and the inputs
// CSV's c_rpm). Rapid indexing (G0 C) at the positioning speed lasts < 1 s per quarter
// turn and is left out, so the sphere campaigns' outputs stay as they were.
double VirtualMachine::cMoveRpm(const MachinePosition& to, double dt_s) const {
  if (!(dt_s > 0) || to.c_deg == pos_.c_deg) return 0;
  return std::fabs(to.c_deg - pos_.c_deg) / 360.0 / (dt_s / 60.0);
}

gcode::ProbeOutcome VirtualMachine::probe(const MachinePosition& to, double F, gcode::ProbeMode mode) {
  refreshOffsets();
  const double t0 = t_;
  const auto r = probeMove(to, F, mode);
  traceRow(r.contact ? "probe_contact" : "probe_no_contact", to, F, t0);
  return r;
}

void VirtualMachine::dwell(double s) {
  refreshOffsets();
  const double t0 = t_;
  dwelling_ = true;
  advance(s);
  dwelling_ = false;
  traceRow("dwell", pos_, 0, t0);
}

void VirtualMachine::toolChange(int tool) {
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

double VirtualMachine::toolLength(int tool) const {
  if (tool == m_.probe.tool) return m_.probe.length_mm;
  if (tool == m_.tool_change.empty_tool) return 0.0;
  if (w_)
    if (const auto* t = w_->tool(tool)) return t->length_mm;
  throw InputError("", 0, "G43 H" + std::to_string(tool) + ": no such tool in the machine's tool table");
}

void VirtualMachine::spindle(double rpm) {
  if (rpm != 0 && tool_ == m_.probe.tool)
    throw SafetyError("spindle start (M3/M4) with the touch probe in the spindle");
  spindle_rpm_ = rpm;
}

// --- the controller's logs -----------------------------------------------------------------
// Fanuc: every program's DPRNT goes to the one dprnt.txt (POPEN names no file). LinuxCNC:
// the program's LOGOPEN file; a later LOGOPEN in the same program renames it (the last
// name wins, as before); a name an earlier program of the run wrote is refused, because
// LinuxCNC would overwrite that log.
void VirtualMachine::openLog(const std::string& name) {
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

void VirtualMachine::log(const std::string& line) {
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
  if (live_) live_->logLine(t_, l.name, line);
}

// A new log of the current program; its index.
int VirtualMachine::newStream(const std::string& name) {
  auto l = std::make_unique<LogStream>();
  l->name = name;
  l->fanuc = program_fanuc_;
  l->program = program_index_;
  l->program_file = program_file_;
  logs_.push_back(std::move(l));
  return static_cast<int>(logs_.size()) - 1;
}

// The run's log of this name (Fanuc's dprnt.txt) becomes the current one, new if there is none.
void VirtualMachine::streamFor(const std::string& name) {
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

}  // namespace probeloop::sim::detail
