#include "gcode/interpreter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <optional>
#include <tuple>

#include "core/error.hpp"
#include "gcode/probe_program.hpp"

namespace probeloop::gcode {
namespace {

// Records every call; probes touch a plane x = contact_x (moving in +X) when set.
struct Recorder : MachineInterface {
  double clock_s = 0;  // the controller's clock (#3011/#3012)
  double controllerClockS() const override { return clock_s; }
  std::vector<std::string> calls;
  std::vector<MachinePosition> targets;
  std::vector<std::string> log_lines;
  std::optional<double> contact_x;
  double path_mm = 0;
  MachinePosition at;
  void rapid(const MachinePosition& to) override { calls.push_back("G0"); targets.push_back(to); at = to; }
  void feed(const MachinePosition& to, double) override {
    calls.push_back("G1");
    path_mm += (to.xyz_mm - at.xyz_mm).norm();
    targets.push_back(to);
    at = to;
  }
  ProbeOutcome probe(const MachinePosition& to, double, ProbeMode mode) override {
    calls.push_back(mode == ProbeMode::ErrorWithoutContact ? "G38.2" : mode == ProbeMode::FlagContact ? "G38.3" : "G31");
    targets.push_back(to);
    ProbeOutcome o;
    if (contact_x && to.xyz_mm.x() >= *contact_x && at.xyz_mm.x() < *contact_x) {
      o.contact = true;
      o.stop = to;
      o.stop.xyz_mm.x() = *contact_x;
    } else {
      o.stop = to;
    }
    at = o.stop;
    return o;
  }
  void dwell(double s) override { calls.push_back("G4 " + std::to_string(s)); }
  void toolChange(int t) override { calls.push_back("M6 T" + std::to_string(t)); }
  double toolLength(int t) const override {
    if (t == 99) return 150;
    if (t == 0) return 0;
    throw InputError("", 0, "no tool " + std::to_string(t));
  }
  void spindle(double rpm) override { calls.push_back("S " + std::to_string(rpm)); }
  void coolant(bool on) override { calls.push_back(on ? "M8" : "M9"); }
  void openLog(const std::string& n) override { calls.push_back("open " + n); }
  void log(const std::string& l) override { log_lines.push_back(l); }
  void closeLog() override { calls.push_back("close"); }
};

TEST(Interpreter, ExpressionsFollowRs274Precedence) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "#1 = [1 + 2 * 3]\n#2 = [2 ** 3 ** 2]\n#3 = [7 MOD 3]\n#4 = [1 LT 2 AND 3 GT 4]\n"
                 "#5 = ATAN[1]/[1]\n#6 = [SQRT[16] + ABS[-2] + FIX[2.7] + FUP[2.1] + ROUND[2.5]]\n"
                 "#<_a> = [-#1 + COS[60]]\n#7 = #[2 + 1]\nM2\n");
  in.run(r);
  EXPECT_EQ(in.parameter(1), 7);
  EXPECT_EQ(in.parameter(2), 64);  // left to right: (2**3)**2
  EXPECT_EQ(in.parameter(3), 1);
  EXPECT_EQ(in.parameter(4), 0);
  EXPECT_NEAR(in.parameter(5), 45, 1e-12);
  EXPECT_EQ(in.parameter(6), 4 + 2 + 2 + 3 + 3);
  EXPECT_NEAR(in.namedParameter("_a"), -6.5, 1e-12);
  EXPECT_EQ(in.parameter(7), 1);
}

