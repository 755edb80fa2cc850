// Safety by construction of the sphere cycle, checked on the op sequence itself.
#include "planner/sphere_cycle.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "parts/piece_kinds.hpp"
#include "verify/safety.hpp"

using namespace probeloop;
using namespace probeloop::planner;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;
parts::SphereArtifact artifact() { return parts::loadSphereArtifact(src + "/parts/sphere_artifact.yaml"); }
parts::Machine machine() { return parts::loadMachine(src + "/parts/machines/nmv5000.yaml"); }
}  // namespace

TEST(SphereCycle, RetractsToClearancePlaneBeforeEveryCMove) {
  const auto a = artifact();
  const auto plan = planSphereCycle(a, machine());
  const double z_clear = plan.manifest.spheres[0].nominal_centre_mm.z() + a.sphereRadius() + 3.0 + a.clearance_mm;
  std::optional<double> z;
  int c_moves = 0;
  for (const auto& op : plan.program.cycle_body) {
    if (auto* r = std::get_if<gcode::Rapid>(&op); r && r->z) z = *r->z;
    if (std::get_if<gcode::ProtectedMove>(&op)) z = std::get<gcode::ProtectedMove>(op).z;
    if (std::get_if<gcode::RotateC>(&op)) {
      ++c_moves;
      ASSERT_TRUE(z.has_value());
      EXPECT_DOUBLE_EQ(*z, z_clear);
    }
  }
  EXPECT_EQ(c_moves, 5);
}

TEST(SphereCycle, EveryProbeMoveIsReachedByAProtectedMoveAndLeftToClearance) {
  const auto plan = planSphereCycle(artifact(), machine());
  const auto& body = plan.program.cycle_body;
  int probes = 0;
  for (size_t i = 0; i < body.size(); ++i) {
    if (!std::get_if<gcode::ProbeMove>(&body[i])) continue;
    ++probes;
    ASSERT_GE(i, 1u);
    EXPECT_TRUE(std::get_if<gcode::ProtectedMove>(&body[i - 1])) << "op " << i;
    ASSERT_LT(i + 2, body.size());
    const auto* back = std::get_if<gcode::Rapid>(&body[i + 1]);
    const auto* up = std::get_if<gcode::Rapid>(&body[i + 2]);
    ASSERT_TRUE(back && up);
    EXPECT_TRUE(up->z && !up->x && !up->y);  // straight up to the clearance plane
  }
  EXPECT_EQ(probes, 25);
  EXPECT_EQ(plan.manifest.points.size(), 25u);
}

TEST(SphereCycle, ProbeTravelIsBoundedByOvertravel) {
  const auto a = artifact();
  const auto plan = planSphereCycle(a, machine());
  size_t k = 0;
  for (const auto& op : plan.program.cycle_body) {
    const auto* p = std::get_if<gcode::ProbeMove>(&op);
    if (!p) continue;
    const auto& mp = plan.manifest.points[k++];
    const Eigen::Vector3d end(p->x, p->y, p->z);
    EXPECT_NEAR((end - mp.contact_mm).norm(), a.overtravel_mm, 1e-9);
    EXPECT_NEAR((end - mp.contact_mm).normalized().dot(mp.approach), 1.0, 1e-12);
  }
}

TEST(SphereCycle, PositionsFollowTheThesisLayoutOnACPrimeAxis) {
  const auto plan = planSphereCycle(artifact(), machine());
  const auto& s = plan.manifest.spheres;
  // C = 0/90/180/270 on a C' axis (table clockwise for +C): -X, +Y, +X, -Y, then -X again.
  EXPECT_NEAR(s[0].nominal_centre_mm.x(), -160, 1e-9);
  EXPECT_NEAR(s[1].nominal_centre_mm.y(), 160, 1e-9);
  EXPECT_NEAR(s[2].nominal_centre_mm.x(), 160, 1e-9);
  EXPECT_NEAR(s[3].nominal_centre_mm.y(), -160, 1e-9);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s[k].formula_index, k + 1);
  EXPECT_EQ(s[4].repeat_of, 1);
  EXPECT_EQ(s[4].formula_index, 0);
}

