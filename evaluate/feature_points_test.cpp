// Stated features as points (issue 34): d2(n) against its published table, the form-based
// scatter against a Monte Carlo of least-squares plane fits, and the placed points' own fits
// returning the stated features exactly.
#include "evaluate/feature_points.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "evaluate/feature_test_support.hpp"
#include "geometry/fit.hpp"

using namespace probeloop;
using namespace probeloop::evaluate;

TEST(ExpectedRangeOfNormals, MatchesThePublishedControlChartConstants) {
  // d2 of ASTM E2587 / Montgomery, Introduction to Statistical Quality Control, App. VI (3 decimals).
  const std::pair<int, double> d2[] = {{2, 1.128}, {3, 1.693}, {4, 2.059}, {5, 2.326}, {10, 3.078}, {12, 3.258}, {25, 3.931}};
  for (const auto& [n, v] : d2) EXPECT_NEAR(expectedRangeOfNormals(n), v, 5e-4) << n;
  EXPECT_NEAR(expectedRangeOfNormals(2), 2 / std::sqrt(M_PI), 1e-9);  // exactly 2/sqrt(pi)
}

TEST(RangeStdOfNormals, MatchesThePublishedControlChartConstants) {
  // d3 of ASTM E2587 / Montgomery App. VI (3 decimals); d3(2) = sqrt(2 - 4/pi) exactly.
  const std::pair<int, double> d3[] = {{2, 0.853}, {3, 0.888}, {4, 0.880}, {5, 0.864}, {10, 0.797}, {12, 0.778}, {24, 0.712}};
  for (const auto& [n, v] : d3) EXPECT_NEAR(rangeStdOfNormals(n), v, 6e-4) << n;
  EXPECT_NEAR(rangeStdOfNormals(2), std::sqrt(2 - 4 / M_PI), 2e-4);
  // The dof of one range's sigma: 1/2 (d2/d3)^2, 8.8 for 12 points (not n - 3 = 9, and far
  // from n - 3 for many points: 85 for 1000, not 997).
  EXPECT_NEAR(rangeDof(12), 0.5 * std::pow(3.258 / 0.778, 2), 0.05);
  EXPECT_LT(rangeDof(1000), 120);
}

TEST(SigmaFromForm, RecoversTheScatterOfLeastSquaresPlaneFitsWithinFivePercent) {
  // 1000 planes of 12 points on a 4 x 3 grid, sigma = 1 um: the mean estimate from the LS form.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1e-3);
  double sum = 0;
  const int runs = 1000;
  for (int r = 0; r < runs; ++r) {
    std::vector<Eigen::Vector3d> p;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) p.emplace_back(10.0 * i, 7.0 * j, g(rng));
    const auto f = geometry::fitElement(geometry::ElementKind::Plane, p, {}).fit;
    sum += sigmaFromForm(f.form_mm, 12, 3);
  }
  EXPECT_NEAR(sum / runs / 1e-3, 1.0, 0.05) << "mean sigma from form / true sigma";
  EXPECT_TRUE(std::isnan(sigmaFromForm(NAN, 12, 3)));
  EXPECT_TRUE(std::isnan(sigmaFromForm(1e-3, 3, 3)));
}

namespace {

parts::PlanManifest plan() {
  parts::PlanManifest m;
  m.file = "plan.json";
  parts::ManifestFeature p;
  p.nominal.id = "F";
  p.nominal.kind = "plane";
  p.nominal.point_mm = {0, 0, 0};
  p.nominal.direction = {0, 0, 1};
  p.nominal.half_u_mm = p.nominal.half_v_mm = 50;
  m.features.push_back(p);
  parts::ManifestFeature c;
  c.nominal.id = "CYL";
  c.nominal.kind = "cylinder";
  c.nominal.point_mm = {0, 0, -10};
  c.nominal.direction = {0, 0, 1};
  c.nominal.radius_mm = 40;
  m.features.push_back(c);
  return m;
}

FeatureActual row(int line, const std::string& id, const std::string& kind, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                  double size, double form_um, int n_points) {
  return feature_test::statedFeature(line, id, kind, p, n, size, form_um, n_points);
}

}  // namespace