TEST(Interpreter, LogicalOperatorsReadBothSidesAndModFollowsLinuxCnc) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "#1 = [0 AND 1]\n#2 = [1 OR 0]\n#3 = [0 OR 0 OR 1]\n#4 = [7 MOD -3]\n#5 = [-7 MOD 3]\n"
                 "#6 = [FIX[-1.5] + FUP[-1.5]]\n#7 = ATAN[-1]/[-1]\nM2\n");
  in.run(r);
  EXPECT_EQ(in.parameter(1), 0);
  EXPECT_EQ(in.parameter(2), 1);
  EXPECT_EQ(in.parameter(3), 1);
  EXPECT_EQ(in.parameter(4), 1);  // fmod(7, -3) = 1
  EXPECT_EQ(in.parameter(5), 2);  // fmod(-7, 3) = -1, + |3|
  EXPECT_EQ(in.parameter(6), -2 + -1);  // LinuxCNC: round down, round up
  EXPECT_NEAR(in.parameter(7), -135, 1e-12);
  // Fanuc truncates toward / away from zero and answers ATAN in 0..360.
  Interpreter fa(ProgramDialect::FanucMacroB, "t.nc", "#1=FIX[-1.5]+FUP[-1.5]\n#2=ATAN[-1]/[-1]\nM30\n");
  fa.run(r);
  EXPECT_EQ(fa.parameter(1), -1 + -2);
  EXPECT_NEAR(fa.parameter(2), 225, 1e-12);
}

TEST(Interpreter, DwellBeforeMotionEndAfterItAndSpeedChangesAtOnce) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc", "S1000 M3\nS2000\nG4 P1.5 G0 X10\nG0 X20 M2\nG0 X30\n");
  in.run(r);
  ASSERT_EQ(r.calls.size(), 5u);
  EXPECT_EQ(r.calls[0], "S " + std::to_string(1000.0));
  EXPECT_EQ(r.calls[1], "S " + std::to_string(2000.0));  // S while turning: at once
  EXPECT_EQ(r.calls[2], "G4 " + std::to_string(1.5));
  EXPECT_EQ(r.calls[3], "G0");
  EXPECT_EQ(r.calls[4], "G0");  // the move on the M2 line runs, the line after it does not
  EXPECT_EQ(r.targets.back().xyz_mm.x(), 20);
}

TEST(Interpreter, LinuxCncLoopsAndBranches) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "#<n> = 0\n#<sum> = 0\no1 while [#<n> LT 5]\n"
                 "  o2 if [#<n> EQ 1]\n    #<sum> = [#<sum> + 10]\n"
                 "  o2 elseif [#<n> EQ 2]\n    #<sum> = [#<sum> + 100]\n"
                 "  o2 else\n    #<sum> = [#<sum> + 1]\n  o2 endif\n"
                 "  #<n> = [#<n> + 1]\no1 endwhile\nM2\n");
  const auto res = in.run(r);
  EXPECT_TRUE(res.ended);
  EXPECT_EQ(in.namedParameter("sum"), 10 + 100 + 3);
}

TEST(Interpreter, RunsTheEmittedLinuxCncProbeBlocksAndLogsLikeLinuxCnc) {
  ProbeProgram p;
  p.title = "t";
  p.log_file = "probe.log";
  p.cycles = 2;
  p.gap_s = 300;
  p.cycle_body = {ToolChange{99, true}, Rapid{10.0, 0.0, 20.0},
                  ProtectedMove{0, 0, 20, 1000}, ProbeMove{30, 0, 20, 200, 1, 1}, ToolChange{0, false}};
  Recorder r;
  r.contact_x = 12.5;  // the protected move (x 10 -> 0) moves away from it: no contact
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc", writeLinuxCnc(p));
  in.run(r);
  ASSERT_EQ(r.log_lines.size(), 2u);
  // LinuxCNC substitutes parameters with %lf (checked against rs274's own LOG output).
  EXPECT_EQ(r.log_lines[0], "PT 1.000000 1 1 12.500000 0.000000 20.000000");
  EXPECT_EQ(r.log_lines[1], "PT 2.000000 1 1 12.500000 0.000000 20.000000");
  // Targets are gauge-line machine coordinates: the probe's 150 mm length is added.
  EXPECT_DOUBLE_EQ(r.targets[0].xyz_mm.z(), 170.0);
  int dwells = 0;
  for (const auto& c : r.calls) dwells += c.rfind("G4", 0) == 0;
  EXPECT_EQ(dwells, 1);  // only between the cycles
}

