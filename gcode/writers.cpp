#include <cmath>
#include <initializer_list>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "core/csv.hpp"
#include "gcode/probe_program.hpp"
#include "gcode/program.hpp"

namespace probeloop::gcode {
namespace {

// A number a program would print as "nan" or "inf": never written.
double finite(double v) {
  if (!std::isfinite(v)) throw std::invalid_argument("a non-finite number (" + formatNumber(v) + ") in a program");
  return v;
}
// 4 decimals = 0.1 um, finer than any axis resolution; "-0.0000" never appears.
std::string n4(double v) { return formatNumber(finite(v), 4); }
std::string n3(double v) { return formatNumber(finite(v), 3); }
// A constant inside a Fanuc expression: "#5061-[-139.0000]", never "#5061--139.0000".
std::string macroConst(double v) { return v < 0 ? "[" + n4(v) + "]" : n4(v); }

template <class... Ts>
struct Overloaded : Ts... { using Ts::operator()...; };
template <class... Ts>
Overloaded(Ts...) -> Overloaded<Ts...>;

std::string axes(const Rapid& r) {
  std::string s;
  if (r.x) s += " X" + n4(*r.x);
  if (r.y) s += " Y" + n4(*r.y);
  if (r.z) s += " Z" + n4(*r.z);
  return s;
}

std::string xyz(double x, double y, double z) {
  return " X" + n4(x) + " Y" + n4(y) + " Z" + n4(z);
}

// Comments cannot nest parentheses in either dialect.
std::string clean(std::string s) {
  for (auto& c : s) {
    if (c == '(') c = '[';
    if (c == ')') c = ']';
  }
  return s;
}

std::string offsetAxes(bool a, bool b, bool c = true) {
  return std::string(" X0 Y0 Z0") + (a ? " A0" : "") + (b ? " B0" : "") + (c ? " C0" : "");
}

const char* wcs(int n) {
  static const char* names[] = {"G54", "G55", "G56", "G57", "G58", "G59"};
  return names[n - 1];
}

// Lines both dialects write identically.
std::string rapidLine(const Rapid& r) { return "G0" + axes(r) + "\n"; }
std::string rotateLine(const RotateC& r) { return "G0 C" + n3(r.c_deg) + "\n"; }
std::string rotateBLine(const RotateB& r) { return "G0 B" + n3(r.b_deg) + "\n"; }
std::string rotateALine(const RotateA& r) { return "G0 A" + n3(r.a_deg) + "\n"; }
// Spindle speeds are whole rpm on every control.
std::string spindleLine(const Spindle& s) {
  return s.rpm > 0 ? "S" + formatNumber(s.rpm, 0) + " M3\n" : std::string("M5\n");
}
std::string coolantLine(const Coolant& c) { return c.on ? "M8\n" : "M9\n"; }
std::string feedLine(const Feed& f) { return "G1" + axes(Rapid{f.x, f.y, f.z}) + " F" + n3(f.feed) + "\n"; }
// Incremental for this line only (n3 always writes the decimal point a Fanuc C word needs).
std::string turnLines(const TurnC& t) {
  return "G91 G1 C" + n3(t.delta_deg) + " F" + n3(t.feed_deg_per_min) + "\nG90\n";
}
std::string toolChangeLines(const ToolChange& t) {
  return "T" + std::to_string(t.tool) + " M6\n" +
         (t.apply_length_offset ? "G43 H" + std::to_string(t.tool) : std::string("G49")) + "\n";
}

// LinuxCNC: O-word labels must be unique per program; count them.
struct LinuxWriter {
  std::ostringstream out;
  int label = 200;
  std::string check_hint = "check the artifact position";  // what the ABORT message tells the operator
  std::vector<std::pair<int, std::string>> loops;  // open o-while: label, parameter name
  bool log_clock = false;  // each point's clock from analog input 1 (probe_program.hpp)

