// The safety verifier on small programs written by the project's own writers (gcode/), the
// shipped sphere artifact and workpiece block on the shipped LinuxCNC mill: one safe probing
// sequence, then each rule broken once (the finding's rule and line checked).
#include "verify/safety.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "gcode/program.hpp"

namespace probeloop::verify {
namespace {

std::string src() {
  const char* d = std::getenv("PROBELOOP_SOURCE_DIR");
  return d ? d : PROBELOOP_SOURCE_DIR;
}

// 1-based line of the first line that starts with `prefix` (after `from`).
int lineOf(const std::string& text, const std::string& prefix, int from = 0) {
  std::istringstream in(text);
  std::string l;
  int n = 0;
  while (std::getline(in, l))
    if (++n > from && l.rfind(prefix, 0) == 0) return n;
  return -1;
}

bool has(const Report& r, const std::string& rule, int line) {
  for (const auto& f : r.findings)
    if (f.rule == rule && f.line == line) return true;
  return false;
}
std::string listed(const Report& r) { return reportText(r); }

struct SphereSetup {
  parts::Machine m = parts::loadMachine(src() + "/parts/machines/linuxcnc_rotary_mill.yaml");
  parts::TestPiece piece = parts::loadTestPiece(src() + "/parts/sphere_artifact.yaml");
  // Sphere centre (-160, 0, 75), R 15, tip r 3: the +X point starts at X-139, contact at -142.
  gcode::Program program(std::vector<gcode::Op> middle) const {
    gcode::Program p;
    p.title = "test";
    p.log_file = "t.log";
    p.ops = {gcode::RapidMachineZ{500}, gcode::ToolChange{99, true}, gcode::Rapid{std::nullopt, std::nullopt, 113.0},
             gcode::RotateC{0}, gcode::Rapid{-139.0, 0.0, std::nullopt}};
    p.ops.insert(p.ops.end(), middle.begin(), middle.end());
    p.ops.push_back(gcode::Rapid{std::nullopt, std::nullopt, 113.0});
    p.ops.push_back(gcode::RapidMachineZ{500});
    p.ops.push_back(gcode::ToolChange{0, false});
    return p;
  }
  std::vector<gcode::Op> probing() const {
    return {gcode::ProtectedMove{-139, 0, 75, 1000}, gcode::ProbeMove{-144, 0, 75, 200, 1, 1}, gcode::Rapid{-139.0, 0.0, 75.0}};
  }
  Report check(const std::string& text, const std::string& file = "t.ngc") const {
    return checkPrograms({{file, text}}, m, piece);
  }
};

TEST(SafetyVerifier, PlannedLikeProbingIsSafeInBothDialects) {
  SphereSetup s;
  const auto p = s.program(s.probing());
  const auto a = s.check(gcode::writeLinuxCnc(p), "t.ngc");
  EXPECT_TRUE(a.safe()) << listed(a);
  const auto b = s.check(gcode::writeFanucMacroB(p), "t.nc");
  EXPECT_TRUE(b.safe()) << listed(b);
  EXPECT_NE(a.model.find("stylus shaft"), std::string::npos);
}

TEST(SafetyVerifier, OffTravel) {
  SphereSetup s;
  auto ops = s.probing();
  ops.push_back(gcode::Rapid{std::nullopt, std::nullopt, 113.0});
  ops.push_back(gcode::Rapid{-400.0, std::nullopt, std::nullopt});
  const std::string t = gcode::writeLinuxCnc(s.program(ops));
  const auto r = s.check(t);
  ASSERT_FALSE(r.findings.empty());
  EXPECT_EQ(r.findings.front().line, lineOf(t, "G0 X-400")) << listed(r);
  for (const auto& f : r.findings) EXPECT_EQ(f.rule, "travel") << listed(r);  // every move out there, up to the tool change
}

TEST(SafetyVerifier, RapidThroughTheSphereIsACollision) {
  SphereSetup s;
  // Straight down through the sphere's centre.
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::Rapid{-160.0, 0.0, std::nullopt}, gcode::Rapid{std::nullopt, std::nullopt, 60.0}}));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "collision", lineOf(t, "G0 Z60"))) << listed(r);
}

