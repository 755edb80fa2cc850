// The stepped workpiece from stated planes (evaluate/sw_features.hpp): rows written from planes
// known by construction give the widths, depths, tilts, slopes and Oz of the construction (and
// of the point route on points on those planes); the per-point sigma is the largest of the MPE,
// the form over d2(n) and a stated u, each derived by hand below; a missing plane is refused
// naming it, a row that fits nothing is listed.
#include "evaluate/sw_features.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "evaluate/sw_test_support.hpp"

namespace probeloop::evaluate {
namespace {

using Eigen::Vector3d;
using namespace sw_test;

FeatureActual plane(int line, const std::string& id, const Vector3d& p, const Vector3d& n) {
  return feature_test::statedFeature(line, id, "plane", p, n);
}

// The planes of Surfaces s (sw_test_support.hpp's pointsOn), as a CMM would state them; ids
// foreign ("PLN_<line>") when asked.
std::vector<FeatureActual> statedPlanes(const parts::PlanManifest& m, const Surfaces& s, bool foreign = false) {
  std::vector<FeatureActual> rows;
  auto add = [&](const std::string& id, const Vector3d& p, const Vector3d& n) {
    const int line = static_cast<int>(rows.size()) + 2;
    rows.push_back(plane(line, foreign ? "PLN_" + std::to_string(line) : id, p, n));
  };
  add("TOP", {15, 15, 0}, {-s.s_x, -s.s_y, 1});
  const double depth[2] = {9, 19}, top[2] = {0, -9};
  for (int k = 1; k <= 2; ++k) {
    const double h = m.sw.sizes_mm[k - 1] / 2 + s.grow_um * 1e-3, zc = 0.5 * (top[k - 1] - depth[k - 1]);
    const std::string id = "S" + std::to_string(k) + "_";
    add(id + "XP", {15 + h, 15, zc}, {1, 0, -s.tilt});  // x = 15 + h + tilt (z - zc)
    add(id + "XN", {15 - h, 15, zc}, {-1, 0, s.tilt});
    add(id + "YP", {15, 15 + h, zc}, {-s.o, 1, -s.tilt});  // y = 15 + h + o (x - 15) + tilt (z - zc)
    add(id + "YN", {15, 15 - h, zc}, {s.o, -1, s.tilt});
    add(id + "F", {15, 15, -depth[k - 1] + s.floor_um * 1e-3}, {-s.s_x, -s.s_y, 1});
  }
  return rows;
}

PlannedCmmPoints planned(const parts::PlanManifest& m) {
  PlannedCmmPoints out;
  for (const auto& p : pointsOn(m, Surfaces{}, "cmm_points.csv").points) out[p.feature].push_back(p.p_mm);
  return out;
}

Surfaces known() {
  Surfaces s;
  s.grow_um = 2.5;  // each wall 2.5 um out: widths +5 um
  s.tilt = 40e-6;
  s.o = 100e-6;
  s.s_x = 30e-6;
  s.s_y = -20e-6;
  s.floor_um = 3.0;  // depths 3 um short
  return s;
}

TEST(SwFeatures, StatedPlanesGiveTheConstructionAndThePointRoutesGeometry) {
  const auto m = twoSteps();
  const auto s = known();
  const auto points = steppedGeometry(m, pointsOn(m, s, "cmm.csv"), "cmm");
  for (bool foreign : {false, true}) {
    const auto c = swCmmFromFeatures(m, statedPlanes(m, s, foreign), planned(m), "f.csv", "features");
    EXPECT_EQ(c.from.assigned_by, foreign ? "nominal geometry" : "labels");
    EXPECT_EQ(c.from.planes.size(), 11u);
    ASSERT_EQ(c.geometry.steps.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
      const auto &f = c.geometry.steps[i], &p = points.steps[i];
      EXPECT_NEAR(f.width_x_error_um(), 5.0, 1e-6);
      EXPECT_NEAR(f.width_y_error_um(), 5.0, 1e-6);
      EXPECT_NEAR(f.depth_error_um(), -3.0, 1e-6);
      EXPECT_NEAR(f.lean_x_urad, 40.0, 1e-3);
      EXPECT_NEAR(f.lean_y_urad, 40.0, 1e-3);
      EXPECT_NEAR(f.floor_slope_x_urad, 30.0, 1e-3);
      EXPECT_NEAR(f.floor_slope_y_urad, -20.0, 1e-3);
      EXPECT_NEAR(f.oz_urad, std::atan(100e-6) * 1e6, 0.05);
      EXPECT_NEAR(f.width_x_mm, p.width_x_mm, 1e-9);
      EXPECT_NEAR(f.depth_mm, p.depth_mm, 1e-9);
      EXPECT_NEAR(f.oz_urad, p.oz_urad, 1e-6);
    }
  }
}

TEST(SwFeatures, PerPointSigmaIsTheLargestOfMpeFormAndStatedU) {
  const auto m = twoSteps();  // MPE 1.5 + L/333 um
  auto rows = statedPlanes(m, known());
  // S1_XP (row 2): form 6 um of 24 points. d2(24) = 3.895 (ASTM E2587): sigma = 6 / (3.895
  // sqrt(21/24)) = 1.6468 um, above MPE(L)/sqrt 3 at its centroid (L = 33.84 mm: 0.9247 um).
  rows[1].form_um = 6.0;
  rows[1].n_points = 24;
  // S1_XN (row 3): u = (0.6, 0.1, 0.1) um stated, n not stated (the plan's 6): along the normal
  // (-1, 0, 4e-5) 0.6 um, i.e. 0.6 sqrt 6 = 1.4697 um per point, above MPE/sqrt 3 (0.893 um).
  rows[2].u_um = Vector3d(0.6, 0.1, 0.1);
  const auto c = swCmmFromFeatures(m, rows, planned(m), "f.csv", "features");
  const auto& xp = c.from.planes[1];
  const auto& xn = c.from.planes[2];
  const auto& yp = c.from.planes[3];
  EXPECT_EQ(xp.sigma_from, "form");
  EXPECT_NEAR(xp.sigma_um, 6.0 / (3.895 * std::sqrt(21.0 / 24)), 2e-3);
  EXPECT_EQ(xn.sigma_from, "stated u");
  EXPECT_NEAR(xn.sigma_um, 0.6 * std::sqrt(6.0), 1e-6);
  // S1_YP: nothing stated: the MPE at its centroid (15, 30.0025, -4.5): L = 33.84 mm.
  EXPECT_EQ(yp.sigma_from, "MPE");
  EXPECT_NEAR(yp.sigma_um, (1.5 + std::sqrt(15.0 * 15 + 30.0025 * 30.0025 + 4.5 * 4.5) / 333) / std::sqrt(3.0), 1e-6);
  // The width's u: each plane's sigma over sqrt(n), n never above the plan's 6 (24 stated: a
  // scan's points are correlated and the MPE does not average down): 1.6468 / sqrt 6 and the
  // stated 0.6.
  const auto& st = c.geometry.steps[0];
  EXPECT_NEAR(st.u_wall_x_um, std::hypot(xp.sigma_um / std::sqrt(6.0), 0.6), 1e-6);
  // The wall tilt's u: the planned layout (z at zc +- 3 mm, twice each of 3 places: M_zz = 54
  // mm^2), sigma scaled by sqrt(n_planned / min(n_stated, n_planned)) = 1 for both.
  EXPECT_NEAR(st.u_lean_x_urad, 0.5 * std::hypot(xp.sigma_um, xn.sigma_um) * 1e-3 / std::sqrt(54.0) * 1e6, 1e-6);
  // The form's sigma carries the dof of a range of 24: 1/2 (d2/d3)^2 = 1/2 (3.895/0.712)^2 =
  // 14.96 (ASTM E2587's d2, d3; below the fit's 21): k = t(0.975, 14.96) = 2.131; the stated u
  // and the MPE none.
  EXPECT_NEAR(st.U_lean_x_urad / st.u_lean_x_urad, 2.131, 2e-3);
  EXPECT_NE(c.geometry.stated_basis.find("from the stated features"), std::string::npos);
}

TEST(SwFeatures, AMissingPlaneIsRefusedAndAForeignRowThatFitsNothingIsListed) {
  const auto m = twoSteps();
  auto rows = statedPlanes(m, known());
  rows.push_back(plane(40, "DATUM_B", {15, 15, 50}, {0, 0, 1}));  // 50 mm above the top
  const auto c = swCmmFromFeatures(m, rows, planned(m), "f.csv", "features");
  ASSERT_EQ(c.from.unmatched.size(), 1u);
  EXPECT_NE(c.from.unmatched[0].find("f.csv:40: plane 'DATUM_B' (nearest TOP, 50 mm: off its plane by 50 mm (at most 0.5))"), std::string::npos)
      << c.from.unmatched[0];
  rows.erase(rows.begin() + 10);  // S2_F
  try {
    swCmmFromFeatures(m, rows, planned(m), "f.csv", "features");
    FAIL() << "a missing floor was accepted";
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("f.csv"), std::string::npos) << w;
    EXPECT_NE(w.find("feature S2_F (floor): not in the file"), std::string::npos) << w;
    EXPECT_NE(w.find("step 2's depth"), std::string::npos) << w;
    EXPECT_NE(w.find("DATUM_B"), std::string::npos) << w;  // the row that fits nothing is named with it
  }
}

TEST(SwFeatures, PlannedPointsAndTheRouteChoice) {
  const auto p = plannedCmmPointsCsv("# plan\nfeature,point,x_mm,y_mm,z_mm,nx,ny,nz\nTOP,1,1,2,0,0,0,1\nTOP,2,3,4,0,0,0,1\nS1_F,1,5,6,-9,0,0,1\n",
                                     "cmm_points.csv");
  ASSERT_EQ(p.at("TOP").size(), 2u);
  EXPECT_EQ(p.at("TOP")[1], Vector3d(3, 4, 0));
  EXPECT_THROW(plannedCmmPointsCsv("feature,x_mm,y_mm\nTOP,1,2\n", "c.csv"), InputError);
  interop::CmmDocument d;
  d.features.emplace_back();
  EXPECT_FALSE(holdsOnlyFeatures(d));  // no measured geometry: nothing to evaluate from
  d.features[0].measured.given = true;
  EXPECT_TRUE(holdsOnlyFeatures(d));
  d.features.emplace_back();
  d.features[1].points.emplace_back();
  EXPECT_FALSE(holdsOnlyFeatures(d));  // points: the point route
}

}  // namespace
}  // namespace probeloop::evaluate