  void op(const Op& o) {
    std::visit(Overloaded{
        [&](const Comment& c) { out << "(" << clean(c.text) << ")\n"; },
        [&](const Rapid& r) { out << rapidLine(r); },
        [&](const RapidMachineZ& r) { out << "G53 G0 Z" << n4(r.z_mm) << "\n"; },
        [&](const RotateC& r) { out << rotateLine(r); },
        [&](const ToolChange& t) { out << toolChangeLines(t); },
        [&](const ProtectedMove& m) {
          // G38.3: stop on contact without error; contact here is a collision -> abort.
          const int l = label++;
          out << "G38.3" << xyz(m.x, m.y, m.z) << " F" << n3(m.feed_mm_per_min) << "\n";
          out << "o" << l << " if [#5070 EQ 1]\n";
          out << "  (ABORT,probeloop: unexpected contact during a protected move - " << check_hint << ")\n";
          out << "o" << l << " endif\n";
        },
        [&](const ProbeMove& m) {
          // G38.2 raises "probe move finished without contact" itself: the program stops
          // and no point is logged.
          out << "G38.2" << xyz(m.x, m.y, m.z) << " F" << n3(m.feed_mm_per_min) << "\n";
          if (log_clock) out << "M66 E" << kLiveClockLinuxCncInput << " L0\n";  // the clock, probe_program.hpp
          out << "(LOG,PT #<_pl_cycle> " << m.position << " " << m.point
              << " #5061 #5062 #5063" << (log_clock ? " #5399" : "") << ")\n";
        },
        [&](const Dwell& d) { out << "G4 P" << n3(d.seconds) << "\n"; },
        [&](const RotateB& r) { out << rotateBLine(r); },
        [&](const RotateA& r) { out << rotateALine(r); },
        [&](const Spindle& sp) { out << spindleLine(sp); },
        [&](const Coolant& c) { out << coolantLine(c); },
        [&](const Feed& f) { out << feedLine(f); },
        [&](const TurnC& t) { out << turnLines(t); },
        [&](const LoopBegin& l) {
          const int lb = label++;
          loops.emplace_back(lb, l.name);
          out << "#<" << l.name << "> = 1\n";
          out << "o" << lb << " while [#<" << l.name << "> LE " << l.count << "]\n";
        },
        [&](const LoopEnd&) {
          if (loops.empty()) throw std::invalid_argument("a loop end without a loop begin");
          const auto [lb, name] = loops.back();
          loops.pop_back();
          out << "#<" << name << "> = [#<" << name << "> + 1]\n";
          out << "o" << lb << " endwhile\n";
        },
    }, o);
  }
};

struct FanucWriter {
  std::ostringstream out;
  int depth = 0;  // open WHILE ... DO levels

