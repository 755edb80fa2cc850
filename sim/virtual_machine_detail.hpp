// Internal to sim/: the virtual machine behind simulateProgram(s) (sim/virtual_machine.hpp),
// one gcode::MachineInterface that the interpreter drives, program after program. It keeps
// the clock, the thermal network and the inputs CSV, the tool and the axes' real state, the
// stock as it is cut, the probe events and the controller's logs; simulatePrograms reads
// them out into SimulationOutputs. Nothing outside sim/ includes this header.
//
// Its member functions are defined by job (docs/simulator.md §2 describes the physics):
// - virtual_machine.cpp: construction, programs (begin, end, machine off), results, and the
//   public entry points (placeOnMachine, simulateProgram, simulatePrograms);
// - machine_motion.cpp: the gcode::MachineInterface: rapid and feed moves, the probe move's
//   entry, dwell, tool change, spindle and the controller's logs;
// - machine_probing.cpp: the touch probe: contact with the sphere or the workpiece,
//   pre-travel, trigger delay, the latched position and the truth of each event;
// - machine_clock.cpp: the clock and the thermal state: heat inputs, time steps, the duty's
//   tool changes, the inputs CSV and the motion trace;
// - machine_kinematics.cpp: where things really are: the tool-side errors, the tip, the
//   sphere artifact on the table, and the checks of travel, feed and collisions with it;
// - machine_cutting.cpp: the workpiece: its frame, collisions with its material and its
//   obstacles, and cutting (removal, forces, deflection, cuts.json).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "gcode/interpreter.hpp"
#include "gcode/probe_program.hpp"
#include "sim/machine_truth.hpp"
#include "sim/material_removal.hpp"
#include "sim/piece_truth.hpp"
#include "sim/thermal_network.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::sim::detail {

using Eigen::Vector3d;
using gcode::MachinePosition;