TEST(SphereCycle, CounterclockwiseTableRemapsFormulaIndices) {
  auto m = machine();
  m.c.positive_is_clockwise = false;
  const auto plan = planSphereCycle(artifact(), m);
  // C = 90 now puts the sphere at -Y (formula index 4), C = 270 at +Y (index 2).
  EXPECT_EQ(plan.manifest.spheres[1].formula_index, 4);
  EXPECT_EQ(plan.manifest.spheres[3].formula_index, 2);
}

TEST(SphereCycle, OutsideTravelIsRefusedWithTheMoveAndAxis) {
  auto a = artifact();
  a.radius_from_axis_mm = 350;  // probe start at X = -350 - 21 on a +-365 mm machine
  try {
    planSphereCycle(a, machine());
    FAIL() << "planned outside travel";
  } catch (const SafetyError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("position 1"), std::string::npos) << m;
    EXPECT_NE(m.find("outside the X travel"), std::string::npos) << m;
  }
}

TEST(SphereCycle, CycleTimeIsTheSumOfItsMoves) {
  // Independent arithmetic for the NMV 5000 defaults, a cycle after the first: 2 tool changes
  // of 6 s; C back from 360 to 0, then 90+90+90+90 deg, at 16.66 rpm = 99.96 deg/s; 25 probing
  // moves of 3 mm at 200 mm/min.
  const auto t = planSphereCycle(artifact(), machine()).cycle_time;
  EXPECT_NEAR(t.tool_change_s, 12.0, 1e-12);
  EXPECT_NEAR(t.c_index_s, 720.0 / 99.96, 1e-9);
  EXPECT_NEAR(t.probing_s, 25 * 3.0 / (200.0 / 60.0), 1e-9);
}

// The schedule: each later cycle starts a cycle and a gap after the previous one, the cycle with
// its C return; tool changes outside the loop are not in it, and the first cycle's points count
// the probe-in change before them.
TEST(SphereCycle, TheScheduleHoldsTheCReturnAndOnlyTheToolChangesThatHappen) {
  auto a = artifact();
  const auto in_loop = planSphereCycle(a, machine());
  const auto& m1 = in_loop.manifest;
  ASSERT_GE(m1.cycles, 3);
  const double T1 = in_loop.cycle_time.total();
  EXPECT_DOUBLE_EQ(m1.cycle_time_s, T1);
  EXPECT_NEAR(m1.cycle_start_s[1] - m1.cycle_start_s[0], T1 + a.gap_s, 1e-9);
  EXPECT_NEAR(m1.cycle_start_s[2] - m1.cycle_start_s[1], T1 + a.gap_s, 1e-9);
  a.tool_change_each_cycle = false;
  const auto outside = planSphereCycle(a, machine());
  EXPECT_EQ(outside.cycle_time.tool_change_s, 0.0);
  EXPECT_NEAR(outside.cycle_time.c_index_s, 720.0 / 99.96, 1e-9);
  EXPECT_NEAR(outside.manifest.cycle_start_s[1], outside.cycle_time.total() + a.gap_s, 1e-9);
  // The first point of the first cycle comes after the probe-in change (6 s), the first of a
  // later cycle after the C return: both at cycle_start + time_in_cycle on one clock.
  EXPECT_GT(outside.manifest.points[0].time_in_cycle_s, 6.0);
}