TEST(PointsOnStatedFeatures, ALeastSquaresFitOfThePlacedPointsReturnsTheStatedFeature) {
  const auto m = plan();
  const Eigen::Vector3d n = Eigen::Vector3d(2e-5, -3e-5, 1).normalized(), axis = Eigen::Vector3d(1e-5, 4e-5, 1).normalized();
  const auto match = matchFeatureActuals({row(4, "PLN", "plane", {3, -2, 0.004}, n, NAN, 1.2, 48),
                                          row(5, "CIR", "cylinder", {0.002, -0.003, -10}, axis, 80.006, NAN, 0)},
                                         m);
  std::map<std::string, std::vector<Eigen::Vector3d>> planned;
  for (int i = 0; i < 12; ++i) planned["F"].emplace_back(-30 + 6.0 * i, 17.0 * std::sin(i), 0.0);
  for (int i = 0; i < 8; ++i) planned["CYL"].emplace_back(40 * std::cos(0.7 * i), 40 * std::sin(0.7 * i), -12.0 + i % 3 * 2.0);
  const auto s = pointsOnStatedFeatures(match, planned, "f.csv", "features");
  ASSERT_EQ(s.points.points.size(), 20u);
  std::vector<Eigen::Vector3d> pf, pc;
  for (const auto& p : s.points.points) {
    (p.feature == "F" ? pf : pc).push_back(p.p_mm);
    EXPECT_EQ(p.line, p.feature == "F" ? 4 : 5);
  }
  const auto fp = geometry::fitElement(geometry::ElementKind::Plane, pf, {}).fit;
  EXPECT_NEAR(std::fabs(fp.element.direction.normalized().dot(n)), 1.0, 1e-14);
  EXPECT_NEAR(n.dot(fp.element.position_mm - Eigen::Vector3d(3, -2, 0.004)), 0.0, 1e-12);
  EXPECT_LT(fp.form_mm, 1e-12);
  const auto fc = geometry::fitElement(geometry::ElementKind::Cylinder, pc, {}).fit;
  EXPECT_NEAR(fc.element.radius_mm, 40.003, 1e-9);
  EXPECT_NEAR(std::fabs(fc.element.direction.normalized().dot(axis)), 1.0, 1e-12);
  const Eigen::Vector3d off = fc.element.position_mm - Eigen::Vector3d(0.002, -0.003, -10);
  EXPECT_LT((off - off.dot(axis) * axis).norm(), 1e-9);
  // The scatter the file states: 48 points for 12 placed, the form over d2(48); not averaged
  // below the planned layout (point_scale 1, nAveraging 12).
  const auto& sf = s.scatter.at("F");
  EXPECT_EQ(sf.n_stated, 48);
  EXPECT_EQ(sf.n_planned, 12);
  EXPECT_EQ(sf.nAveraging(), 12);
  EXPECT_DOUBLE_EQ(sf.point_scale, 1.0);
  EXPECT_NEAR(sf.form_dof, 0.5 * std::pow(expectedRangeOfNormals(48) / rangeStdOfNormals(48), 2), 1e-12);  // below 45
  EXPECT_NEAR(sf.sigma_from_form_mm, 1.2e-3 / (expectedRangeOfNormals(48) * std::sqrt(45.0 / 48)), 1e-15);
  EXPECT_EQ(sf.row, "PLN (f.csv:4)");
  EXPECT_TRUE(std::isnan(s.scatter.at("CYL").sigma_from_form_mm));
  EXPECT_DOUBLE_EQ(s.scatter.at("CYL").point_scale, 1.0);
}

TEST(PointsOnStatedFeatures, Refusals) {
  const auto m = plan();
  auto what = [&](const FeatureActual& r, std::map<std::string, std::vector<Eigen::Vector3d>> planned) {
    try {
      pointsOnStatedFeatures(matchFeatureActuals({r}, m), planned, "f.csv", "features");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(what(row(3, "F", "plane", {0, 0, 0}, {0, 0, 1}, NAN, NAN, 0), {}).find("f.csv:3: plane 'F' is F, which the plan has no points for"),
            std::string::npos);
  EXPECT_NE(what(row(3, "CYL", "cylinder", {0, 0, -10}, {0, 0, 1}, 80, NAN, 0), {{"CYL", {{0, 0, -5}}}}).find("lies on the stated axis"),
            std::string::npos);
  EXPECT_NE(what(row(4, "CYL", "cylinder", {0, 0, -10}, {0, 0, 1}, NAN, NAN, 0), {{"CYL", {{40, 0, -5}}}}).find("f.csv:4: cylinder 'CYL' (CYL) states no diameter"),
            std::string::npos);
}

TEST(PointsOnStatedFeatures, FewerPointsStatedThanPlannedScaleUpNeverDown) {
  const auto m = plan();
  std::map<std::string, std::vector<Eigen::Vector3d>> planned;
  for (int i = 0; i < 12; ++i) planned["F"].emplace_back(-30 + 6.0 * i, 17.0 * std::sin(i), 0.0);
  for (int n : {6, 12, 5000}) {
    const auto s = pointsOnStatedFeatures(matchFeatureActuals({row(2, "F", "plane", {0, 0, 0}, {0, 0, 1}, NAN, NAN, n)}, m), planned,
                                          "f.csv", "features");
    EXPECT_DOUBLE_EQ(s.scatter.at("F").point_scale, n < 12 ? std::sqrt(2.0) : 1.0) << n;
  }
}
