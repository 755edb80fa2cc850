// The safety verifier on a tilting table (issue 33): the trunnion's swing (rule tilt-swing)
// and moves made while the table is tilted. The shipped sphere artifact (sphere d 30 mm at
// 160 mm from C, centre 75 mm above the table, stem d 10 mm) on the shipped LinuxCNC mill
// given a B axis through X0 Z0 (the table surface at the C axis; +B clockwise seen from +Y),
// and on the table-table A/C machine. Where the bodies go is derived here: a table point
// (x, z) at B = q is at (x cos q - z sin q, x sin q + z cos q) (a rotation by -q about +Y).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "gcode/program.hpp"
#include "verify/safety.hpp"

namespace probeloop::verify {
namespace {

std::string source() {
  const char* d = std::getenv("PROBELOOP_SOURCE_DIR");
  return d ? d : PROBELOOP_SOURCE_DIR;
}

int lineStarting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  std::string l;
  int n = 0;
  while (std::getline(in, l))
    if (++n > 0 && l.rfind(prefix, 0) == 0) return n;
  return -1;
}

// The angle a tilt-swing finding names: "... at B -0.862 deg".
double angleAt(const Finding& f, const std::string& axis) {
  const auto at = f.what.rfind("at " + axis + " ");
  return at == std::string::npos ? NAN : std::stod(f.what.substr(at + 3 + axis.size() + 1));
}

const Finding* finding(const Report& r, const std::string& rule, int line = -1) {
  for (const auto& f : r.findings)
    if (f.rule == rule && (line < 0 || f.line == line)) return &f;
  return nullptr;
}

struct TiltSetup {
  parts::Machine m = trunnion();
  parts::TestPiece piece = parts::loadTestPiece(source() + "/parts/sphere_artifact.yaml");

  static parts::Machine trunnion() {
    auto m = parts::loadMachine(source() + "/parts/machines/linuxcnc_rotary_mill.yaml");
    m.b.present = true;
    m.b.min_deg = -120;
    m.b.max_deg = 120;
    m.b.max_speed_rpm = 10;
    m.b_axis_centre_xz_mm = Eigen::Vector2d(0, 0);
    return m;
  }
  // The probe from the tool change, the tip over the C axis at Z 350; `middle`; up to Z 300,
  // the table level again, the spindle emptied.
  std::string program(std::vector<gcode::Op> middle, bool level_at_end = true) const {
    gcode::Program p;
    p.title = "tilt";
    p.log_file = "t.log";
    p.has_b_axis = m.b.present;
    p.has_a_axis = m.a.present;
    p.ops = {gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{99, true}, gcode::RotateC{0}};
    p.ops.insert(p.ops.end(), middle.begin(), middle.end());
    p.ops.push_back(gcode::Rapid{std::nullopt, std::nullopt, 300.0});
    if (level_at_end) p.ops.push_back(m.a.present ? gcode::Op{gcode::RotateA{0}} : gcode::Op{gcode::RotateB{0}});
    p.ops.push_back(gcode::RapidMachineZ{m.tool_change.z_mm});
    p.ops.push_back(gcode::ToolChange{0, false});
    return gcode::writeLinuxCnc(p);
  }
  // Down beside the sphere's +X point (tip X-139, 3 mm off the contact), probe it, back.
  static std::vector<gcode::Op> probePlusX() {
    return {gcode::Rapid{-139.0, 0.0, std::nullopt}, gcode::ProtectedMove{-139, 0, 75, 1000},
            gcode::ProbeMove{-144, 0, 75, 200, 1, 1}, gcode::Rapid{-139.0, 0.0, 75.0}};
  }
  Report check(const std::string& text) const { return checkPrograms({{"t.ngc", text}}, m, piece); }
};

// The swing that would hit the probe sitting low is refused, naming the line, the axis, the
// angles and what it would hit. At B = -30 deg the sphere's centre goes from (-160, 75) to
// (-101.1, 145.0): it rises through the tip waiting 3 mm off its +X side.
TEST(SafetyVerifierTilt, ASwingIntoTheProbeSittingLowIsRefused) {
  TiltSetup s;
  auto ops = TiltSetup::probePlusX();
  ops.push_back(gcode::RotateB{-30});
  const std::string t = s.program(ops);
  const auto r = s.check(t);
  const Finding* f = finding(r, "tilt-swing", lineStarting(t, "G0 B-30"));
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("B moves from 0.000 to -30.000 deg: the table swings the sphere of the artifact"), std::string::npos) << f->what;
  EXPECT_NE(f->what.find("of the probe's"), std::string::npos) << f->what;
  EXPECT_NEAR(f->where_mm.x(), -139, 1e-9);
  // The centre moves by (75, 160) mm per radian at first; the tip, 21 mm off it, comes within
  // 20 mm (radii 15 + 3 and the 2 mm margin) at 31225 d^2 - 3150 d + 41 = 0: d = 0.88 deg.
  EXPECT_LT(angleAt(*f, "B"), -0.80) << f->what;
  EXPECT_GE(angleAt(*f, "B"), -0.88) << f->what;
  EXPECT_NE(f->limit.find("B axis line through X0.000 Z0.000 along Y"), std::string::npos) << f->limit;
}

