// The stepped workpiece's geometry and separation from one part (evaluate/stepped_workpiece.hpp)
// on points placed exactly on planes whose widths, depths, tilts and squareness are known by
// construction (hand derivations in the comments); the truth recovery on the virtual machine is
// tests/integration/sw_separation.py.
#include "evaluate/stepped_workpiece.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "evaluate/sw_test_support.hpp"

namespace probeloop::evaluate {
namespace {

using Eigen::Vector3d;

using namespace sw_test;

TEST(SteppedWorkpieceGeometry, WidthsDepthsTiltsAndSquarenessOfKnownPlanes) {
  const auto m = twoSteps();
  Surfaces s;
  s.grow_um = 2.5;     // each wall 2.5 um out: widths +5 um
  s.tilt = 40e-6;      // dx/dz (and dy/dz) of every wall
  s.o = 100e-6;        // Y walls y = c + o (x - 15): Oz = atan(o)
  s.s_x = 30e-6;       // floors and top dz/dx
  s.s_y = -20e-6;
  s.floor_um = 3.0;    // floors 3 um high: depths 3 um short
  const auto g = steppedGeometry(m, pointsOn(m, s, "cmm.csv"), "cmm");
  ASSERT_EQ(g.steps.size(), 2u);
  for (const auto& st : g.steps) {
    EXPECT_NEAR(st.width_x_error_um(), 5.0, 1e-6) << st.step;
    EXPECT_NEAR(st.width_y_error_um(), 5.0, 1e-6) << st.step;
    EXPECT_NEAR(st.depth_error_um(), -3.0, 1e-6) << st.step;
    EXPECT_NEAR(st.lean_x_urad, 40.0, 1e-3) << st.step;
    // the Y walls' dy/dz: tilt (the turn about Z does not incline them)
    EXPECT_NEAR(st.lean_y_urad, 40.0, 1e-3) << st.step;
    EXPECT_NEAR(st.floor_slope_x_urad, 30.0, 1e-3) << st.step;
    EXPECT_NEAR(st.floor_slope_y_urad, -20.0, 1e-3) << st.step;
    // outward normals (1, 0, .) and (-o, 1, .): the angle between them 90 deg + atan(o)
    EXPECT_NEAR(st.oz_urad, std::atan(100e-6) * 1e6, 0.05) << st.step;
    EXPECT_NEAR(st.u_wall_x_um, 0.0, 1e-6);  // exact planes: no residuals
  }
}

// A machine whose X axis is long by c (a scale error about the steps' centre, x_real = x +
// c (x - 15)) cuts each X wall with the tool's centre at h + r_tool from the centre and the tool
// pushed delta/2 outward: the walls stand at 15 +- (h + c (h + r_tool) + delta/2), which the
// CMM sees. The probe's ball touches each wall from outside with the same long axis: it reports
// the surface where its commanded centre, made long by c, meets the wall, minus its radius.
// Solved exactly here (not to first order), so:
//   CMM - probe = c (width + d_probe) -> k = c (every step alike),
//   probe width error = delta + c (d_tool - d_probe) (first order) -> e_proc = delta.
TEST(SteppedWorkpieceSeparation, PositionErrorAndProcessErrorOfALongAxis) {
  auto m = twoSteps();
  const double c = 0.2e-3, r_tool = 5, r_probe = 1;
  const double delta_mm[2] = {3e-3, 5e-3};
  TtpPoints cmm = pointsOn(m, {}, "cmm.csv"), probe = pointsOn(m, {}, "probe.log");
  for (auto* t : {&cmm, &probe})
    for (auto& p : t->points) {
      const int k = p.feature.rfind("S1_", 0) == 0 ? 0 : p.feature.rfind("S2_", 0) == 0 ? 1 : -1;
      const bool xp = p.feature.find("XP") != std::string::npos, xn = p.feature.find("XN") != std::string::npos;
      if (k < 0 || !(xp || xn)) continue;
      const double h = m.sw.sizes_mm[static_cast<std::size_t>(k)] / 2, side = xp ? 1.0 : -1.0;
      const double wall = 15 + side * (h + c * (h + r_tool) + delta_mm[k] / 2);  // as cut
      if (t == &cmm) {
        p.p_mm.x() = wall;
      } else {
        const double centre = (wall + side * r_probe + 15 * c) / (1 + c);  // commanded, the real one touching
        p.p_mm.x() = centre - side * r_probe;
      }
    }
  const auto e = evaluateSteppedWorkpiece(m, cmm, probe);
  ASSERT_EQ(e.steps.size(), 2u);
  EXPECT_NEAR(e.k_pos_x_um_per_mm.value, c * 1e3, 1e-4);  // to second order in c (c^2 = 4e-5 um/mm)
  for (int k = 0; k < 2; ++k) {
    const double size = m.sw.sizes_mm[static_cast<std::size_t>(k)];
    EXPECT_NEAR(e.steps[static_cast<std::size_t>(k)].e_pos_x_um.value, c * (size + 2 * r_probe) * 1e3, 0.01) << k;
    EXPECT_NEAR(e.steps[static_cast<std::size_t>(k)].e_proc_x_um.value, delta_mm[k] * 1e3, 0.01) << k;
    // The CMM error a re-cut is predicted to have: c (size + d_tool) + delta.
    EXPECT_NEAR(e.steps[static_cast<std::size_t>(k)].predicted_width_x_um.value, (c * (size + 2 * r_tool) + delta_mm[k]) * 1e3, 0.01) << k;
    EXPECT_NEAR(e.steps[static_cast<std::size_t>(k)].e_pos_y_um.value, 0.0, 1e-6);
  }
  EXPECT_EQ(e.probe_repeat_pairs, 0);  // no repeats: the manifest's 2 sigma / 2
  EXPECT_DOUBLE_EQ(e.probe_repeatability_um, 1.0);
  // u(k) holds the part's temperature whole (alpha x 1 K / sqrt 3 on the machine, 0.5 K at the
  // CMM), which the steps' scatter cannot reveal.
  const double alpha = 23.4e-3;  // um per mm per K
  EXPECT_GT(e.k_pos_x_um_per_mm.u_c, std::hypot(alpha / std::sqrt(3.0), alpha * 0.5 / std::sqrt(3.0)) - 1e-12);
}

TEST(SteppedWorkpieceSeparation, RepeatabilityFromRepeatedPlannedPoints) {
  auto m = twoSteps();
  parts::ManifestPoint a;
  a.feature = "S1_XP";
  a.point = 1;
  a.contact_mm = {31, 15, -4};
  a.approach = -Vector3d::UnitX();
  parts::ManifestPoint b = a;
  b.point = 2;  // the same place again
  m.points = {a, b};
  TtpPoints t;
  t.points.push_back({"S1_XP", 1, 1, {30.0, 15, -4}});
  t.points.push_back({"S1_XP", 2, 2, {30.0 + 1.2e-3, 15, -4}});
  const auto r = probeRepeatability(m, t);
  EXPECT_EQ(r.pairs, 1);
  EXPECT_NEAR(r.s_um, 1.2 / std::sqrt(2.0), 1e-9);  // s of one point from one difference d: |d| / sqrt 2
  // A third touch of the same place: 2 degrees of freedom, s from the deviations from the mean
  // (0, 1.2, 0.3 um: mean 0.5, squares 0.25 + 0.49 + 0.04 = 0.78, s = sqrt(0.78 / 2)).
  parts::ManifestPoint c3 = a;
  c3.point = 3;
  m.points.push_back(c3);
  t.points.push_back({"S1_XP", 3, 3, {30.0 + 0.3e-3, 15, -4}});
  const auto r3 = probeRepeatability(m, t);
  EXPECT_EQ(r3.pairs, 2);
  EXPECT_NEAR(r3.s_um, std::sqrt(0.78 / 2), 1e-9);
}

TEST(SteppedWorkpieceSeparation, MissingFeaturesAndOtherKindsAreRefused) {
  auto m = twoSteps();
  TtpPoints t = pointsOn(m, {}, "cmm.csv");
  std::erase_if(t.points, [](const TtpPoint& p) { return p.feature == "S2_YN"; });
  try {
    steppedGeometry(m, t, "cmm");
    FAIL() << "accepted a step without its -Y wall";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cmm.csv: feature S2_YN: no points measured"), std::string::npos) << e.what();
  }
  m.kind = "thermal_test_piece";
  EXPECT_THROW(evaluateSteppedWorkpiece(m, t, t), InputError);
}

}  // namespace
}  // namespace probeloop::evaluate