// The live interval (cycles.live_interval): the wait between cycles is read from outside while
// the program runs. The expected blocks are written out here by hand from the design (Fanuc
// #500 into #101 inside DO2; LinuxCNC M66 E0 L0 into #<_pl_wait>), not taken from the writer.
namespace {
const std::string kFanucWait =
    "IF [#100 GE 12] GOTO 10\n"
    "#101=#500\n"
    "WHILE [#101 GT 0] DO2\n"
    "IF [#101 GT 60.000] THEN #101=60.000\n"
    "G4 X#101\n"
    "#101=#500\n"
    "END2\n"
    "N10 #100=#100+1\n"
    "END1\n";
const std::string kLinuxCncWait =
    "o101 if [#<_pl_cycle> LT 12]\n"
    "M66 E0 L0\n"
    "#<_pl_wait> = #5399\n"
    "o102 while [#<_pl_wait> GT 0]\n"
    "o103 if [#<_pl_wait> GT 60.000]\n"
    "#<_pl_wait> = 60.000\n"
    "o103 endif\n"
    "G4 P#<_pl_wait>\n"
    "M66 E0 L0\n"
    "#<_pl_wait> = #5399\n"
    "o102 endwhile\n"
    "o101 endif\n";
parts::Machine linuxCncMill() { return parts::loadMachine(src + "/parts/machines/linuxcnc_rotary_mill.yaml"); }

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++n;
  return n;
}
}  // namespace

TEST(SphereCycle, TheLiveIntervalReplacesTheFixedDwellInBothDialects) {
  auto a = artifact();
  a.live_interval = true;
  const auto fa = programText(planSphereCycle(a, machine()), parts::Dialect::FanucMacroB);
  const auto lc = programText(planSphereCycle(a, linuxCncMill()), parts::Dialect::LinuxCnc);
  EXPECT_EQ(count(fa, kFanucWait), 1u) << fa;
  EXPECT_EQ(count(lc, kLinuxCncWait), 1u) << lc;
  EXPECT_EQ(count(fa, "G4 X300.000"), 0u);  // the nominal gap is not dwelt
  EXPECT_EQ(count(lc, "G4 P300.000"), 0u);
  // The header says where the value comes from, that 0 runs the cycles back to back and that
  // the schedule is nominal.
  EXPECT_NE(fa.find("(MEASUREMENT INTERVAL: LIVE, FROM COMMON VARIABLE #500 [WRITTEN BY FOCAS CNC_WRMACRO]"),
            std::string::npos) << fa;
  EXPECT_NE(lc.find("(measurement interval: live, from HAL analog input 0 [M66 E0 L0 -> #5399]"), std::string::npos)
      << lc;
  for (const auto* t : {&fa, &lc}) {
    EXPECT_EQ(count(*t, "back to back") + count(*t, "BACK TO BACK"), 1u);
    EXPECT_EQ(count(*t, "nominal gap 300 s") + count(*t, "NOMINAL GAP 300 S"), 1u);
  }
  // The manifest's schedule stays the nominal one, with the gap.
  const auto fixed = planSphereCycle(artifact(), machine());
  EXPECT_EQ(planSphereCycle(a, machine()).manifest.cycle_start_s, fixed.manifest.cycle_start_s);
  // Without the option: the fixed dwell, and nothing of the live interval.
  const auto fa0 = programText(fixed, parts::Dialect::FanucMacroB);
  EXPECT_EQ(count(fa0, "G4 X300.000"), 1u);
  EXPECT_EQ(count(fa0, "#500"), 0u);
  EXPECT_EQ(count(programText(planSphereCycle(artifact(), linuxCncMill()), parts::Dialect::LinuxCnc), "M66"), 0u);
}

