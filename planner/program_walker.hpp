// Walks a dialect-neutral program (gcode/program.hpp) the way the simulator's clock runs it
// and checks every target before any text is written. Used by the planners of machined
// test pieces (planner/thermal_test_piece.hpp).
//
// Clock (exactly docs/simulator.md §2 "Clock", no acceleration; the functions below are the
// one copy of it in the planner, the walker's and its tests'): rapids move every axis at the
// rapid feed (A, B and C at their maximum positioning speed) and take the slowest axis's time;
// feeds take XYZ path length / F, a move of C alone (TurnC) degrees / F; protected moves run
// to their end; measuring moves are timed to the nominal contact the planner names; dwells;
// tool changes at tool_change.time. Several programs run back to back in one session:
// position, C, tool and clock carry over. The machine starts with the gauge line at the top of
// the Z travel above the C axis (clamped into the X/Y travel), C = B = A = 0, empty spindle. C is
// a linear axis here, as in the simulator: after TurnC +360 it reads 360, and an absolute
// index from there turns the long way (a control with C rollover may go another way round:
// only the time differs, docs/thermal-test-piece.md §5).
//
// Checks (SafetyError "<program>: <where>: <what> ..." naming the axis and value): every
// number finite; every target of the gauge line (tip + tool length) within the X/Y/Z travel,
// A, B and C within theirs (a non-continuous C also for TurnC); linear feeds within the slowest
// axis's max_feed (as the simulator checks them); a move of C alone within C's
// max_turning_speed; a cut only with a cutter and the spindle turning; probing only with the
// probe and the spindle stopped; a tool change only with the spindle stopped and the gauge
// line at the tool-change height (G53 Z tool_change.z). Collisions are the caller's: every
// motion is handed to its check first (Motion).
#pragma once
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "gcode/program.hpp"
#include "parts/machine.hpp"
#include "parts/machine_clock.hpp"

namespace probeloop::planner {

// What the planner knows of an op beyond its G-code.
struct OpNote {
  std::string where;            // "test cycle 3, facet X2_3"
  bool cut = false;             // an intended cut: the tool may touch the part
  bool retract = false;         // straight back from a probe contact along the approach line
  int cut_index = -1;           // the manifest cut this op makes
  int point_index = -1;         // ProbeMove: the manifest point it probes
  Eigen::Vector3d contact_mm = Eigen::Vector3d::Zero();  // ProbeMove: nominal tip centre at contact
};

// A program as a planner builds it: ops and their notes side by side.
struct NotedProgram {
  std::string file, role;
  gcode::Program program;
  std::vector<OpNote> notes;
  // GeometryError "<file>: <where>: ..." for an op holding a number that is not finite (a
  // layout the planner did not refuse earlier: never written as "nan").
  void add(gcode::Op op, OpNote note);
};

// An empty program for this machine: its work offset (zeroed by the program) and the rotary
// axes it has.
NotedProgram newNotedProgram(const parts::Machine& m, const std::string& role, const std::string& file, int number,
                             const std::string& title);

// A tool the walker knows: from the part's tool list, the machine's probe, the empty spindle.
struct WalkerTool {
  int number = 0;
  double length_mm = 0, radius_mm = 0;
  bool probe = false, cutter = false;
};

enum class MotionKind {
  Rapid,       // G0 of X/Y/Z (program coordinates)
  MachineZ,    // G53 G0 Z: the retract to the tool-change height
  CIndex,      // G0 C
  Feed,        // G1 X/Y/Z (a cut when the note says so)
  CFeed,       // TurnC: C alone at a feed
  Protected,   // protected probe move
  Measuring,   // the measuring move (meant to touch the part)
};

// A motion about to be made, for the caller's collision check (program = machine tip
// coordinates; C in degrees).
struct Motion {
  const std::string* program = nullptr;
  const OpNote* note = nullptr;
  MotionKind kind = MotionKind::Rapid;
  const char* what = "";  // for messages: "rapid move", "cut", "C feed move", "probe move" ...
  Eigen::Vector3d from_tip = Eigen::Vector3d::Zero(), to_tip = Eigen::Vector3d::Zero();
  double from_c = 0, to_c = 0;
  WalkerTool tool;
};

// Seconds spent per kind of op (the summary's breakdown).
struct WalkTimes {
  double tool_change_s = 0, rapid_s = 0, rotary_index_s = 0, feed_s = 0, rotary_feed_s = 0, protected_s = 0,
         probing_s = 0, dwell_s = 0;
};

class ProgramWalker {
 public:
  ProgramWalker(const parts::Machine& m, std::vector<WalkerTool> tools);

  void setCheck(std::function<void(const Motion&)> check) { check_ = std::move(check); }
  // Called after every op (loops expanded: an op inside a loop once per pass) with its index
  // in the program and the clock before and after it.
  using OpCallback = std::function<void(std::size_t op, double t_before, double t_after)>;
  void run(const NotedProgram& p, const OpCallback& on_op = {});

  double time() const { return t_; }
  const WalkTimes& times() const { return times_; }
  Eigen::Vector3d tip() const { return gauge_ - Eigen::Vector3d(0, 0, tool_.length_mm); }
  double c() const { return c_; }

 private:
  void step(const gcode::Op& op, const OpNote& note);
  void checkTravel(const Eigen::Vector3d& gauge, const OpNote& note, const char* what) const;
  void checkCTravel(double c_deg, const OpNote& note, const char* what) const;
  // An A or B index: the axis present and the target in its travel, timed; `now` follows it.
  void tilt(const parts::RotaryAxis& axis, const char* name, double deg, double& now, const OpNote& note);
  void checkLinearFeed(double F, const OpNote& note, const char* what) const;
  void motion(MotionKind kind, const char* what, const Eigen::Vector3d& to_tip, double to_c, const OpNote& note) const;
  [[noreturn]] void fail(const OpNote& note, const std::string& message) const;
  const WalkerTool& toolFor(int number, const OpNote& note) const;

  const parts::Machine& m_;
  std::vector<WalkerTool> tools_;
  std::function<void(const Motion&)> check_;
  const std::string* program_ = nullptr;
  Eigen::Vector3d gauge_;
  double c_ = 0, b_ = 0, a_ = 0, t_ = 0, spindle_rpm_ = 0;
  WalkerTool tool_;  // number 0 = empty spindle until the first change
  WalkTimes times_;
};

// The clock is the machine's (parts/machine_clock.hpp), shared with the simulator.
using parts::linearFeedSeconds;
using parts::rapidSeconds;
using parts::rotaryFeedSeconds;
using parts::rotaryIndexSeconds;

// The value a writer prints (coordinates 4 decimals, C / feeds / dwells 3): planners build
// their ops from these so that what they time is what the controller reads.
double round4(double v);
double round3(double v);

}  // namespace probeloop::planner
