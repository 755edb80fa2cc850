// The location-error budget, each term against an independent derivation, and seed 004
// Table 5.3's 3D root-sum-square.
#include "evaluate/location_budget.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"

using namespace probeloop;
using evaluate::CycleBudgetInput;

namespace {

// The thesis layout by hand: positions 1-4 at -X, +Y, +X, -Y, d/2 = 160 mm.
parts::PlanManifest thesis() {
  parts::PlanManifest m;
  const double ang[4] = {180, 90, 0, 270};
  for (int k = 0; k < 4; ++k) {
    parts::ManifestSphere s;
    s.position = k + 1;
    s.angle_deg = ang[k];
    s.nominal_centre_mm = {160 * std::cos(degToRad(ang[k])), 160 * std::sin(degToRad(ang[k])), 75};
    s.formula_index = k + 1;
    m.spheres.push_back(s);
  }
  m.radius_from_axis_mm = 160;
  m.sphere_radius_mm = 15;
  m.probe_repeatability_2sigma_um = 0;
  m.coordinate_resolution_mm = 0;
  return m;
}

evaluate::LocationLeastSquares estimator() { return evaluate::LocationLeastSquares({180, 90, 0, 270}, 160); }

CycleBudgetInput quietCycle() {
  CycleBudgetInput c;
  for (int k = 0; k < 4; ++k) c.centre_cov_unscaled.push_back(Eigen::Matrix3d::Zero()), c.tau_s.push_back(0);
  return c;
}

double contribution(const uncertainty::Budget& b, const std::string& starts_with) {
  double u = 0;
  for (const auto& c : b.contributions)
    if (c.input.rfind(starts_with, 0) == 0) u = std::max(u, c.u);
  return u;
}

TEST(LocationBudget, ToolChangeMovesOnlyTheTranslations) {
  auto m = thesis();
  m.tool_change_each_cycle = true;
  m.probe_tool_change_repeatability_2sigma_um = 1.5;
  const auto b = evaluate::locationErrorBudgets(estimator(), m, quietCycle(), quietCycle(), {}, {}, 2.0);
  // A rigid translation t of all centres is read as EX, EY, EZ = t exactly (Eqs. 5.4-5.6 are
  // means) and leaves ER, EA, EB, EC at 0: u = sigma per cycle, sqrt 2 sigma for two cycles.
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(contribution(b[j], "tool-change repeatability, this cycle"), 0.75, 1e-12);
    EXPECT_NEAR(b[j].u_c, 0.75 * std::sqrt(2.0), 1e-12);
  }
  for (int j = 3; j < 7; ++j) EXPECT_NEAR(b[j].u_c, 0, 1e-12);
  m.probe_tool_change_repeatability_2sigma_um = NAN;  // not stated: listed, 0, says where
  const auto n = evaluate::locationErrorBudgets(estimator(), m, quietCycle(), quietCycle(), {}, {}, 2.0);
  bool said = false;
  for (const auto& c : n[0].contributions) said = said || c.basis.find("not stated") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(LocationBudget, ArtifactExpansionAndRadiusTerms) {
  auto m = thesis();
  m.sphere_centre_height_mm = 75;
  m.artifact_alpha_um_per_m_K = 11.5;
  m.artifact_temperature_change_half_width_K = 1;
  m.radius_from_axis_u_mm = 0.16;
  const std::array<double, 7> values = {1, 2, 3, 4, 10, -20, 30};
  const auto b = evaluate::locationErrorBudgets(estimator(), m, quietCycle(), quietCycle(), values, {}, 2.0);
  // 11.5 um/(m K) x (75 + 15) mm x 1 K / sqrt 3 = 0.5976 um, on EZ0T only.
  EXPECT_NEAR(b[2].u_c, 11.5e-3 * 90 / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(b[0].u_c, 0, 1e-15);
  // Angles are displacements over d: u = |E| u(d/2) / (d/2) = |E| x 1e-3.
  EXPECT_NEAR(b[4].u_c, 10e-3, 1e-15);
  EXPECT_NEAR(b[5].u_c, 20e-3, 1e-15);
  EXPECT_NEAR(b[6].u_c, 30e-3, 1e-15);
  EXPECT_NEAR(b[3].u_c, 0, 1e-15);
}

TEST(LocationBudget, DriftDuringTheCycleFollowsTheProbingTimes) {
  const auto m = thesis();
  auto c = quietCycle();
  const double t = 30;  // s: positions probed at -t, -t/3, t/3, t from the cycle's mean time
  c.tau_s = {-t, -t / 3, t / 3, t};
  c.rate_known = true;
  const double r = 0.01;  // um/s of EX0C only
  c.rate_per_s = {r, 0, 0, 0, 0, 0, 0};
  auto steady_ref = quietCycle();
  steady_ref.rate_known = true;  // the reference cycle saw no drift
  const auto b = evaluate::locationErrorBudgets(estimator(), m, c, steady_ref, {}, {}, 2.0);
  // By Eqs. 5.4-5.10: EX0C = mean x -> bias r mean(tau) = 0; EC0C = (y1 + x2 - y3 - x4)/(2d)
  // -> bias r (tau2 - tau4) / (2 d) with d = 0.32 m, in urad; ER0T = (x3 - x1 + ...)/4
  // -> r (tau3 - tau1) / 4. Rectangular: u = |bias| / sqrt 3.
  EXPECT_NEAR(contribution(b[0], "drift during the cycle"), 0, 1e-12);
  EXPECT_NEAR(contribution(b[6], "drift during the cycle"), std::fabs(r * (-t / 3 - t) / (2 * 0.32)) / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(contribution(b[3], "drift during the cycle"), std::fabs(r * (t / 3 + t) / 4) / std::sqrt(3.0), 1e-12);
  // E = W (c_i - c_ref): the same drift, probed with the same timing in the reference cycle,
  // gives the same false errors there, and they cancel.
  const auto same = evaluate::locationErrorBudgets(estimator(), m, c, c, {}, {}, 2.0);
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(contribution(same[j], "drift during the cycle"), 0, 1e-12);
}

TEST(LocationBudget, ProbeScatterUsesTheLargerOfTypeAAndTypeB) {
  auto m = thesis();
  m.probe_repeatability_2sigma_um = 1.0;
  auto c = quietCycle();
  for (auto& cov : c.centre_cov_unscaled) cov = Eigen::Matrix3d::Identity() * 0.25;  // each centre coordinate: sigma/2
  evaluate::PointScatter ps;
  ps.type_b_sigma_mm = 0.5e-3;
  ps.type_a_sigma_mm = 0.8e-3;
  ps.type_a_dof = 60;
  const auto b = evaluate::locationErrorBudgets(estimator(), m, c, c, {}, ps, 2.0);
  // EX0C = mean of 4 x-coordinates: u = (sigma/2) / 2 per cycle, two cycles.
  EXPECT_NEAR(b[0].u_c, 0.8 / 4 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(b[0].nu_eff, 60, 1e-9);  // one s (nu = 60) serves both cycles: counted once
  ps.type_a_sigma_mm = 0.3e-3;
  const auto bb = evaluate::locationErrorBudgets(estimator(), m, c, c, {}, ps, 2.0);
  EXPECT_NEAR(bb[0].u_c, 0.5 / 4 * std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(std::isinf(bb[0].nu_eff));
}

TEST(LocationBudget, PlannerPredictsFromTheNominalPoints) {
  // Five points (4 on the equator, 1 on top) of a sphere of radius rho: the known-radius fit's
  // (J^T J)^-1 is diag(1/2, 1/2, 1) for the centre, so EX0C = mean of 4 x has u = sigma
  // sqrt(1/2) / 2 per cycle.
  auto m = thesis();
  m.probe_repeatability_2sigma_um = 1.0;
  m.tip_radius_mm = 3;
  for (const auto& s : m.spheres) {
    const double rho = 18;
    const Eigen::Vector3d dirs[5] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
    for (int i = 0; i < 5; ++i) {
      parts::ManifestPoint p;
      p.position = s.position;
      p.point = i + 1;
      p.contact_mm = s.nominal_centre_mm + rho * dirs[i];
      m.points.push_back(p);
    }
  }
  const auto b = evaluate::predictLocationErrorBudgets(m);
  EXPECT_NEAR(b[0].u_c, 0.5e-0 * std::sqrt(0.5) / 2 * std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(b[2].u_c, 0.5 * 1.0 / 2 * std::sqrt(2.0), 1e-9);  // EZ0T: mean of 4 z, var 1 each
}

TEST(LocationBudget, SphereCentreCarriesScatterResolutionFormAndToolChange) {
  auto m = thesis();
  m.probe_repeatability_2sigma_um = 1.0;
  m.coordinate_resolution_mm = 0.001;
  m.sphere_form_error_um = 0.4;
  m.tool_change_each_cycle = true;
  m.probe_tool_change_repeatability_2sigma_um = 1.5;
  evaluate::PointScatter ps;
  ps.type_b_sigma_mm = 0.5e-3;
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.5, 0.5, 1.0).asDiagonal();  // 4 equator points + top
  const auto b = evaluate::sphereCentreBudgets(m, {1, 2, 3}, cov, ps);
  // per point: 0.5 (probe), 1/sqrt 12 (resolution), 0.2/sqrt 3 (form) um, through sqrt(cov);
  // the tool change moves the centre by 0.75 um per axis.
  const double per_point2 = 0.25 + 1.0 / 12 + 0.04 / 3;
  EXPECT_NEAR(b[0].u_c, std::sqrt(per_point2 * 0.5 + 0.75 * 0.75), 1e-12);
  EXPECT_NEAR(b[2].u_c, std::sqrt(per_point2 * 1.0 + 0.75 * 0.75), 1e-12);
  EXPECT_DOUBLE_EQ(b[1].value, 2000);
}

// Seed 004 Table 5.3: the 3D line is the root-sum-square of X, Y, Z: 2.2 um without and
// 2.6 um with tool changes.
TEST(CentreRepeatability, ReproducesTable53RootSumSquare) {
  EXPECT_EQ(std::round(evaluate::rootSumSquare({1.2, 1.8, 0.2}) * 10) / 10, 2.2);
  EXPECT_EQ(std::round(evaluate::rootSumSquare({1.2, 1.7, 1.5}) * 10) / 10, 2.6);
  // Centres alternating +-a: s = sqrt(n a^2 / (n - 1)); U = 2 s and 2 s / sqrt n.
  std::vector<Eigen::Vector3d> c;
  const double a = 1e-3;
  for (int i = 0; i < 4; ++i) c.push_back(Eigen::Vector3d(i % 2 ? a : -a, 0, 2 * (i % 2 ? a : -a)));
  const auto r = evaluate::centreRepeatability(c);
  const double s = std::sqrt(4.0 / 3.0);  // um
  EXPECT_NEAR(r.s_um.x(), s, 1e-12);
  EXPECT_NEAR(r.U_single_um.z(), 4 * s, 1e-12);
  EXPECT_NEAR(r.U_single_3d_um, std::sqrt(4 * s * s + 16 * s * s), 1e-12);
  EXPECT_NEAR(r.U_mean_3d_um, r.U_single_3d_um / 2, 1e-12);
  EXPECT_THROW(evaluate::centreRepeatability({Eigen::Vector3d::Zero()}), GeometryError);
}

}  // namespace