// LinuxCNC's LOG has no clock: the live program reads HAL analog input 1 after every probing
// move and logs it as the eighth field; the fixed program logs the six fields only.
TEST(SphereCycle, TheLiveLinuxCncProgramLogsTheClockOfAnalogInputOneWithEveryPoint) {
  auto a = artifact();
  a.live_interval = true;
  const auto lc = programText(planSphereCycle(a, linuxCncMill()), parts::Dialect::LinuxCnc);
  const std::size_t probes = count(lc, "G38.2 ");
  EXPECT_EQ(probes, 25u);
  EXPECT_EQ(count(lc, "\nM66 E1 L0\n(LOG,PT #<_pl_cycle> "), probes) << lc;
  EXPECT_EQ(count(lc, " #5061 #5062 #5063 #5399)\n"), probes);
  EXPECT_NE(lc.find("(point times: HAL analog input 1"), std::string::npos);
  const auto fixed = programText(planSphereCycle(artifact(), linuxCncMill()), parts::Dialect::LinuxCnc);
  EXPECT_EQ(count(fixed, " #5061 #5062 #5063)\n"), 25u);
  EXPECT_EQ(count(fixed, "#5399"), 0u);
}

// `plan` and `probeloop check` run the safety verifier on the program text: with nothing
// writing the value (0) the wait loop is not entered, and no block of it is refused.
TEST(SphereCycle, TheLiveProgramsPassTheSafetyVerifier) {
  auto a = artifact();
  a.live_interval = true;
  const auto piece = parts::loadTestPiece(src + "/parts/sphere_artifact.yaml");
  const auto fa = verify::checkPrograms(
      {{"sphere_cycle.nc", programText(planSphereCycle(a, machine()), parts::Dialect::FanucMacroB)}}, machine(), piece);
  EXPECT_TRUE(fa.safe()) << fa.findings.front().file << ":" << fa.findings.front().line << " " << fa.findings.front().what;
  const auto lc = verify::checkPrograms(
      {{"sphere_cycle.ngc", programText(planSphereCycle(a, linuxCncMill()), parts::Dialect::LinuxCnc)}}, linuxCncMill(),
      piece);
  EXPECT_TRUE(lc.safe()) << lc.findings.front().file << ":" << lc.findings.front().line << " " << lc.findings.front().what;
}

// LinuxCNC's own interpreter (rs274, linuxcnc-uspace; scripts/setup.sh installs it) runs the
// live program to its end. Standalone it reads analog inputs as 0, so it never dwells: every
// cycle's probe moves follow back to back, where the fixed program dwells 11 times.
TEST(SphereCycle, Rs274RunsTheLiveLinuxCncProgram) {
  namespace fs = std::filesystem;
  ASSERT_EQ(std::system("command -v rs274 >/dev/null 2>&1"), 0)
      << "LinuxCNC's rs274 is not installed (linuxcnc-uspace; run scripts/setup.sh)";
  const fs::path dir = fs::temp_directory_path() / ("probeloop_live_rs274_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // rs274 standalone reads tool lengths in inches: the probe's 150 mm.
  std::ofstream(dir / "tool.tbl") << "T99 P99 Z5.905511811 D0.236220472 ;probe\n";
  auto canon = [&](bool live) {
    auto a = artifact();
    a.live_interval = live;
    std::ofstream(dir / "cycle.ngc") << programText(planSphereCycle(a, linuxCncMill()), parts::Dialect::LinuxCnc);
    const std::string cmd = "cd '" + dir.string() + "' && rs274 -t tool.tbl -g cycle.ngc > canon.txt 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::stringstream s;
    s << std::ifstream(dir / "canon.txt").rdbuf();
    return s.str();
  };
  const std::string live = canon(true), fixed = canon(false);
  fs::remove_all(dir);
  EXPECT_NE(live.find("PROGRAM_END()"), std::string::npos) << live.substr(live.size() > 2000 ? live.size() - 2000 : 0);
  EXPECT_EQ(count(live, "STRAIGHT_PROBE("), 2u * 25u * 12u);  // protected + measuring move per point
  EXPECT_EQ(count(live, "LOG(\"PT "), 25u * 12u);
  EXPECT_EQ(count(live, "DWELL("), 0u);
  EXPECT_EQ(count(fixed, "DWELL(300.0000)"), 11u);
}