TEST(Interpreter, FanucProgramWithSkipAlarmsAndDprnt) {
  ProbeProgram p;
  p.title = "t";
  p.cycles = 3;
  p.gap_s = 60;
  p.cycle_body = {ToolChange{99, true}, Rapid{10.0, 0.0, 20.0}, ProbeMove{30, 0, 20, 200, 2, 4}};
  Recorder r;
  r.contact_x = 12.5;
  r.clock_s = 3 * 86400.0 + 7 * 3600 + 15 * 60 + 30.9;  // 2026-01-04 07:15:30.9
  Interpreter in(ProgramDialect::FanucMacroB, "t.nc", writeFanucMacroB(p));
  in.run(r);
  ASSERT_EQ(r.log_lines.size(), 6u);  // % + START + 3 points + %
  EXPECT_EQ(r.log_lines.front(), "%");
  // '*' prints a space, #i[ab] a sign column, a integer and b decimal digits; #3011 the date
  // YYYYMMDD and #3012 the time HHMMSS (whole seconds) of the controller's clock.
  EXPECT_EQ(r.log_lines[1], "START  20260104   71530");
  EXPECT_EQ(r.log_lines[2], "PT     1 2 4    12.5000     0.0000    20.0000  20260104   71530");
  EXPECT_EQ(r.log_lines[4], "PT     3 2 4    12.5000     0.0000    20.0000  20260104   71530");

  // Without contact the program's own check raises alarm #3000=1 at its line.
  Recorder none;
  Interpreter in2(ProgramDialect::FanucMacroB, "t.nc", writeFanucMacroB(p));
  try {
    in2.run(none);
    FAIL() << "expected the alarm";
  } catch (const SafetyError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("t.nc:"), std::string::npos) << w;
    EXPECT_NE(w.find("#3000=1"), std::string::npos) << w;
    EXPECT_NE(w.find("PROBE DID NOT TRIGGER"), std::string::npos) << w;
  }
}

TEST(Interpreter, G382WithoutContactStopsTheProgram) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc", "G21 G90\nG0 X0 Y0 Z0\nG38.2 X5 F100\nM2\n");
  try {
    in.run(r);
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("t.ngc:3: G38.2 probe move finished without contact"), std::string::npos)
        << e.what();
  }
}

TEST(Interpreter, ArcsAreFollowedWithinATenthOfAMicrometre) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc", "G0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F500\nG2 X10 Y0 R10\nM2\n");
  in.run(r);
  // Quarter circle of radius 10 twice: chords are shorter than the arc by < 1e-4 relative.
  EXPECT_NEAR(r.path_mm, 2 * 10 * std::numbers::pi / 2, 2e-3);
  EXPECT_LT(r.path_mm, 2 * 10 * std::numbers::pi / 2);
  for (std::size_t k = 1; k < r.targets.size(); ++k)
    EXPECT_NEAR(r.targets[k].xyz_mm.head<2>().norm(), 10.0, 1e-9);
  EXPECT_NEAR(r.targets.back().xyz_mm.x(), 10.0, 1e-12);
}

TEST(Interpreter, WorkOffsetsToolLengthAndMachineCoordinates) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "G10 L2 P2 X100 Y-50 Z5 C0\nG55\nT99 M6\nG43 H99\nG0 X1 Y2 Z3\nG91 G0 X1\nG90\nG53 G0 Z400\nM2\n");
  in.run(r);
  ASSERT_EQ(r.targets.size(), 3u);
  EXPECT_EQ(r.targets[0].xyz_mm, Eigen::Vector3d(101, -48, 158));
  EXPECT_EQ(r.targets[1].xyz_mm, Eigen::Vector3d(102, -48, 158));
  EXPECT_EQ(r.targets[2].xyz_mm, Eigen::Vector3d(102, -48, 400));
}