// Thrown at the first block at or after SimulationPart::until_s: the run ends there.
struct TimeLimitReached {};

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
                 std::uint64_t seed);

  MachinePosition start() const override { return pos_; }
  // The controller's clock (Fanuc #3011/#3012): Monday 2026-01-05 at the truth's start_clock
  // (the hall's time of day at t = 0; midnight without one), then the simulated time.
  double controllerClockS() const override { return 4 * 86400.0 + tr_.thermal.environment.start_clock_s + t_; }
  void atLine(int line) override;
  // What the live loop wrote (sim/live_link.hpp); nothing without one.
  std::optional<double> externalVariable(int n) const override {
    return live_ ? live_->externalVariable(t_, n) : std::nullopt;
  }
  // Analog input 1 carries the machine's clock (the inputs' time_s), as a live-interval LinuxCNC
  // program expects (gcode/probe_program.hpp); the others come from the live loop, or read 0.
  double analogInput(int n) override {
    if (n == gcode::kLiveClockLinuxCncInput) return t_;
    return live_ ? live_->analogInput(t_, n) : 0.0;
  }

  // --- gcode::MachineInterface (machine_motion.cpp) ---------------------------------------
  void rapid(const MachinePosition& to) override;
  void feed(const MachinePosition& to, double F) override;
  gcode::ProbeOutcome probe(const MachinePosition& to, double F, gcode::ProbeMode mode) override;
  void dwell(double s) override;
  void toolChange(int tool) override;
  double toolLength(int tool) const override;
  void spindle(double rpm) override;
  void coolant(bool on) override { coolant_ = on; }
  void openLog(const std::string& name) override;
  void log(const std::string& line) override;
  void closeLog() override {}

  // --- programs (virtual_machine.cpp) -----------------------------------------------------
  void beginProgram(const std::string& file, bool fanuc);
  void endProgram();
  void ensureLog(bool fanuc);
  void machineOff(double s);

  // --- results (virtual_machine.cpp) ------------------------------------------------------
  double time() const { return t_; }
  long linesStarted() const { return lines_started_; }  // atLine calls so far
  std::vector<LogOutput> logs() const;
  std::string inputsText() const { return inputs_.str(); }
  const std::vector<ProbeEvent>& events() const { return events_; }
  void finish();
  const Stock& stock() const { return stock_; }
  const std::vector<CutState>& cutStates() const { return cut_states_; }
  double partAlphaPerK() const { return partAlpha(); }
  void enableTrace(bool with_program);
  std::string traceText() const { return trace_.str(); }
  std::string cutsJson() const { return cuts_.dump(1) + "\n"; }
  const nlohmann::ordered_json& toolChangeLog() const { return tool_change_log_; }

 private:
  struct Artifact {
    Vector3d centre;      // actual sphere centre (tip coordinates)
    double radius = 0;    // actual sphere radius
    double stem_radius = 0;
    double table_z = 0;
    double dT = 0;
    std::array<double, 7> location{};
    // The table's normal and a point of its surface (tilted with A or B; else +Z at table_z).
    Vector3d up = Vector3d::UnitZ();
    Vector3d table_point = Vector3d::Zero();
  };

  // --- moves and logs (machine_motion.cpp) ------------------------------------------------
  double cMoveRpm(const MachinePosition& to, double dt_s) const;
  int newStream(const std::string& name);
  void streamFor(const std::string& name);

  // --- the touch probe (machine_probing.cpp) ----------------------------------------------
  gcode::ProbeOutcome probeMove(const MachinePosition& to, double F, gcode::ProbeMode mode);
  gcode::ProbeOutcome noTrigger(const MachinePosition& to, double len, double F);
  ProbeEvent newEvent(const Vector3d& dir, double pretravel_um) const;
  gcode::ProbeOutcome latchTrigger(ProbeEvent ev, const Vector3d& dir, double travel_mm, double F);
  double pretravel(const Vector3d& dir) const;
  double firstSphereContact(const Vector3d& a, const Vector3d& b, const Artifact& art) const;
  std::optional<double> sphereEntryOnLine(const Vector3d& a, const Vector3d& b, const Artifact& art) const;
  void fillTruth(ProbeEvent& ev, const Artifact& art) const;
  gcode::ProbeOutcome probeWorkpiece(const MachinePosition& to, double F, const Vector3d& dir, double len,
                                     gcode::ProbeMode mode);

  // --- clock and thermal state (machine_clock.cpp) ----------------------------------------
  double cRpm(double t);
  bool mwfOn(double t) const;
  Eigen::VectorXd heat(double t);
  void traceRow(const char* kind, const MachinePosition& to, double feed, double t_start);
  void move(double dt, double speed_mm_per_min);
  void advance(double dt);
  double drawDutyGap();
  void dutyToolChange();
  void recordToolChange(const char* source);
  void sample();
  double settlingUm() const { return tr_.settling_tool_Z_um * settling_; }
  double nodeRise(int node) const;

  // --- where things really are (machine_kinematics.cpp) -----------------------------------
  Vector3d toolDriftUm() const;
  void noteAxesMotion(const Vector3d& to, double dt_s);
  Vector3d scaleUmPerMm() const;
  std::array<double, 7> locationErrors() const;
  std::array<double, 6> tiltLocationErrors() const;
  // Where the tilting axis (with its location errors) takes a point of the level table;
  // the identity without a tilt and without tilt errors.
  Eigen::Isometry3d tiltTransform() const;
  double currentToolLength() const { return toolLength(tool_); }
  double tipRadius() const;
  const parts::CuttingTool* cutter() const { return w_ ? w_->tool(tool_) : nullptr; }
  bool isCutter() const { return cutter() != nullptr; }
  Vector3d toolError(const Vector3d& g) const;
  // The part of toolError that the linear axes' geometric errors and squareness make (um).
  Vector3d axesErrorUm(const Vector3d& gauge) const { return toolError(gauge) * 1e3 - toolDriftUm(); }
  Vector3d tipActual(const Vector3d& gauge) const;
  Artifact artifact() const;
  void checkStemAndTable(const Vector3d& a, const Vector3d& b, const Artifact& art, const std::string& what) const;
  void checkPath(const MachinePosition& to, const std::string& what) const;
  void checkFeed(double F) const;
  void checkRotaryFeed(const MachinePosition& to, double F_deg_per_min) const;
  void checkTravel(const MachinePosition& to) const;
  void checkAxisA(const MachinePosition& to, double rotary_feed_deg_per_min = 0) const;  // machine_motion.cpp

  // --- the workpiece (machine_cutting.cpp) ------------------------------------------------
  Vector3d toWorkpiece(const Vector3d& q) const;
  Vector3d tableToPart(Vector3d p) const;
  Eigen::Vector2d cAxisInPart() const;
  // A part angle th appears in the machine at th + s C: s = -1 when +C turns the table clockwise.
  double cSense() const { return parts::tableTurnSign(m_.c.positive_is_clockwise); }
  double partAlpha() const;
  double workpieceAbove20K() const;
  Vector3d workpieceDirToMachine(const Vector3d& v) const;
  bool inMaterial(const Vector3d& g, double tolerance_mm = 1e-6) const;
  // The lowest point of what is in the spindle, below the tip (the probe's ball reaches r
  // below its centre; a flat end mill's tip is its bottom).
  double bottomBelowTip() const { return tool_ == m_.probe.tool ? tipRadius() : 0.0; }
  void checkObstacles(const Vector3d& w0, const Vector3d& w1, const std::string& what) const;
  void checkObstaclesArc(const Eigen::Vector2d& axis, double rho, double lo, double span, double z_tip,
                         const std::string& what) const;
  void checkTurn(const MachinePosition& to, const std::string& what) const;
  static constexpr double kTurnClearance_mm = 0.5;

  // The arc a still tool at part position w describes when C changes by dc_deg: it starts at
  // its angle about the axis and sweeps -s dC (counterclockwise positive); `ccw` is the same
  // as a counterclockwise [lo, lo + span] of at most one turn.
  struct TurnArc {
    double start = 0, sweep = 0;
    CcwArc ccw;
  };
  TurnArc turnArc(const Vector3d& w, const Eigen::Vector2d& axis, double dc_deg) const;

  void checkWorkpiecePath(const MachinePosition& to, const std::string& what) const;
  void checkTogetherWithC(const MachinePosition& to, const std::string& what) const;
  static double toolCompliance(const parts::CuttingTool& t);
  double compliance(const parts::CuttingTool& t, const Vector3d& away_m) const;
  void recordCutState(const Vector3d& deflection_mm = Vector3d::Zero(), const Vector3d* from = nullptr,
                      const Vector3d* to = nullptr, double feed = 0);
  void cutMove(const MachinePosition& to, double F);
  void arcCut(const MachinePosition& to, double F_deg_per_min);

  // The live loop's offsets now, at the nominal tip of the current position (before a motion).
  void refreshOffsets();

  // --- state ------------------------------------------------------------------------------
  LiveLink* live_ = nullptr;
  std::optional<double> until_s_;
  Vector3d offset_mm_ = Vector3d::Zero();  // external offsets in effect (added to the commanded XYZ)
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
  std::string inputs_header_;  // the inputs CSV's lines before the first row
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
  std::vector<ProbeEvent> events_;
  int line_ = 0;
  long lines_started_ = 0;
  bool trace_on_ = false, trace_program_ = false;
  std::ostringstream trace_;
};

}  // namespace probeloop::sim::detail
