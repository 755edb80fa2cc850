// Internal to gcode/: one run of a program through the interpreter (interpreter.hpp is the
// public contract). Interpreter::run builds an Execution over the program's lines and the
// machine; the Execution holds the cursor, the modal state, the parameters and the control
// flow, and a probe branch (ProbeBranching) is a copy of it. Nothing outside gcode/ includes
// this header.
//
// Its member functions are defined by job, in the order a block is read and done:
// - interpreter.cpp: reading the text into lines, the run (runFrom: the cursor, the block
//   bound, errors placed at their line) and the dispatch of each line (executeLine);
// - interpreter_expressions.cpp: numbers, parameters (#i, #<name>, Fanuc's clock #3011/#3012
//   and its common variables #500..#999 as written from outside),
//   functions and operators, a word's value, and parameter assignment (#i=..., alarms #3000);
// - interpreter_control.cpp: the control structures resolved before the run (LinuxCNC
//   o-words, Fanuc labels and WHILE/DO/END) and taken during it (conditions, GOTO, IF THEN),
//   the Fanuc log words POPEN/PCLOS/DPRNT among them;
// - interpreter_logs.cpp: what the controller writes: Fanuc DPRNT formats, LinuxCNC active
//   comments (LOGOPEN, LOG, ABORT, ...) and their parameter substitution;
// - interpreter_blocks.cpp: an ordinary block: its words read and checked, the modal state it
//   sets (G, M, F, S, T, H, G10 offsets, G4 dwell, M66 E<n> L0), every word made to act;
// - interpreter_motion.cpp: motion: targets through the work offset and tool length, rapid,
//   feed, arcs as chords, probe moves and their results (#5061.., #5070) and branches.
#pragma once
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "gcode/interpreter.hpp"

namespace probeloop::gcode {

namespace detail {

inline constexpr double kPi = std::numbers::pi;

inline std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}
inline std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// A small non-negative integer written in the program (labels, loop numbers, parameter
// numbers); nullopt when it is not one.
inline std::optional<int> smallInt(const std::string& digits) {
  if (digits.empty() || digits.size() > 6) return std::nullopt;
  for (char c : digits)
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  return std::stoi(digits);
}

// An error raised by the program itself (alarm, ABORT, probe without contact): the
// controller stops there.
[[noreturn]] inline void stop(const std::string& file, int line, const std::string& what) {
  throw SafetyError(file + ":" + std::to_string(line) + ": " + what);
}

}  // namespace detail

using detail::kPi;
using detail::lower;
using detail::smallInt;
using detail::stop;
using detail::upper;

// One run of the program: cursor, modal state and control flow.
class Execution {
 public:
  Execution(Interpreter& in, MachineInterface& m, ProbeBranching* branching)
      : in_(in), m_(m), params_(in.params_), named_(in.named_), branching_(branching), pos_(m.start()) {}

  InterpreterResult run(long max_blocks) {
    buildJumps();
    max_blocks_ = max_blocks;
    return runFrom(0);
  }

  // The parameters as the run left them (for Interpreter::parameter).
  void publishParameters() const {
    in_.params_ = params_;
    in_.named_ = named_;
  }

 private:
  InterpreterResult runFrom(std::size_t start);

  Interpreter& in_;
  MachineInterface& m_;
  // Parameters of this run (a probe branch has its own copy): numbered and named.
  std::map<int, double> params_;
  std::map<std::string, double> named_;
  double parameter(int n) const {
    const auto it = params_.find(n);
    return it == params_.end() ? 0.0 : it->second;
  }
  ProbeBranching* branching_ = nullptr;
  long max_blocks_ = Interpreter::kMaxBlocks;
  long blocks_ = 0;       // blocks executed so far (a branch goes on counting)
  bool line_ends_ = false;  // M2/M30 on the line being executed
  std::size_t pc_ = 0;
  int line_ = 0;

  // Modal state.
  double motion_ = 0;  // 0, 1, 2, 3, 38.2, 38.3, 80 (none)
  bool absolute_ = true;
  double feed_ = 0;
  int wcs_ = 1;
  std::array<std::array<double, 6>, 7> offsets_{};  // [1..6] x y z a b c
  double tool_length_ = 0;
  int tool_in_spindle_ = 0, tool_selected_ = 0;
  double spindle_rpm_ = 0;
  int spindle_dir_ = 0;  // +1 M3, -1 M4, 0 stopped
  MachinePosition pos_;  // gauge line, machine coordinates
  bool log_open_ = false;
  bool seen_program_number_ = false;

  // Control flow.
  // Resolved once per run, before it starts; a probe branch shares them.
  struct Control {
    std::map<std::size_t, std::size_t> jump;       // line index -> matching end / next branch
    std::map<std::size_t, std::size_t> loop_back;  // end of loop -> its head
    std::map<int, std::size_t> labels;             // Fanuc N labels
    std::map<std::size_t, std::size_t> endif_of;   // elseif/else line -> its endif
  };
  std::shared_ptr<Control> control_;

  [[noreturn]] void fail(const std::string& m) const { throw InputError(in_.file_, line_, m); }


  // ---------------------------------------------------------------------------------
  // Expressions