// The same swing from the clearance plane over the C axis passes: the sphere ends 101 mm to
// the side of the tip (at Z 113) and the table surface stays at Z 0 under it (the axis line
// lies in it there).
TEST(SafetyVerifierTilt, TheSameSwingFromTheClearancePlaneOverTheAxisPasses) {
  TiltSetup s;
  auto ops = TiltSetup::probePlusX();
  for (const gcode::Op& op : {gcode::Op{gcode::Rapid{std::nullopt, std::nullopt, 113.0}}, gcode::Op{gcode::Rapid{0.0, 0.0, std::nullopt}},
                              gcode::Op{gcode::RotateB{-30}}, gcode::Op{gcode::RotateB{0}}})
    ops.push_back(op);
  const auto r = s.check(s.program(ops));
  EXPECT_TRUE(r.safe()) << reportText(r);
  EXPECT_NE(r.model.find("the table tilts with B about the line through X0.000 Z0.000 along Y"), std::string::npos) << r.model;
}

// At the clearance plane but over the sphere (tip X-139 Z113): the level-table rule let this
// pass (the probe is not below the plane), yet half-way, at B = -15 deg, the sphere's centre is
// at (-135.1, 113.8), where the tip is; at B = -7.6 deg it is at (-148.7, 95.5), 20.0 mm from
// the tip (radii 15 + 3 and the margin).
TEST(SafetyVerifierTilt, TheClearancePlaneOverTheSphereIsNotEnoughForASwing) {
  TiltSetup s;
  auto ops = TiltSetup::probePlusX();
  ops.push_back(gcode::Rapid{std::nullopt, std::nullopt, 113.0});
  ops.push_back(gcode::RotateB{-30});
  const std::string t = s.program(ops);
  const auto r = s.check(t);
  const Finding* f = finding(r, "tilt-swing", lineStarting(t, "G0 B-30"));
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("B moves from 0.000 to -30.000 deg: the table swings the sphere of the artifact"), std::string::npos) << f->what;
  EXPECT_NEAR(angleAt(*f, "B"), -7.6, 0.1) << f->what;
}

