// Safety by construction of the sphere cycle, checked on the op sequence itself.
#include "planner/sphere_cycle.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"

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