// The A axis (issue 33): its work offset, absolute and incremental moves, and the probed
// position in LinuxCNC's numbering (#5064 A, #5065 B, #5066 C).
TEST(Interpreter, TheAAxisMovesWithItsOffsetAndItsProbedPosition) {
  Recorder r;
  r.contact_x = 5;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "G10 L2 P1 A2 B0 C10\nG54\nG0 A-30\nG91 G0 A5\nG90\nG0 B7 C20\nG38.2 X6 F100\nM2\n");
  in.run(r);
  ASSERT_EQ(r.targets.size(), 4u);
  EXPECT_EQ(r.targets[0].a_deg, -28);  // -30 + the offset's 2
  EXPECT_EQ(r.targets[1].a_deg, -23);  // incremental: no offset again
  EXPECT_EQ(r.targets[2].a_deg, -23);
  EXPECT_EQ(r.targets[2].b_deg, 7);
  EXPECT_EQ(r.targets[2].c_deg, 30);
  EXPECT_EQ(in.parameter(5064), -25);
  EXPECT_EQ(in.parameter(5065), 7);
  EXPECT_EQ(in.parameter(5066), 20);
}

// Bad input: every refusal names the file and line and what is not modelled.
void expectInputError(ProgramDialect d, const std::string& text, const std::string& want) {
  Recorder r;
  try {
    Interpreter in(d, "bad.ngc", text);
    in.run(r);
    FAIL() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(Interpreter, RefusesWhatItDoesNotModelWithTheLine) {
  expectInputError(ProgramDialect::LinuxCnc, "G0 X0\nG0 Q5\n", "bad.ngc:2: word 'Q' is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "G0 X0\nG81 X1 Z-1 R1\n", "bad.ngc:2: G81 is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "G20\n", "bad.ngc:1: G20 (inch)");
  expectInputError(ProgramDialect::LinuxCnc, "M7\n", "bad.ngc:1: M7 is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "o10 sub\no10 endsub\n", "bad.ngc:1: o-word 'sub' is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "o1 while [1]\nG0 X0\n", "bad.ngc:1: this block is never closed");
  expectInputError(ProgramDialect::LinuxCnc, "#1 = [1 +* 2]\n", "bad.ngc:1:");
  expectInputError(ProgramDialect::LinuxCnc, "G1 X5\n", "bad.ngc:1: a feed move without a feed rate");
  expectInputError(ProgramDialect::LinuxCnc, "#1 = [#<nope> + 1]\n", "#<nope> is read before it is set");
  expectInputError(ProgramDialect::LinuxCnc, "G0 X1 K5\n", "bad.ngc:1: word 'K' is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "G0 X1 H5\n", "bad.ngc:1: word 'H5' has no effect on this line");
  expectInputError(ProgramDialect::LinuxCnc, "G1 X1 I2 F100\n", "bad.ngc:1: word 'I2' has no effect");
  expectInputError(ProgramDialect::LinuxCnc, "#1 = [-8 ** 0.5]\n", "bad.ngc:1: a negative number to a non-integer power");
  expectInputError(ProgramDialect::LinuxCnc, "T1.5 M6\n", "bad.ngc:1: T1.5: expected a whole number");
  expectInputError(ProgramDialect::FanucMacroB, "G0 X10\n", "bad.ngc:1: 'X10' has no decimal point");
  expectInputError(ProgramDialect::FanucMacroB, "G0 A30\n", "bad.ngc:1: 'A30' has no decimal point");
  expectInputError(ProgramDialect::FanucMacroB, "WHILE [1 LT 2] DO\nEND1\n", "bad.ngc:1: WHILE [..] DOm needs m");
  expectInputError(ProgramDialect::FanucMacroB, "N12345678 G0 X1.\n", "bad.ngc:1: label N12345678 is not a number");
  expectInputError(ProgramDialect::LinuxCnc, "T5 M6\nG43\n", "bad.ngc:2: no tool 5");
  expectInputError(ProgramDialect::FanucMacroB, "M98 P1000\n", "bad.ngc:1: subprogram calls");
  expectInputError(ProgramDialect::FanucMacroB, "G38.2 X1. F100\n", "bad.ngc:1: G38.2 is not modelled");
  expectInputError(ProgramDialect::FanucMacroB, "GOTO 5\n", "bad.ngc:1: GOTO 5: no block N5");
}

// Numbers read exactly as strtod reads them: "5." and ".5", a subnormal, a value below the
// smallest double (0, as strtod has it), 600 significant digits; one above the largest is an
// error with the line.
TEST(Interpreter, NumbersReadAsStrtodReadsThem) {
  Recorder r;
  const std::string tiny = "0." + std::string(400, '0') + "1";
  const std::string subnormal = "0." + std::string(309, '0') + "1";  // 1e-310
  const std::string long_digits = "1." + std::string(300, '3') + std::string(300, '7');
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc",
                 "#1 = 5.\n#2 = .5\n#3 = " + tiny + "\n#4 = " + subnormal + "\n#5 = " + long_digits +
                     "\n#6 = 000012.250\nM2\n");
  in.run(r);
  EXPECT_EQ(in.parameter(1), 5.0);
  EXPECT_EQ(in.parameter(2), 0.5);
  EXPECT_EQ(in.parameter(3), 0.0);
  EXPECT_EQ(in.parameter(4), std::strtod(subnormal.c_str(), nullptr));
  EXPECT_EQ(in.parameter(5), std::strtod(long_digits.c_str(), nullptr));
  EXPECT_EQ(in.parameter(6), 12.25);
  expectInputError(ProgramDialect::LinuxCnc, "#1 = " + std::string(400, '9') + "\n", "bad.ngc:1: '999");
}

// Found by fuzz/gcode_linuxcnc_fuzz: thousands of nested brackets exhausted the stack.
TEST(Interpreter, DeepNestingIsRefusedNotAStackOverflow) {
  const std::string deep = "#1 = " + std::string(20000, '[') + "1" + std::string(20000, ']') + "\n";
  expectInputError(ProgramDialect::LinuxCnc, "G0 X0\n" + deep, "bad.ngc:2: expression nested more than 100 levels deep");
  expectInputError(ProgramDialect::FanucMacroB, "#1=" + std::string(20000, '-') + "1\n", "bad.ngc:1: expression nested");
  expectInputError(ProgramDialect::LinuxCnc, "#1 = " + std::string(20000, '#') + "1\n", "bad.ngc:1: expression nested");
  // Ninety levels, more than any program needs, still read.
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "ok.ngc", "#1 = " + std::string(90, '[') + "2" + std::string(90, ']') + "\nM2\n");
  in.run(r);
  EXPECT_EQ(in.parameter(1), 2.0);
}

// Issue 28: a value that is not a finite number never reaches the machine. Every shape a
// hostile-input suite found (an overflow to infinity, inf - inf = NaN, a product past the
// largest double, an offset that overflows the target) stops at its own line, naming what
// overflowed, with no move made.
TEST(Interpreter, NonFiniteValuesStopTheProgramAtTheirLine) {
  const std::string big = "1" + std::string(308, '0');  // 1e308: finite, the largest decade
  const std::string tan90 = "TAN[90.]";
  std::string tans = tan90;
  for (int i = 0; i < 20; ++i) tans += "*" + tan90;  // 1.6e16 ** 21: past the largest double
  struct Case {
    ProgramDialect d;
    std::string program, want;
  };
  const std::vector<Case> cases{
      {ProgramDialect::LinuxCnc, "G0 X0\n#1 = [EXP[1000]]\n#2 = [#1 - #1]\nG0 Z#2\n", "bad.ngc:2: EXP in '#1=[EXP[1000]]' gives an infinite value"},
      {ProgramDialect::LinuxCnc, "G0 X[" + big + " * 10]\n", "bad.ngc:1: a product in"},
      {ProgramDialect::LinuxCnc, "#1 = [" + big + " + " + big + "]\n", "bad.ngc:1: a sum in"},
      {ProgramDialect::LinuxCnc, "#1 = [-" + big + " - " + big + "]\n", "bad.ngc:1: a difference in"},
      {ProgramDialect::LinuxCnc, "#1 = [" + big + " / 0.1]\n", "bad.ngc:1: a quotient in"},
      {ProgramDialect::LinuxCnc, "#1 = [10 ** 400]\n", "bad.ngc:1: a power (**) in"},
      {ProgramDialect::LinuxCnc, "G10 L2 P1 Z" + big + "\nG0 Z" + big + "\n", "bad.ngc:2: the Z target"},
      {ProgramDialect::LinuxCnc, "G91\nG0 X" + big + "\nG0 X" + big + "\n", "bad.ngc:3: the X target"},
      {ProgramDialect::FanucMacroB, "#1=EXP[1000.]\n#2=#1-#1\nG0 Z#2\n", "bad.ngc:1: EXP in"},
      {ProgramDialect::FanucMacroB, "#1=" + tans + "\nG1 Z[#1*0] F100.\n", "bad.ngc:1: a product in"},
  };
  for (const auto& c : cases) {
    Recorder r;
    Interpreter in(c.d, "bad.ngc", c.program);
    try {
      in.run(r);
      ADD_FAILURE() << "not refused: " << c.program.substr(0, 80);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.want), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not a finite number"), std::string::npos) << e.what();
    }
    for (const auto& t : r.targets) EXPECT_TRUE(t.xyz_mm.allFinite() && std::isfinite(t.c_deg) && std::isfinite(t.b_deg));
  }
  // The largest finite values still compute: 1e308 is a value, only its overflow is refused.
  Recorder r;
  Interpreter ok(ProgramDialect::LinuxCnc, "ok.ngc", "#1 = [" + big + " * 1.5]\n#2 = [EXP[700]]\nM2\n");
  ok.run(r);
  EXPECT_EQ(ok.parameter(1), 1e308 * 1.5);
  EXPECT_EQ(ok.parameter(2), std::exp(700.0));
}