TEST(SafetyVerifier, StylusShaftBeforeTheTipIsACollision) {
  SphereSetup s;
  // A protected move whose tip stays clear but whose shaft meets the sphere: the tip below the
  // sphere (Z 57, the sphere's bottom at 60), moving in under it, clear of the 5 mm stem.
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::ProtectedMove{-139, 0, 57, 1000}, gcode::ProtectedMove{-151, 0, 57, 500}}));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "collision", lineOf(t, "G38.3 X-151"))) << listed(r);
}

TEST(SafetyVerifier, UnprotectedProbeMoves) {
  SphereSetup s;
  const std::string ok = gcode::writeLinuxCnc(s.program(s.probing()));
  // The #5070 check after G38.3 removed: a touch would go unnoticed.
  std::string t;
  {
    std::istringstream in(ok);
    std::string l;
    int skip = 0;
    while (std::getline(in, l)) {
      if (l.rfind("o1", 0) == 0 && l.find(" if ") != std::string::npos) skip = 3;
      if (skip > 0) {
        --skip;
        continue;
      }
      t += l + "\n";
    }
  }
  auto r = s.check(t);
  EXPECT_TRUE(has(r, "probe-unprotected", lineOf(t, "G38.3"))) << listed(r);
  ASSERT_EQ(r.findings.size(), 1u) << listed(r);
  EXPECT_NEAR(r.findings[0].where_mm.z(), 75.0, 1e-9);  // the stylus-tip centre where the move ends, not the gauge line
  // Fanuc: the measuring move's check removed (G31 goes on to the DPRNT without a trigger).
  const std::string f = gcode::writeFanucMacroB(s.program(s.probing()));
  std::string g;
  std::istringstream in(f);
  std::string l;
  while (std::getline(in, l))
    if (l.find("PROBE DID NOT TRIGGER") == std::string::npos) g += l + "\n";
  r = s.check(g, "t.nc");
  EXPECT_TRUE(has(r, "probe-unprotected", lineOf(g, "G31 X-144"))) << listed(r);
  EXPECT_EQ(r.findings.size(), 1u) << listed(r);
}

TEST(SafetyVerifier, PositioningWithTheProbeBelowTheClearancePlaneNeedsProtection) {
  SphereSetup s;
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::Rapid{-139.0, 0.0, 75.0}, gcode::ProbeMove{-144, 0, 75, 200, 1, 1},
                                                        gcode::Rapid{-139.0, 0.0, 75.0}}));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "positioning-unprotected", lineOf(t, "G0 X-139.0000 Y0.0000 Z75"))) << listed(r);
  EXPECT_EQ(r.findings.size(), 1u) << listed(r);  // the retreat after the contact is not one
}

TEST(SafetyVerifier, RotaryMoveBelowTheClearancePlane) {
  SphereSetup s;
  auto ops = s.probing();
  ops.push_back(gcode::RotateC{90});
  const std::string t = gcode::writeLinuxCnc(s.program(ops));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "rotary-below-clearance", lineOf(t, "G0 C90"))) << listed(r);
  EXPECT_EQ(r.findings.size(), 1u) << listed(r);
}

TEST(SafetyVerifier, RotaryMoveOutsideTheBodiesCircleIsAllowed) {
  SphereSetup s;
  // Below the clearance plane but 197 mm from the C axis: the sphere (out to 175 mm) cannot
  // reach the probe while the table turns (the thermal test piece indexes C like this).
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::Rapid{-200.0, 0.0, std::nullopt}, gcode::ProtectedMove{-200, 0, 75, 1000},
                                                        gcode::RotateC{90}}));
  const auto r = s.check(t);
  EXPECT_TRUE(r.safe()) << listed(r);
}

TEST(SafetyVerifier, MeasuringMoveThatMeetsNothingStopsTheProgram) {
  SphereSetup s;
  // 30 mm off the sphere in Y: G38.2 ends without contact, LinuxCNC stops the program there.
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::Rapid{-139.0, 30.0, std::nullopt}, gcode::ProtectedMove{-139, 30, 75, 1000},
                                                        gcode::ProbeMove{-144, 30, 75, 200, 1, 1}}));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "program-stops", lineOf(t, "G38.2"))) << listed(r);
  EXPECT_EQ(r.findings.size(), 1u) << listed(r);
}

