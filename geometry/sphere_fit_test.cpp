#include "geometry/sphere_fit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace {
// Points on an exact sphere: the LS solution is the generating sphere (zero residuals).
std::vector<Vector3d> onSphere(const Vector3d& c, double r, int n, double max_polar = M_PI) {
  std::vector<Vector3d> p;
  for (int i = 0; i < n; ++i) {
    const double th = max_polar * (i + 0.5) / n;
    const double ph = 2.399963229728653 * i;  // golden angle
    p.push_back(c + r * Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                                 std::cos(th)));
  }
  return p;
}
}  // namespace

TEST(FitSphere, RecoversExactSphereFarFromOrigin) {
  const Vector3d c(1000.123, -850.5, 420.25);
  const auto fit = fitSphere(onSphere(c, 12.7, 25));
  EXPECT_LT((fit.centre_mm - c).norm(), 1e-9);
  EXPECT_NEAR(fit.radius_mm, 12.7, 1e-9);
  EXPECT_LT(fit.rms_mm, 1e-9);
}

TEST(FitSphere, FiveProbePointsFixedAndFreeRadius) {
  // The sphere-artifact layout: four on the equator and the top, as stylus-tip centres.
  const Vector3d c(-160.0, 0.0, 75.0);
  const double R = 15.0 + 3.0;
  std::vector<Vector3d> p{c + Vector3d(R, 0, 0), c + Vector3d(-R, 0, 0), c + Vector3d(0, R, 0),
                          c + Vector3d(0, -R, 0), c + Vector3d(0, 0, R)};
  const auto free = fitSphere(p);
  EXPECT_LT((free.centre_mm - c).norm(), 1e-10);
  EXPECT_EQ(free.dof, 1);
  SphereFitOptions o;
  o.fixed_radius_mm = R;
  const auto fixed = fitSphere(p, o);
  EXPECT_LT((fixed.centre_mm - c).norm(), 1e-10);
  EXPECT_EQ(fixed.dof, 2);
  // Known-radius fit of this layout: x is set by the +-X pair alone, so var(cx) = sigma^2/2.
  EXPECT_NEAR(fixed.covariance_unscaled(0, 0), 0.5, 1e-9);
}

TEST(FitSphere, LeastSquaresPropertyWithNoise) {
  // At the LS optimum the gradient J^T r vanishes: sum of residuals = 0 (free radius) and
  // sum r_i * unit(p_i - c) = 0. Checked independently of the solver.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  auto p = onSphere(Vector3d(10, 20, 30), 25.0, 40, 2.0);
  for (auto& x : p) x += Vector3d(noise(rng), noise(rng), noise(rng));
  const auto fit = fitSphere(p);
  double sum = 0.0;
  Vector3d g = Vector3d::Zero();
  for (size_t i = 0; i < p.size(); ++i) {
    const double r = (p[i] - fit.centre_mm).norm() - fit.radius_mm;
    EXPECT_NEAR(r, fit.residuals_mm[i], 1e-12);
    sum += r;
    g += r * (p[i] - fit.centre_mm).normalized();
  }
  EXPECT_NEAR(sum, 0.0, 1e-12);
  EXPECT_LT(g.norm(), 1e-12);
}

TEST(FitSphere, TooFewPointsIsExplained) {
  std::vector<Vector3d> p{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  try {
    fitSphere(p);
    FAIL();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find(">= 4"), std::string::npos);
  }
}

TEST(FitSphere, CoplanarPointsAreExplained) {
  std::vector<Vector3d> p{{1, 0, 5}, {0, 1, 5}, {-1, 0, 5}, {0, -1, 5}, {0.7071, 0.7071, 5}};
  try {
    fitSphere(p);
    FAIL();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("of a plane"), std::string::npos) << e.what();
  }
}

TEST(FitSphere, NanAndDuplicatesAreRejected) {
  std::vector<Vector3d> p{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {NAN, 0, 0}};
  EXPECT_THROW(fitSphere(p), GeometryError);
  std::vector<Vector3d> d{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 1}, {-1, 0, 0}};
  EXPECT_THROW(fitSphere(d), GeometryError);
}