// A live loop on the other side of the controller: at t = 0 it asks for the next cycle in
// `wait_s` seconds and counts the value down with the machine's clock (only dwells take time
// here), as the TALC loop's writer does; Fanuc reads it as #500, LinuxCNC as analog input 0.
struct LiveMachine : Recorder {
  double t_s = 0, wait_s = 150;
  mutable std::vector<int> variables_read;
  std::vector<int> inputs_read;
  double remaining() const { return std::max(0.0, wait_s - t_s); }
  void dwell(double s) override {
    Recorder::dwell(s);
    t_s += s;
  }
  std::optional<double> externalVariable(int n) const override {
    variables_read.push_back(n);
    return n == 500 ? std::optional<double>(remaining()) : std::nullopt;
  }
  double analogInput(int n) override {
    inputs_read.push_back(n);
    return n == 0 ? remaining() : n == 1 ? 1000.0 + t_s : 0.0;  // input 1: a clock
  }
};

// The dwells of a run and where they fell: the index of each among the probe moves before it.
std::vector<std::pair<std::string, int>> dwellsAfterProbes(const Recorder& r) {
  std::vector<std::pair<std::string, int>> out;
  int probes = 0;
  for (const auto& c : r.calls) {
    if (c == "G31" || c == "G38.2") ++probes;
    if (c.rfind("G4 ", 0) == 0) out.emplace_back(c.substr(3), probes);
  }
  return out;
}

