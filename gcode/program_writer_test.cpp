// The machining/probing program model (gcode/program.hpp) in both dialects: the lines each op
// becomes, the counted loop, and that our interpreter runs what the writers emit.
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <stdexcept>

#include "core/error.hpp"
#include "gcode/interpreter.hpp"
#include "gcode/probe_program.hpp"
#include "gcode/program.hpp"

namespace probeloop::gcode {
namespace {

Program sample() {
  Program p;
  p.title = "t (test)";
  p.header = {"a header"};
  p.number = 2002;
  p.has_b_axis = true;
  p.ops = {RapidMachineZ{500},
           RotateB{0},
           ToolChange{3, true},
           Spindle{8000},
           Coolant{true},
           Rapid{-130, 0, std::nullopt},
           Feed{std::nullopt, std::nullopt, -12.1, 3000},
           Feed{115, -24, std::nullopt, 1500},
           RotateC{36.5},
           LoopBegin{3, "_pl_load"},
           TurnC{720, 3600},
           TurnC{-720, 3600},
           LoopEnd{},
           Dwell{12.5},
           Coolant{false},
           Spindle{0},
           ToolChange{0, false}};
  return p;
}

// Counts what the interpreter asks of the machine.
struct Counter : MachineInterface {
  int rapids = 0, feeds = 0, c_feeds = 0, probes = 0, dwells = 0, tool_changes = 0;
  std::vector<double> spindle_rpm;
  std::vector<bool> coolant_on;
  std::vector<std::string> logs;
  MachinePosition at;
  void rapid(const MachinePosition& to) override { ++rapids; at = to; }
  void feed(const MachinePosition& to, double) override {
    ++feeds;
    if (to.c_deg != at.c_deg) ++c_feeds;
    at = to;
  }
  // A plane at machine z = 0: a probe move that goes below it touches it there.
  ProbeOutcome probe(const MachinePosition& to, double, ProbeMode) override {
    ++probes;
    ProbeOutcome o;
    o.stop = to;
    if (to.xyz_mm.z() < 0) {
      o.contact = true;
      o.stop.xyz_mm.z() = 0;
    }
    at = o.stop;
    return o;
  }
  void dwell(double) override { ++dwells; }
  void toolChange(int) override { ++tool_changes; }
  double toolLength(int t) const override { return t == 0 ? 0.0 : 100.0 + t; }
  void spindle(double rpm) override { spindle_rpm.push_back(rpm); }
  void coolant(bool on) override { coolant_on.push_back(on); }
  void openLog(const std::string&) override {}
  void log(const std::string& l) override { logs.push_back(l); }
  void closeLog() override {}
};

TEST(ProgramWriter, LinuxCncLines) {
  const std::string s = writeLinuxCnc(sample());
  EXPECT_NE(s.find("(t [test])\n(a header)\nG21 G90 G17 G40 G49 G80 G94\nG10 L2 P6 X0 Y0 Z0 B0 C0\nG59\n"), std::string::npos) << s;
  EXPECT_NE(s.find("G0 B0.000\nT3 M6\nG43 H3\nS8000 M3\nM8\n"), std::string::npos) << s;
  EXPECT_NE(s.find("G1 Z-12.1000 F3000.000\nG1 X115.0000 Y-24.0000 F1500.000\nG0 C36.500\n"), std::string::npos) << s;
  EXPECT_NE(s.find("#<_pl_load> = 1\no100 while [#<_pl_load> LE 3]\nG91 G1 C720.000 F3600.000\nG90\nG91 G1 C-720.000 F3600.000\nG90\n"
                   "#<_pl_load> = [#<_pl_load> + 1]\no100 endwhile\nG4 P12.500\nM9\nM5\nT0 M6\nG49\nM2\n"),
            std::string::npos)
      << s;
  EXPECT_EQ(s.find("LOGOPEN"), std::string::npos);  // no log without probing
}

TEST(ProgramWriter, FanucLines) {
  const std::string s = writeFanucMacroB(sample());
  EXPECT_EQ(s.rfind("%\nO2002 (T [TEST])\n(A HEADER)\n", 0), 0u) << s;
  EXPECT_NE(s.find("#101=1\nWHILE [#101 LE 3] DO1\nG91 G1 C720.000 F3600.000\nG90\nG91 G1 C-720.000 F3600.000\nG90\n"
                   "#101=#101+1\nEND1\n"
                   "G4 X12.500\nM9\nM5\n"),
            std::string::npos)
      << s;
  EXPECT_NE(s.find("M30\n%\n"), std::string::npos);
}

// A table-table A/C machine (issue 33): the A word as B's, the work offset zeroing A, and our
// interpreter handing A to the machine in both dialects.
TEST(ProgramWriter, TheAAxisIsWrittenAndReadLikeB) {
  Program p;
  p.title = "a";
  p.has_a_axis = true;
  p.ops = {RotateA{-30}, RotateC{90}, RotateA{12.5}};
  const std::string l = writeLinuxCnc(p), f = writeFanucMacroB(p);
  for (const auto& s : {l, f}) {
    EXPECT_NE(s.find("G10 L2 P6 X0 Y0 Z0 A0 C0\nG59\nG0 A-30.000\nG0 C90.000\nG0 A12.500\n"), std::string::npos) << s;
  }
  EXPECT_FALSE(allFinite(Op{RotateA{NAN}}));
  for (auto d : {ProgramDialect::LinuxCnc, ProgramDialect::FanucMacroB}) {
    Counter c;
    Interpreter in(d, "a", d == ProgramDialect::LinuxCnc ? l : f);
    EXPECT_TRUE(in.run(c).ended);
    EXPECT_EQ(c.rapids, 3);
    EXPECT_EQ(c.at.a_deg, 12.5);
    EXPECT_EQ(c.at.c_deg, 90);
    EXPECT_EQ(c.at.b_deg, 0);
  }
  // A ProbeProgram zeroes A in its work offset too; without A nothing changes.
  ProbeProgram pp;
  pp.title = "pa";
  pp.log_file = "pa.log";
  pp.has_a_axis = true;
  EXPECT_NE(writeLinuxCnc(pp).find("G10 L2 P6 X0 Y0 Z0 A0 C0\n"), std::string::npos);
  pp.has_a_axis = false;
  EXPECT_NE(writeFanucMacroB(pp).find("G10 L2 P6 X0 Y0 Z0 C0\n"), std::string::npos);
}

TEST(ProgramWriter, NestedLoopsUseOneCounterPerLevel) {
  Program p;
  p.title = "nested";
  p.ops = {LoopBegin{2, "_a"}, LoopBegin{3, "_b"}, Dwell{1}, LoopEnd{}, LoopEnd{}};
  const std::string f = writeFanucMacroB(p);
  EXPECT_NE(f.find("WHILE [#101 LE 2] DO1\n#102=1\nWHILE [#102 LE 3] DO2\nG4 X1.000\n#102=#102+1\nEND2\n#101=#101+1\nEND1\n"),
            std::string::npos)
      << f;
  const std::string l = writeLinuxCnc(p);
  EXPECT_NE(l.find("o100 while [#<_a> LE 2]\n#<_b> = 1\no101 while [#<_b> LE 3]"), std::string::npos) << l;
  for (auto d : {ProgramDialect::LinuxCnc, ProgramDialect::FanucMacroB}) {
    Counter c;
    Interpreter in(d, "nested", d == ProgramDialect::LinuxCnc ? l : f);
    EXPECT_TRUE(in.run(c).ended);
    EXPECT_EQ(c.dwells, 6);
  }
}

TEST(ProgramWriter, RefusesUnbalancedLoopsDeepNestingAndProbingWithoutALog) {
  Program p;
  p.title = "bad";
  p.ops = {LoopBegin{2, "_a"}};
  EXPECT_THROW(writeLinuxCnc(p), std::invalid_argument);
  p.ops = {LoopEnd{}};
  EXPECT_THROW(writeFanucMacroB(p), std::invalid_argument);
  p.ops = {LoopBegin{1, "_a"}, LoopBegin{1, "_b"}, LoopBegin{1, "_c"}, LoopBegin{1, "_d"},
           LoopEnd{},          LoopEnd{},          LoopEnd{},          LoopEnd{}};
  EXPECT_THROW(writeFanucMacroB(p), std::invalid_argument);  // DO1..DO3 only
  p.ops = {ProbeMove{1, 2, 3, 200, 1, 1}};
  EXPECT_THROW(writeLinuxCnc(p), std::invalid_argument);
  p.log_file = "x.log";
  EXPECT_NO_THROW(writeLinuxCnc(p));
}

TEST(ProgramWriter, RefusesNumbersThatAreNotFinite) {
  Program p;
  p.title = "nan";
  for (const Op& op : std::initializer_list<Op>{Rapid{NAN, 0, std::nullopt}, Feed{1, 2, INFINITY, 100}, TurnC{360, NAN},
                                                RotateC{NAN}, ProtectedMove{1, 2, 3, NAN}, Dwell{-INFINITY}}) {
    EXPECT_FALSE(allFinite(op));
    p.ops = {op};
    EXPECT_THROW(writeLinuxCnc(p), std::invalid_argument);
    EXPECT_THROW(writeFanucMacroB(p), std::invalid_argument);
  }
  EXPECT_TRUE(allFinite(Rapid{1, std::nullopt, std::nullopt}));
  EXPECT_TRUE(allFinite(TurnC{-360, 340}));
}

TEST(ProgramWriter, OurInterpreterRunsBothDialects) {
  for (auto d : {ProgramDialect::LinuxCnc, ProgramDialect::FanucMacroB}) {
    Counter c;
    const Program p = sample();
    Interpreter in(d, "sample", d == ProgramDialect::LinuxCnc ? writeLinuxCnc(p) : writeFanucMacroB(p));
    const auto r = in.run(c);
    EXPECT_TRUE(r.ended);
    EXPECT_EQ(c.c_feeds, 6);  // 3 x (forward, back)
    EXPECT_EQ(c.feeds, 8);
    // Incremental turns: +720 and -720 from the index, back where C stood; G90 again after them
    // (the last absolute move, T0 M6's G49, leaves XYZ where the feeds left them).
    EXPECT_NEAR(c.at.c_deg, 36.5, 1e-12);
    EXPECT_NEAR(c.at.xyz_mm.x(), 115, 1e-12);
    EXPECT_EQ(c.dwells, 1);
    EXPECT_EQ(c.tool_changes, 2);
    ASSERT_EQ(c.spindle_rpm.size(), 2u);
    EXPECT_EQ(c.spindle_rpm[0], 8000);
    EXPECT_EQ(c.spindle_rpm[1], 0);
    ASSERT_EQ(c.coolant_on.size(), 2u);
    // The counter ends one past the count.
    EXPECT_EQ(d == ProgramDialect::LinuxCnc ? in.namedParameter("_pl_load") : in.parameter(101), 4);
  }
}

TEST(ProgramWriter, ProbingProgramLogsCycleOne) {
  Program p;
  p.title = "probe";
  p.log_file = "ttp_probe.log";
  // Tool 99 is 199 mm long here: program z -199 is machine z 0, the plane.
  p.ops = {ToolChange{99, true}, ProtectedMove{10, 0, -196, 1000}, ProbeMove{10, 0, -201, 200, 4, 7}};
  for (auto d : {ProgramDialect::LinuxCnc, ProgramDialect::FanucMacroB}) {
    Counter c;
    Interpreter in(d, "probe", d == ProgramDialect::LinuxCnc ? writeLinuxCnc(p) : writeFanucMacroB(p));
    in.run(c);
    EXPECT_EQ(c.probes, 2);
    std::erase(c.logs, "%");  // Fanuc POPEN/PCLOS punch a leader
    if (d == ProgramDialect::FanucMacroB) {  // and the controller's clock when the program starts
      ASSERT_FALSE(c.logs.empty());
      EXPECT_EQ(c.logs.front().rfind("START ", 0), 0u) << c.logs.front();
      c.logs.erase(c.logs.begin());
    }
    ASSERT_EQ(c.logs.size(), 1u);
    EXPECT_EQ(c.logs[0].rfind(d == ProgramDialect::LinuxCnc ? "PT 1.000000 4 7 " : "PT", 0), 0u) << c.logs[0];
    EXPECT_NE(c.logs[0].find("-199"), std::string::npos) << c.logs[0];
  }
}

}  // namespace
}  // namespace probeloop::gcode