  // The expression reader recurses per bracket, unary sign and '#' of an indirect parameter
  // (##1); without a bound, "[[[[..." of a few thousand levels exhausted the stack (found by
  // fuzz/gcode_linuxcnc_fuzz). LinuxCNC's lines are at most 256 characters; 100 levels is far
  // more than any program needs.
  static constexpr int kMaxNesting = 100;
  int nesting_ = 0;
  struct Nest {
    Nest(Execution& e, const std::string& line, std::size_t column) : e_(e) {
      if (++e_.nesting_ > kMaxNesting) {
        --e_.nesting_;  // a constructor that throws gets no destructor call
        e_.fail("expression nested more than " + std::to_string(kMaxNesting) + " levels deep (brackets, signs or #) at column " +
                std::to_string(column + 1) + " of '" + line.substr(0, 60) + (line.size() > 60 ? "...'" : "'"));
      }
    }
    ~Nest() { --e_.nesting_; }
    Nest(const Nest&) = delete;
    Nest& operator=(const Nest&) = delete;
    Execution& e_;
  };

  struct Cursor {
    const std::string& s;
    std::size_t i = 0;
    bool end() const { return i >= s.size(); }
    char peek() const { return end() ? '\0' : s[i]; }
    // Called for every operator and keyword tried at every position of every expression
    // evaluated: the first character decides most calls without a compare.
    bool take(std::string_view t) {
      if (i >= s.size() || s[i] != t.front()) return false;
      if (s.compare(i, t.size(), t) == 0) {
        i += t.size();
        return true;
      }
      return false;
    }
  };

  // Every value the program computes must be a finite number: an overflow (EXP[1000],
  // [1e300*1e300]) or what follows from one (inf - inf = NaN) stops the program here, as a
  // controller stops with a calculation-overflow alarm. A NaN let through would compare false
  // with every limit and a move to it could pass any check (issue 28).
  double finite(double v, const Cursor& c, const char* what) const;

  double number(Cursor& c);

  double readParam(Cursor& c);

  // A numbered parameter; Fanuc's #3011 (date YYYYMMDD) and #3012 (time HHMMSS) read the
  // controller's clock, its #500..#999 the machine's externalVariable when it has one.
  double paramValue(int n);

  int paramNumber(Cursor& c);

  double bracket(Cursor& c);

  double primary(Cursor& c);

  // A function's value, after its name.
  double function(const std::string& fn, Cursor& c);

  double power(Cursor& c);
  double product(Cursor& c);
  double sum(Cursor& c);
  double comparison(Cursor& c);
  double expression(Cursor& c);

  // A word's value: a number, a parameter, or a bracketed expression, with a sign.
  double wordValue(Cursor& c);

  // ---------------------------------------------------------------------------------
  // Control structures, resolved once before running.

  struct OWord {
    std::string label, keyword;
    std::size_t rest = 0;  // index in code after the keyword
  };
  std::optional<OWord> oword(const std::string& code) const;

  void buildJumps();

  // Returns true when the program ends.
  bool executeLine(const Interpreter::Line& line, std::size_t& next);

  void controlLinux(const OWord& o, const std::string& code, std::size_t& next);
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t branch_target_ = kNone;

  bool condition(Cursor& c);

  // Fanuc control words; true when the line was one.
  bool controlFanuc(const std::string& rest, std::size_t& next);

  std::size_t label(int n);

  // Fanuc DPRNT: letters as they are, '*' = space, #i[ab] = value with a integer and b
  // decimal digits (sign column first).
  std::string dprnt(const std::string& body);

  // LinuxCNC active comments.
  void activeComment(const std::string& body);

  // LinuxCNC substitutes #n and #<name> in LOG text with "%lf" and nothing else.
  std::string substitute(const std::string& text);
  static std::string fmtLf(double v);

  // #i=expr, #<name>=expr (LinuxCNC allows several on a line; values are read first).
  void assign(const std::string& stmt);
  static std::string alarmText(const std::string& comment);

  // ---------------------------------------------------------------------------------
  // Ordinary blocks

  struct Words {
    std::vector<double> g, m;
    std::map<char, double> v;
    std::set<char> used;
    bool has(char k) const { return v.count(k) > 0; }
    double take(char k) {
      used.insert(k);
      return v.at(k);
    }
  };

  bool block(const std::string& code);

  static bool isG(double g, double want) { return std::fabs(g - want) < 1e-6; }

  // A word that must be a whole number in a sane range (tool, offset, P of G10...).
  int wholeWord(Words& w, char k, int lo, int hi);
  static std::string formatG(double v);

  bool execute(Words& w);

  // LinuxCNC M66 E<n> L0: the analog input into #5399 (any other M66 form is refused).
  void analogRead(Words& w);

  // Every word on a line must have done something: one that did not is refused, so a
  // program the simulator misreads never runs silently.
  void finishWords(const Words& w);

  void move(Words& w, bool g53, bool g31);

  void requireFeed();

  // A probe move's outcome. With a ProbeBranching, the rest of the program is first offered
  // with another outcome, from a copy of this run's state (unless this outcome already stops
  // the program: then there is nothing to protect).
  void probed(const ProbeOutcome& r, ProbeMode mode);
  void applyProbe(const ProbeOutcome& r, ProbeMode mode);
  // A branch: this probe line finishes with `other`, then the program runs on from the next
  // line (nothing on a probe line acts after its move but an M2/M30 on it).
  InterpreterResult continueAfterProbe(const ProbeOutcome& other, ProbeMode mode);

  static std::string fmtG(double g);

  std::array<double, 6> activeOffset() const;

  MachinePosition target(Words& w, bool machine_coords);

  // After a probe move both dialects report the latched position in program coordinates.
  void setProbeResult(const ProbeOutcome& r);

  // G2/G3 in the XY plane as chords within 0.1 um of the arc.
  void arc(Words& w, const MachinePosition& to, bool clockwise);
};

}  // namespace probeloop::gcode