ProbeProgram liveProgram() {
  ProbeProgram p;
  p.title = "t";
  p.log_file = "probe.log";
  p.cycles = 3;
  p.gap_s = 300;  // nominal only: the program waits as told
  p.live_interval = true;
  p.cycle_body = {ToolChange{99, true}, Rapid{10.0, 0.0, 20.0}, ProbeMove{30, 0, 20, 200, 1, 1}};
  return p;
}

// 150 s to wait: 60 + 60 + 30 s of dwell after the first cycle (a read after each), then 0, so
// the third cycle follows the second at once; the fixed 300 s gap is never dwelt.
TEST(Interpreter, TheLiveIntervalIsReadFromOutsideInBothDialects) {
  const std::vector<std::pair<std::string, int>> want = {
      {std::to_string(60.0), 1}, {std::to_string(60.0), 1}, {std::to_string(30.0), 1}};
  LiveMachine fa;
  fa.contact_x = 12.5;
  Interpreter fanuc(ProgramDialect::FanucMacroB, "t.nc", writeFanucMacroB(liveProgram()));
  EXPECT_TRUE(fanuc.run(fa).ended);
  EXPECT_EQ(dwellsAfterProbes(fa), want);
  EXPECT_EQ(fa.log_lines.size(), 3u + 3u);  // %, START, 3 points, %
  // Read once before the wait loop and once after each dwell, after each of the 2 first cycles.
  EXPECT_EQ(fa.variables_read, std::vector<int>(1 + 3 + 1, 500));
  EXPECT_EQ(fanuc.parameter(500), 0.0);  // the last value read stays stored
  EXPECT_EQ(fanuc.parameter(101), 0.0);

  LiveMachine lc;
  lc.contact_x = 12.5;
  Interpreter linuxcnc(ProgramDialect::LinuxCnc, "t.ngc", writeLinuxCnc(liveProgram()));
  EXPECT_TRUE(linuxcnc.run(lc).ended);
  EXPECT_EQ(dwellsAfterProbes(lc), want);
  EXPECT_EQ(lc.log_lines.size(), 3u);
  // The clock (input 1) after each probe move, the wait (input 0) once before each wait loop and
  // after each dwell; the clock is the log line's eighth field.
  EXPECT_EQ(lc.inputs_read, (std::vector<int>{1, 0, 0, 0, 0, 1, 0, 1}));
  ASSERT_EQ(lc.log_lines.size(), 3u);
  EXPECT_NE(lc.log_lines[0].find(" 1000.000000"), std::string::npos) << lc.log_lines[0];
  EXPECT_NE(lc.log_lines[1].find(" 1150.000000"), std::string::npos) << lc.log_lines[1];
  EXPECT_EQ(linuxcnc.parameter(5399), 1150.0);  // the last read: the third point's clock

  // Nothing writing the value (a machine without a live loop): the cycles run back to back.
  for (const auto d : {ProgramDialect::FanucMacroB, ProgramDialect::LinuxCnc}) {
    Recorder quiet;
    quiet.contact_x = 12.5;
    const auto p = liveProgram();
    Interpreter in(d, "t", d == ProgramDialect::LinuxCnc ? writeLinuxCnc(p) : writeFanucMacroB(p));
    in.run(quiet);
    EXPECT_TRUE(dwellsAfterProbes(quiet).empty());
  }
  // Without the option the nominal gap is dwelt, 300 s after each cycle but the last.
  auto fixed = liveProgram();
  fixed.live_interval = false;
  LiveMachine f2;
  f2.contact_x = 12.5;
  Interpreter in(ProgramDialect::FanucMacroB, "t.nc", writeFanucMacroB(fixed));
  in.run(f2);
  EXPECT_EQ(dwellsAfterProbes(f2), (std::vector<std::pair<std::string, int>>{{std::to_string(300.0), 1},
                                                                              {std::to_string(300.0), 2}}));
  EXPECT_TRUE(f2.variables_read.empty());
}