TEST(SafetyVerifier, SpindleWithTheProbe) {
  SphereSetup s;
  auto ops = s.probing();
  ops.insert(ops.begin(), gcode::Spindle{1000});
  ops.push_back(gcode::Spindle{0});
  const std::string t = gcode::writeLinuxCnc(s.program(ops));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "spindle-with-probe", lineOf(t, "S1000 M3"))) << listed(r);
  EXPECT_EQ(r.findings.size(), 1u) << listed(r);
}

TEST(SafetyVerifier, ProbeMoveTooFarPastTheContact) {
  SphereSetup s;
  const std::string t = gcode::writeLinuxCnc(s.program({gcode::ProtectedMove{-139, 0, 75, 1000}, gcode::ProbeMove{-152, 0, 75, 200, 1, 1},
                                                        gcode::Rapid{-139.0, 0.0, 75.0}}));
  const auto r = s.check(t);
  EXPECT_TRUE(has(r, "probe-unbounded", lineOf(t, "G38.2"))) << listed(r);
}

TEST(SafetyVerifier, MaterialCutByTheProgramIsGone) {
  const auto m = parts::loadMachine(src() + "/parts/machines/linuxcnc_rotary_mill.yaml");
  const auto piece = parts::loadTestPiece(src() + "/examples/workpiece_block.yaml");
  // Block X -40..40, Y -30..30, Z 0..40; T1 d10, 25 mm of flutes. A slot at Z30 along X, a
  // rapid back through it (clear), then a rapid sideways into the block (a collision).
  const std::string t =
      "G21 G90 G17 G40 G49 G80 G94\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nG53 G0 Z500\nT1 M6\nG43 H1\nG0 X-60 Y0\nG0 Z30\n"
      "S3000 M3\nG1 X60 F500\nG0 X0\nG0 Y20\nG0 Z100\nM5\nM2\n";
  auto r = checkPrograms({{"cut.ngc", t}}, m, piece);
  EXPECT_TRUE(has(r, "collision", 12)) << listed(r);
  ASSERT_FALSE(r.findings.empty());
  EXPECT_EQ(r.findings.front().line, 12) << listed(r);  // the cut (10) and the rapid back through the slot (11) are clear
  // The same slot with the spindle off: the feed move itself meets the stock.
  std::string off = t;
  off.replace(off.find("S3000 M3\n"), 9, "");
  r = checkPrograms({{"cut.ngc", off}}, m, piece);
  EXPECT_TRUE(has(r, "collision", 11)) << listed(r);
}

TEST(SafetyVerifier, TurningTheTableUnderTheCutterCutsARing) {
  const auto m = parts::loadMachine(src() + "/parts/machines/linuxcnc_rotary_mill.yaml");
  const auto piece = parts::loadTestPiece(src() + "/examples/workpiece_block.yaml");
  // The block (X -40..40, Y -30..30) on the C axis; T1 (d10) at X45 Z30 while C turns once
  // removes everything 40 mm or more from the axis above Z30 (the block's corners). Then, out
  // to X60, over to Y25 and in to X41 Y25 (the tool never nearer the axis than 43 mm) is
  // clear; without the turn the last rapid meets the corner that is still there. (A straight
  // rapid from X45 Y0 to X41 Y25 would not be clear: it passes 39.4 mm from the axis.)
  const std::string head = "G21 G90 G17 G40 G49 G80 G94\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT1 M6\nG43 H1\nG0 X45 Y0\nG0 Z30\nS3000 M3\n";
  const std::string turn = "G91 G1 C360 F3000\nG90\n";
  const std::string tail = "G0 X60\nG0 Y25\nG0 X41\nG0 Z100\nM5\nM2\n";
  auto r = checkPrograms({{"ring.ngc", head + turn + tail}}, m, piece);
  EXPECT_TRUE(r.safe()) << listed(r);
  r = checkPrograms({{"ring.ngc", head + tail}}, m, piece);
  EXPECT_TRUE(has(r, "collision", 11)) << listed(r);
}