// With the table tilted to B = -45 deg the stem leans from (-113.137, 113.137) to (-70.711,
// 155.563) (X, Z) and the sphere sits at (-60.104, 166.170). A positioning probe move along Y
// at the stem's middle (X-91.924 Z134.350) meets the stem; on the level table the same move
// passes 68 mm from the stem's axis. A rapid there is a collision with the stem.
TEST(SafetyVerifierTilt, AMoveIntoTheTiltedStemIsRefused) {
  TiltSetup s;
  const double x = -91.924, z = 134.35;
  std::vector<gcode::Op> to_stem = {gcode::Rapid{100.0, -30.0, 200.0}, gcode::RotateB{-45}, gcode::Rapid{x, -30.0, std::nullopt},
                                    gcode::ProtectedMove{x, -30, z, 1000}};
  auto ops = to_stem;
  ops.push_back(gcode::ProtectedMove{x, 0, z, 1000});
  std::string t = s.program(ops);
  auto r = s.check(t);
  const Finding* f = finding(r, "program-stops");
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("unexpected contact"), std::string::npos) << f->what;
  EXPECT_EQ(finding(r, "tilt-swing"), nullptr) << reportText(r);  // the swing at Z 200 over X100 is clear
  ops = to_stem;
  ops.push_back(gcode::Rapid{x, 0.0, z});
  t = s.program(ops);
  r = s.check(t);
  f = finding(r, "collision", lineStarting(t, "G0 X-91.9240 Y0.0000 Z134.3500"));
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("(the table tilted to B -45.000 deg): the stylus tip of the probe meets the artifact's stem"), std::string::npos)
      << f->what;
  // The stem's surface is 8 mm (its radius and the tip's) from the tip centre at the contact.
  EXPECT_NEAR(f->where_mm.y(), -8, 0.1);
}

// A tilted table under the tip: at B = -30 deg the table surface at X-100 is at Z 57.7; a
// probe waiting at Z 40 there is under it when the swing ends.
TEST(SafetyVerifierTilt, TheProbeMustNotEndBelowTheTiltedTable) {
  TiltSetup s;
  const std::string t = s.program({gcode::Rapid{-100.0, 100.0, std::nullopt}, gcode::ProtectedMove{-100, 100, 40, 1000},
                                   gcode::RotateB{-30}});
  const auto r = s.check(t);
  const Finding* f = finding(r, "tilt-swing", lineStarting(t, "G0 B-30"));
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("the tilting table comes within"), std::string::npos) << f->what;
}

// The A/C machine: A turns the cradle about X (its line through Y0 Z-50). +A (clockwise seen
// from +X) carries the sphere, 125 mm above the line, toward +Y: at A = 20 deg its centre is at
// Y 42.8 Z 67.5, through a tip waiting 7 mm off its +Y side (Y25 Z75). From over the C axis at
// the clearance plane the same swing passes.
TEST(SafetyVerifierTilt, TheCradlesSwingOnTheACMachine) {
  TiltSetup s;
  s.m = parts::loadMachine(source() + "/parts/machines/table_table_ac.yaml");
  std::string t = s.program({gcode::Rapid{-160.0, 25.0, std::nullopt}, gcode::ProtectedMove{-160, 25, 75, 1000}, gcode::RotateA{20}});
  auto r = s.check(t);
  const Finding* f = finding(r, "tilt-swing", lineStarting(t, "G0 A20"));
  ASSERT_NE(f, nullptr) << reportText(r);
  EXPECT_NE(f->what.find("A moves from 0.000 to 20.000 deg: the table swings the sphere of the artifact"), std::string::npos) << f->what;
  EXPECT_NE(f->limit.find("A axis line through Y0.000 Z-50.000 along X"), std::string::npos) << f->limit;
  // The centre, 125 mm from the line, comes toward the tip at 125 mm/rad: the 7 mm gap is down
  // to the 2 mm margin after 5 mm, at 2.3 deg.
  EXPECT_NEAR(angleAt(*f, "A"), 2.3, 0.1) << f->what;
  t = s.program({gcode::Rapid{0.0, 0.0, 113.0}, gcode::RotateA{20}, gcode::Rapid{std::nullopt, std::nullopt, 300.0}});
  r = s.check(t);
  EXPECT_TRUE(r.safe()) << reportText(r);
}

}  // namespace
}  // namespace probeloop::verify