// The machine's value replaces the stored one only for Fanuc's #500..#999, and only when it has
// one; LinuxCNC's #500 is a plain parameter.
TEST(Interpreter, ExternalVariablesReplaceTheStoredValueOnlyWhereAWriterCanReachThem) {
  struct Writer : Recorder {
    mutable std::vector<int> asked;
    std::optional<double> externalVariable(int n) const override {
      asked.push_back(n);
      return n == 999 ? std::nullopt : std::optional<double>(3.0);
    }
  };
  Writer w;
  Interpreter fa(ProgramDialect::FanucMacroB, "t.nc",
                 "#500=7\n#999=8\n#499=9\n#1000=10\n#1=#500+#999\n#2=#499+#1000\nM30\n");
  fa.run(w);
  EXPECT_EQ(fa.parameter(1), 3 + 8);   // #500 as written from outside, #999 as stored
  EXPECT_EQ(fa.parameter(2), 9 + 10);  // not common variables a FOCAS writer sets
  EXPECT_EQ(fa.parameter(500), 3.0);   // stored, as if written just before the read
  EXPECT_EQ(w.asked, (std::vector<int>{500, 999}));
  Recorder nobody;
  Interpreter fa2(ProgramDialect::FanucMacroB, "t.nc", "#500=7\n#1=#500\nM30\n");
  fa2.run(nobody);
  EXPECT_EQ(fa2.parameter(1), 7.0);
  Writer w2;
  Interpreter lc(ProgramDialect::LinuxCnc, "t.ngc", "#500 = 7\n#1 = #500\nM2\n");
  lc.run(w2);
  EXPECT_EQ(lc.parameter(1), 7.0);
  EXPECT_TRUE(w2.asked.empty());

  struct Broken : Recorder {
    std::optional<double> externalVariable(int) const override { return std::nan(""); }
    double analogInput(int) override { return INFINITY; }
  };
  for (const auto& [d, text, want] :
       {std::tuple{ProgramDialect::FanucMacroB, std::string("G4 X1.\n#1=#500\n"),
                   std::string("t:2: #500 written from outside is not a finite number")},
        std::tuple{ProgramDialect::LinuxCnc, std::string("G4 P1\nM66 E1 L0\n"),
                   std::string("t:2: analog input 1 reads a value that is not a finite number")}}) {
    Broken b;
    Interpreter in(d, "t", text);
    try {
      in.run(b);
      FAIL() << "accepted " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  }
}

// LinuxCNC M66 E<n> L0 reads analog input n into #5399; every other M66 form is refused with its
// line, since a run that took it for an immediate read would not wait when LinuxCNC waits.
TEST(Interpreter, M66ReadsAnAnalogInputAtOnceAndRefusesItsOtherForms) {
  struct Inputs : Recorder {
    std::vector<int> asked;
    double analogInput(int n) override {
      asked.push_back(n);
      return 10.0 + n;
    }
  };
  Inputs r;
  Interpreter in(ProgramDialect::LinuxCnc, "t.ngc", "M66 E2 L0\n#1 = #5399\nN5 M66 E63 L0\nM2\n");
  in.run(r);
  EXPECT_EQ(in.parameter(1), 12.0);
  EXPECT_EQ(in.parameter(5399), 73.0);
  EXPECT_EQ(r.asked, (std::vector<int>{2, 63}));
  const std::string only = "only M66 E<n> L0";
  expectInputError(ProgramDialect::LinuxCnc, "G0 X0\nM66 P0 L0\n", "bad.ngc:2: M66 P (a digital input)");
  expectInputError(ProgramDialect::LinuxCnc, "M66 E0 L1\n", "bad.ngc:1: M66 L1 waits on the input; " + only);
  expectInputError(ProgramDialect::LinuxCnc, "M66 E0 L3 Q5\n", "bad.ngc:1: word 'Q' is not modelled");
  expectInputError(ProgramDialect::LinuxCnc, "M66 E0\n", "bad.ngc:1: M66 without L0");
  expectInputError(ProgramDialect::LinuxCnc, "M66 L0\n", "bad.ngc:1: M66 without E<n>");
  expectInputError(ProgramDialect::LinuxCnc, "M66 E0.5 L0\n", "bad.ngc:1: E0.5: expected a whole number 0..63");
  expectInputError(ProgramDialect::LinuxCnc, "M66 E64 L0\n", "bad.ngc:1: E64: expected a whole number 0..63");
  expectInputError(ProgramDialect::LinuxCnc, "G4 P1 M66 E0 L0\n", "bad.ngc:1: M66 E<n> L0 must stand on a line of its own");
  expectInputError(ProgramDialect::LinuxCnc, "M66 E0 L0 X5\n", "bad.ngc:1: word 'X5' has no effect on this line");
  expectInputError(ProgramDialect::LinuxCnc, "G0 X1 E2\n", "bad.ngc:1: word 'E2' has no effect on this line");
  // A Fanuc control has no M66 of its own (a machine builder's M code): not modelled.
  expectInputError(ProgramDialect::FanucMacroB, "M66\n", "bad.ngc:1: M66 is not modelled");
  expectInputError(ProgramDialect::FanucMacroB, "G0 X1. E2.\n", "bad.ngc:1: word 'E' is not modelled");
}

TEST(Interpreter, AnEndlessLoopIsStoppedAndNamed) {
  Recorder r;
  Interpreter in(ProgramDialect::LinuxCnc, "loop.ngc", "o1 while [1]\no1 endwhile\n");
  try {
    in.run(r, 1000);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("endless loop"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probeloop::gcode