  void op(const Op& o) {
    std::visit(Overloaded{
        [&](const Comment& c) { out << "(" << upper(clean(c.text)) << ")\n"; },
        [&](const Rapid& r) { out << rapidLine(r); },
        [&](const RapidMachineZ& r) { out << "G0 G53 Z" << n4(r.z_mm) << "\n"; },
        [&](const RotateC& r) { out << rotateLine(r); },
        [&](const ToolChange& t) { out << toolChangeLines(t); },
        [&](const ProtectedMove& m) {
          // G31 completes the move when nothing triggers; a skip position short of the
          // target means contact, i.e. a collision -> alarm.
          out << "G31" << xyz(m.x, m.y, m.z) << " F" << n3(m.feed_mm_per_min) << "\n";
          out << "IF [[ABS[#5061-" << macroConst(m.x) << "]+ABS[#5062-" << macroConst(m.y)
              << "]+ABS[#5063-" << macroConst(m.z) << "]] GT 0.0005] THEN #3000=2 (UNEXPECTED CONTACT)\n";
        },
        [&](const ProbeMove& m) {
          // Fanuc G31 completes the move without a trigger: a skip position at the target
          // means no contact -> alarm instead of logging a wrong point.
          out << "G31" << xyz(m.x, m.y, m.z) << " F" << n3(m.feed_mm_per_min) << "\n";
          out << "IF [[ABS[#5061-" << macroConst(m.x) << "]+ABS[#5062-" << macroConst(m.y)
              << "]+ABS[#5063-" << macroConst(m.z) << "]] LT 0.0005] THEN #3000=1 (PROBE DID NOT TRIGGER)\n";
          // The controller's clock with every point (#3011 date, #3012 time, 1 s): the log
          // carries its own times (gcode/probe_log.hpp).
          out << "DPRNT[PT*#100[40]*" << m.position << "*" << m.point
              << "*#5061[44]*#5062[44]*#5063[44]*#3011[80]*#3012[60]]\n";
        },
        [&](const Dwell& d) { out << "G4 X" << n3(d.seconds) << "\n"; },
        [&](const RotateB& r) { out << rotateBLine(r); },
        [&](const RotateA& r) { out << rotateALine(r); },
        [&](const Spindle& sp) { out << spindleLine(sp); },
        [&](const Coolant& c) { out << coolantLine(c); },
        [&](const Feed& f) { out << feedLine(f); },
        [&](const TurnC& t) { out << turnLines(t); },
        [&](const LoopBegin& l) {
          // Macro B nests WHILE ... DO1..DO3; #101.. count the loops (#100 is the log's cycle).
          if (++depth > 3) throw std::invalid_argument("loops nested deeper than 3 (Fanuc WHILE ... DO1..DO3)");
          const std::string v = "#" + std::to_string(100 + depth);
          out << v << "=1\n";
          out << "WHILE [" << v << " LE " << l.count << "] DO" << depth << "\n";
        },
        [&](const LoopEnd&) {
          if (depth == 0) throw std::invalid_argument("a loop end without a loop begin");
          const std::string v = "#" + std::to_string(100 + depth);
          out << v << "=" << v << "+1\n";
          out << "END" << depth << "\n";
          --depth;
        },
    }, o);
  }
  static std::string upper(std::string s) {
    for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return s;
  }
};

// A program that probes must open its log; loops must close; every number is finite.
void checkProgram(const Program& p) {
  int depth = 0;
  for (std::size_t i = 0; i < p.ops.size(); ++i) {
    const Op& op = p.ops[i];
    if (!allFinite(op))
      throw std::invalid_argument(p.title + ": op " + std::to_string(i + 1) + " holds a number that is not finite");
    if (std::holds_alternative<LoopBegin>(op)) ++depth;
    if (std::holds_alternative<LoopEnd>(op) && --depth < 0)
      throw std::invalid_argument(p.title + ": a loop end without a loop begin");
    if (std::holds_alternative<ProbeMove>(op) && p.log_file.empty())
      throw std::invalid_argument(p.title + ": a probe move in a program that opens no log");
  }
  if (depth != 0) throw std::invalid_argument(p.title + ": a loop is never closed");
}

}  // namespace

bool allFinite(const Op& op) {
  auto f = [](std::initializer_list<double> v) {
    for (double x : v)
      if (!std::isfinite(x)) return false;
    return true;
  };
  auto o = [](const std::optional<double>& v) { return !v || std::isfinite(*v); };
  return std::visit(Overloaded{
                        [&](const Comment&) { return true; },
                        [&](const Rapid& r) { return o(r.x) && o(r.y) && o(r.z); },
                        [&](const RapidMachineZ& r) { return f({r.z_mm}); },
                        [&](const RotateC& r) { return f({r.c_deg}); },
                        [&](const RotateB& r) { return f({r.b_deg}); },
                        [&](const RotateA& r) { return f({r.a_deg}); },
                        [&](const ToolChange&) { return true; },
                        [&](const ProtectedMove& m) { return f({m.x, m.y, m.z, m.feed_mm_per_min}); },
                        [&](const ProbeMove& m) { return f({m.x, m.y, m.z, m.feed_mm_per_min}); },
                        [&](const Dwell& d) { return f({d.seconds}); },
                        [&](const Spindle& s) { return f({s.rpm}); },
                        [&](const Coolant&) { return true; },
                        [&](const Feed& x) { return o(x.x) && o(x.y) && o(x.z) && f({x.feed}); },
                        [&](const TurnC& t) { return f({t.delta_deg, t.feed_deg_per_min}); },
                        [&](const LoopBegin&) { return true; },
                        [&](const LoopEnd&) { return true; },
                    },
                    op);
}

std::string writeLinuxCnc(const Program& p) {
  checkProgram(p);
  LinuxWriter w;
  w.label = 100;
  w.check_hint = "check the part position and the clearances";
  auto& o = w.out;
  o << "(" << clean(p.title) << ")\n";
  for (const auto& h : p.header) o << "(" << clean(h) << ")\n";
  o << "G21 G90 G17 G40 G49 G80 G94\n";
  o << "G10 L2 P" << p.work_offset << offsetAxes(p.has_a_axis, p.has_b_axis, p.has_c_axis) << "\n";
  o << wcs(p.work_offset) << "\n";
  if (!p.log_file.empty()) {
    o << "(LOGOPEN," << p.log_file << ")\n";
    o << "#<_pl_cycle> = 1\n";
  }
  for (const auto& op : p.ops) w.op(op);
  if (!p.log_file.empty()) o << "(LOGCLOSE)\n";
  o << "M2\n";
  return o.str();
}

std::string writeFanucMacroB(const Program& p) {
  checkProgram(p);
  FanucWriter w;
  auto& o = w.out;
  o << "%\n";
  o << "O" << p.number << " (" << FanucWriter::upper(clean(p.title)) << ")\n";
  for (const auto& h : p.header) o << "(" << FanucWriter::upper(clean(h)) << ")\n";
  o << "G21 G90 G17 G40 G49 G80 G94\n";
  o << "G10 L2 P" << p.work_offset << offsetAxes(p.has_a_axis, p.has_b_axis, p.has_c_axis) << "\n";
  o << wcs(p.work_offset) << "\n";
  if (!p.log_file.empty()) {
    o << "POPEN\n";
    o << "DPRNT[START*#3011[80]*#3012[60]]\n";  // the clock when the program starts
    o << "#100=1\n";
  }
  for (const auto& op : p.ops) w.op(op);
  if (!p.log_file.empty()) o << "PCLOS\n";
  o << "M30\n";
  o << "%\n";
  return o.str();
}

namespace {

// The live interval's header lines (probe_program.hpp): where the wait comes from, what the
// value means, and what happens when nothing writes it.
std::vector<std::string> liveIntervalHeader(const ProbeProgram& p, const std::string& source) {
  if (!p.live_interval) return {};
  const std::string chunk = formatNumber(kLiveIntervalChunkS);
  return {
      "measurement interval: live, from " + source + ", read after every cycle but the last",
      // Plain words: a Fanuc comment is safest without characters such as > or '.
      "the value is the seconds still to wait: while it is above 0 the program dwells at most " + chunk +
          " s and reads it again",
      "nothing writing it (value 0): the cycles run back to back; the schedule in plan.json is nominal (gap " +
          formatNumber(p.gap_s) + " s)",
  };
}

// The wait between two cycles, inside the "not the last cycle" branch.
void linuxCncWait(std::ostream& o, const ProbeProgram& p) {
  if (!p.live_interval) {
    o << "G4 P" << n3(p.gap_s) << "\n";
    return;
  }
  // M66 L0 reads at once; LinuxCNC runs it only after the queued motion (the dwell) is done,
  // so each read is the value at the end of the previous chunk.
  const std::string read = "M66 E" + std::to_string(kLiveIntervalLinuxCncInput) + " L0\n#<_pl_wait> = #5399\n";
  const std::string chunk = n3(kLiveIntervalChunkS);
  o << read;
  o << "o102 while [#<_pl_wait> GT 0]\n";
  o << "o103 if [#<_pl_wait> GT " << chunk << "]\n";
  o << "#<_pl_wait> = " << chunk << "\n";
  o << "o103 endif\n";
  o << "G4 P#<_pl_wait>\n";
  o << read;
  o << "o102 endwhile\n";
}

// The same on a Fanuc control, inside WHILE ... DO1 (#100 the cycle, #101 the value read).
void fanucWait(std::ostream& o, const ProbeProgram& p) {
  if (!p.live_interval) {
    o << "G4 X" << n3(p.gap_s) << "\n";
    return;
  }
  const std::string read = "#101=#" + std::to_string(kLiveIntervalFanucVariable) + "\n";
  const std::string chunk = n3(kLiveIntervalChunkS);
  o << read;
  o << "WHILE [#101 GT 0] DO2\n";
  o << "IF [#101 GT " << chunk << "] THEN #101=" << chunk << "\n";
  o << "G4 X#101\n";
  o << read;
  o << "END2\n";
}

}  // namespace

std::string writeLinuxCnc(const ProbeProgram& p) {
  LinuxWriter w;
  auto& o = w.out;
  o << "(" << clean(p.title) << ")\n";
  for (const auto& h : p.header) o << "(" << clean(h) << ")\n";
  for (const auto& h : liveIntervalHeader(p, "HAL analog input " + std::to_string(kLiveIntervalLinuxCncInput) +
                                                 " (M66 E" + std::to_string(kLiveIntervalLinuxCncInput) +
                                                 " L0 -> #5399)"))
    o << "(" << clean(h) << ")\n";
  if (p.live_interval) {
    w.log_clock = true;
    o << "(point times: HAL analog input " << kLiveClockLinuxCncInput << " [M66 E" << kLiveClockLinuxCncInput
      << " L0 -> #5399] after each probing move, logged as the 8th field: the inputs logger's clock in s)\n";
  }
  o << "G21 G90 G17 G40 G49 G80 G94\n";
  o << "G10 L2 P" << p.work_offset << offsetAxes(p.has_a_axis, p.has_b_axis) << "\n";
  o << wcs(p.work_offset) << "\n";
  o << "(LOGOPEN," << p.log_file << ")\n";
  for (const auto& op : p.before_cycles) w.op(op);
  o << "#<_pl_cycle> = 1\n";
  o << "o100 while [#<_pl_cycle> LE " << p.cycles << "]\n";
  for (const auto& op : p.cycle_body) w.op(op);
  o << "o101 if [#<_pl_cycle> LT " << p.cycles << "]\n";
  linuxCncWait(o, p);
  o << "o101 endif\n";
  o << "#<_pl_cycle> = [#<_pl_cycle> + 1]\n";
  o << "o100 endwhile\n";
  for (const auto& op : p.after_cycles) w.op(op);
  o << "(LOGCLOSE)\n";
  o << "M2\n";
  return o.str();
}

std::string writeFanucMacroB(const ProbeProgram& p, int program_number) {
  FanucWriter w;
  auto& o = w.out;
  o << "%\n";
  o << "O" << program_number << " (" << FanucWriter::upper(clean(p.title)) << ")\n";
  for (const auto& h : p.header) o << "(" << FanucWriter::upper(clean(h)) << ")\n";
  for (const auto& h : liveIntervalHeader(p, "common variable #" + std::to_string(kLiveIntervalFanucVariable) +
                                                 " (written by FOCAS cnc_wrmacro)"))
    o << "(" << FanucWriter::upper(clean(h)) << ")\n";
  o << "G21 G90 G17 G40 G49 G80 G94\n";
  o << "G10 L2 P" << p.work_offset << offsetAxes(p.has_a_axis, p.has_b_axis) << "\n";
  o << wcs(p.work_offset) << "\n";
  o << "POPEN\n";
  o << "DPRNT[START*#3011[80]*#3012[60]]\n";  // the clock when the program starts
  for (const auto& op : p.before_cycles) w.op(op);
  o << "#100=1\n";
  o << "WHILE [#100 LE " << p.cycles << "] DO1\n";
  for (const auto& op : p.cycle_body) w.op(op);
  o << "IF [#100 GE " << p.cycles << "] GOTO 10\n";
  fanucWait(o, p);
  o << "N10 #100=#100+1\n";
  o << "END1\n";
  for (const auto& op : p.after_cycles) w.op(op);
  o << "PCLOS\n";
  o << "M30\n";
  o << "%\n";
  return o.str();
}

}  // namespace probeloop::gcode
