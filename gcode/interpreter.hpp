// Interpreter of the G-code the planner emits, in both dialects (LinuxCNC RS274NGC and
// Fanuc macro B): modal state, G0/G1/G2/G3 (XY plane), G38.2/G38.3 and G31 probing, G4,
// T/M6, G43/G49, M3/M4/M5 with S, M8/M9, G10 L2, G53, G54-G59, rotary axes A, B and C,
// #-parameters (numbered, and LinuxCNC named #<...>), expressions with [ ], functions and
// comparisons, LinuxCNC o-word while/if/elseif/else and Fanuc WHILE/DO/END, IF..GOTO,
// IF..THEN, GOTO, #3000 alarms, LinuxCNC LOGOPEN/LOG/LOGCLOSE/ABORT and Fanuc
// POPEN/DPRNT/PCLOS, and values written from outside while the program runs: Fanuc common
// variables #500..#999 and LinuxCNC M66 E<n> L0 (an analog input into #5399).
//
// Contract: the interpreter owns the controller's view (program coordinates, offsets,
// parameters, control flow) and asks a MachineInterface to move; the machine answers with
// what physically happened (probe contact) and keeps time. Positions handed to the machine
// are machine coordinates of the controlled point of the spindle (the gauge line): program
// coordinates + work offset + tool length (G43). Anything the interpreter does not model
// (a word, a G or M code, an o-word keyword, M98 subprograms, inch units, another plane)
// is an InputError "<file>:<line>: ..." naming it, never a silent skip. Errors the machine
// raises (SafetyError, InputError without a line) are re-thrown with the program line.
#pragma once
#include <Eigen/Dense>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace probeloop::gcode {

enum class ProgramDialect { LinuxCnc, FanucMacroB };

struct MachinePosition {
  Eigen::Vector3d xyz_mm = Eigen::Vector3d::Zero();  // gauge line, machine coordinates
  double a_deg = 0, b_deg = 0, c_deg = 0;
};

enum class ProbeMode {
  ErrorWithoutContact,  // LinuxCNC G38.2: no contact is an error that stops the program
  FlagContact,          // LinuxCNC G38.3: stops on contact, #5070 says whether it did
  SkipToTarget,         // Fanuc G31: stops on contact, completes the move otherwise
};

struct ProbeOutcome {
  bool contact = false;
  MachinePosition stop;  // where the controller latched (contact) or the target (none)
};

// The physical machine the program runs on. Each call advances the machine's clock.
class MachineInterface {
 public:
  virtual ~MachineInterface() = default;
  virtual void rapid(const MachinePosition& to) = 0;
  virtual void feed(const MachinePosition& to, double feed_mm_per_min) = 0;
  virtual ProbeOutcome probe(const MachinePosition& to, double feed_mm_per_min, ProbeMode mode) = 0;
  virtual void dwell(double seconds) = 0;
  virtual void toolChange(int tool) = 0;
  virtual double toolLength(int tool) const = 0;  // InputError for an unknown tool
  virtual void spindle(double rpm) = 0;           // 0 = stopped; negative = M4
  virtual void coolant(bool on) = 0;
  virtual void openLog(const std::string& name) = 0;
  virtual void log(const std::string& line) = 0;  // one line as the controller writes it
  virtual void closeLog() = 0;
  // Where the machine stands when the program starts (gauge line, machine coordinates).
  virtual MachinePosition start() const { return {}; }
  // The program line about to execute (for traces).
  virtual void atLine(int /*line*/) {}
  // The controller's clock: seconds since 2026-01-01 00:00 (Fanuc reads it as #3011, the date
  // YYYYMMDD, and #3012, the time HHMMSS; LinuxCNC has no clock a program can read).
  virtual double controllerClockS() const { return 0.0; }
  // Values the program reads from outside, at the instant it reads them (the sphere cycle's
  // live measurement interval, planner/sphere_cycle.hpp). The defaults are a machine nobody
  // writes to: the program sees what it stored itself, and inputs read 0.
  // - Fanuc common variables #500..#999 (retained; a FOCAS cnc_wrmacro writer sets them while
  //   the program runs): a value returned replaces the stored one, as if it had been written
  //   just before the read; nullopt keeps the stored one (0 when the program never set it).
  virtual std::optional<double> externalVariable(int /*n*/) const { return std::nullopt; }
  // - LinuxCNC M66 E<n> L0: analog input n (HAL motion.analog-in-NN) read at once; the
  //   interpreter stores it in #5399, as LinuxCNC does.
  virtual double analogInput(int /*n*/) { return 0.0; }
};

struct InterpreterResult {
  long blocks_executed = 0;
  bool ended = false;  // M2/M30 reached
};

// Each probe move's other outcome, tried without running the program again from its start
// (the safety verifier: is every probe move protected?). Right after a probe move's outcome is
// known, and only if that outcome does not itself stop the program (G38.2 without contact),
// the interpreter calls atProbe with a function that runs the rest of the program from this
// point with another outcome, on a copy of the run's state (position, modal state, parameters,
// control flow): the nominal run then goes on as if nothing happened. The machine is the same
// object in both, so atProbe saves and restores the machine's own state around the call.
// Errors of the branch (a SafetyError where the program stops, an InputError) reach atProbe.
// A branch does not branch again. The cost is that of the branch's own blocks: one run of the
// program plus what each branch executes, not one run per probe line.
class ProbeBranching {
 public:
  virtual ~ProbeBranching() = default;
  using RunWith = std::function<InterpreterResult(const ProbeOutcome& other)>;
  virtual void atProbe(const ProbeOutcome& nominal, const RunWith& run_with) = 0;
};

class Interpreter {
 public:
  Interpreter(ProgramDialect dialect, std::string file_name, const std::string& text);

  // The bound on blocks executed in one run: a program that has not ended by then is taken for
  // an endless loop (an InputError names the line it was at). The longest program we emit, a
  // year of hourly sphere cycles (8760 cycles x 222 blocks), executes 1.94 million blocks; the
  // bound is ten times that (a year of 6-minute cycles, or ten years of hourly ones). An
  // endless loop with moves reaches it in seconds on a 2-core machine (docs/reliability.md:
  // measured, for check and simulate), where 1e8 took about 27 s.
  static constexpr long kMaxBlocks = 20'000'000;

  // Runs from the first line to M2/M30 (or the end of the text).
  InterpreterResult run(MachineInterface& machine, long max_blocks = kMaxBlocks, ProbeBranching* branching = nullptr);

  // Parameters after a run (published when it ends or stops), for tests: numbered and named
  // (lower case).
  double parameter(int number) const;
  double namedParameter(const std::string& name) const;

  struct Line {
    int number = 0;       // 1-based line in the file
    std::string code;     // upper case, comments and blanks removed (LinuxCNC named
                          // parameters keep their lower-case names)
    std::string message;  // the (LOG,...)-style comment's text, original case
    std::string comment;  // the last comment on the line (Fanuc alarm texts)
  };

 private:
  ProgramDialect dialect_;
  std::string file_;
  std::vector<Line> lines_;
  std::map<int, double> params_;
  std::map<std::string, double> named_;
  friend class Execution;
};

}  // namespace probeloop::gcode