TEST(SafetyVerifier, UnknownToolIsBadInput) {
  SphereSetup s;
  const std::string t = "G21 G90\nT7 M6\nG43 H7\nM2\n";
  try {
    s.check(t);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.ngc:2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probeloop::verify

namespace probeloop::verify {
namespace {

// The emitted probing sequence with the #5070 check after its G38.3 replaced by `insert`.
std::string withoutContactCheck(const std::string& ok, const std::vector<std::string>& insert, int& g38_line) {
  std::vector<std::string> lines;
  std::istringstream in(ok);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  std::size_t i = 0;
  while (lines[i].rfind("G38.3", 0) != 0) ++i;
  g38_line = static_cast<int>(i) + 1;
  lines.erase(lines.begin() + static_cast<long>(i) + 1, lines.begin() + static_cast<long>(i) + 4);  // o1 if / ABORT / endif
  lines.insert(lines.begin() + static_cast<long>(i) + 1, insert.begin(), insert.end());
  std::string t;
  for (const auto& l : lines) t += l + "\n";
  return t;
}

// Issue 29: each probe move's inverted outcome runs on a copy of the interpreter's state at the
// move (parameters included), not on the nominal run's. Here the branch adds 1 to #100 before
// its next move; were the parameters shared, the nominal run would then see #100 = 2 and stop
// (a program-stops finding). Only the unprotected G38.3 is found.
TEST(SafetyVerifier, AProbeBranchRunsOnACopyOfTheState) {
  SphereSetup s;
  int g38 = 0;
  const std::string t = withoutContactCheck(gcode::writeLinuxCnc(s.program(s.probing())),
                                            {"#100 = [#100 + 1]", "G0 X-139 Y0 Z75", "o2 if [#100 GT 1]",
                                             "(ABORT, the branch's parameter reached the nominal run)", "o2 endif"},
                                            g38);
  const auto r = s.check(t);
  ASSERT_EQ(r.findings.size(), 1u) << listed(r);
  EXPECT_TRUE(has(r, "probe-unprotected", g38)) << listed(r);
  EXPECT_NE(r.findings[0].what.find("goes on to a rapid move"), std::string::npos) << listed(r);
}

// A probe line that also ends the program (M2 on it): the branch ends there too, and the
// finding says the program went on to its end.
TEST(SafetyVerifier, AProbeLineThatEndsTheProgramGoesOnToItsEnd) {
  SphereSetup s;
  int g38 = 0;
  std::string t = withoutContactCheck(gcode::writeLinuxCnc(s.program(s.probing())), {}, g38);
  const std::size_t at = t.find("G38.3");
  t.insert(t.find('\n', at), " M2");
  const auto r = s.check(t);
  ASSERT_EQ(r.findings.size(), 1u) << listed(r);
  EXPECT_TRUE(has(r, "probe-unprotected", g38)) << listed(r);
  EXPECT_NE(r.findings[0].what.find("goes on to the program's end"), std::string::npos) << listed(r);
}

// A probe line inside a loop is tried once (its first execution), and the loop's other
// iterations do not repeat the finding.
TEST(SafetyVerifier, AProbeLineInALoopIsTriedOnce) {
  SphereSetup s;
  int g38 = 0;
  std::string t = withoutContactCheck(gcode::writeLinuxCnc(s.program(s.probing())), {}, g38);
  // The descent in a loop of three, each turn from the clearance plane (a retreat), so that the
  // last one leaves the probe where the measuring move expects it.
  std::vector<std::string> lines;
  std::istringstream in(t);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  const auto i = static_cast<long>(g38) - 1;
  lines.insert(lines.begin() + i + 1, {"#101 = [#101 + 1]", "o3 endwhile"});
  lines.insert(lines.begin() + i, {"#101 = 0", "o3 while [#101 LT 3]", "G0 Z113"});
  t.clear();
  for (const auto& l : lines) t += l + "\n";
  const auto r = s.check(t);
  ASSERT_EQ(r.findings.size(), 1u) << listed(r);
  EXPECT_TRUE(has(r, "probe-unprotected", g38 + 3)) << listed(r);
}

}  // namespace
}  // namespace probeloop::verify
