// The fast paths of the least-squares engine against the plain ones: statistics from the
// fit's last pass (keep_residuals = false) against the residual vector, the hashed
// duplicate search against a brute-force pair search, and scans that start far from the
// solution (coarse stage on a subsample, last step without a pass) against small sets
// fitted the verified way. Accuracy itself is pinned by ls_reference_test.cpp and
// nist_reference_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace {

// Noisy points on an element: sphere cap, full cylinder, cone band, circle, plane patch.
Points3 noisyPoints(ElementKind kind, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Points3 p;
  p.reserve(n);
  const Vector3d o(412.5, -233.25, 118.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * u(rng), t = u(rng), e = noise(rng);
    switch (kind) {
      case ElementKind::Sphere: {
        const double pol = 1.2 * t;  // a cap of 2 x 69 deg
        p.push_back(o + (25.0 + e) * Vector3d(std::sin(pol) * std::cos(a), std::sin(pol) * std::sin(a),
                                              std::cos(pol)));
        break;
      }
      case ElementKind::Cylinder:
        p.push_back(o + Vector3d((20.0 + e) * std::cos(a), (20.0 + e) * std::sin(a), 80.0 * t));
        break;
      case ElementKind::Cone: {
        const double z = 40.0 * t, r = 10.0 + z * std::tan(0.3);
        p.push_back(o + Vector3d((r + e) * std::cos(a), (r + e) * std::sin(a), z));
        break;
      }
      case ElementKind::Circle3D:
        p.push_back(o + Vector3d((30.0 + e) * std::cos(a), (30.0 + e) * std::sin(a), 0.0));
        break;
      default:
        p.push_back(o + Vector3d(100.0 * u(rng), 60.0 * t, e + 0.01 * (u(rng) - 0.5)));
    }
  }
  return p;
}

}  // namespace

TEST(LeastSquaresEngine, StatisticsWithoutResidualsMatchTheResidualVector) {
  for (ElementKind kind : {ElementKind::Plane, ElementKind::Circle3D, ElementKind::Sphere,
                           ElementKind::Cylinder, ElementKind::Cone}) {
    for (std::size_t n : {std::size_t{50}, std::size_t{5000}, std::size_t{60000}}) {
      const Points3 p = noisyPoints(kind, n, 7 + n);
      const FitResult full = fitLeastSquares(kind, p);
      LeastSquaresOptions o;
      o.keep_residuals = false;
      const FitResult stats = fitLeastSquares(kind, p, o);
      SCOPED_TRACE(std::string(elementName(kind)) + " n=" + std::to_string(n));
      ASSERT_EQ(full.residuals_mm.size(), n);
      EXPECT_TRUE(stats.residuals_mm.empty());
      // The same element: both runs are the same computation up to the statistics.
      EXPECT_EQ(stats.element.position_mm, full.element.position_mm);
      EXPECT_EQ(stats.element.radius_mm, full.element.radius_mm);
      EXPECT_EQ(stats.dof, full.dof);
      // Statistics of the last pass against those of signedDistance at the reported element:
      // an unverified step of at most 10 pm apart (the engine's bound, kUnverifiedStepMm).
      EXPECT_NEAR(stats.ssr_mm2, full.ssr_mm2, 1e-9 * full.ssr_mm2);
      EXPECT_NEAR(stats.rms_mm, full.rms_mm, 1e-9 * full.rms_mm);
      EXPECT_NEAR(stats.form_mm, full.form_mm, 2e-8);
      EXPECT_NEAR(stats.residual_variance_mm2, full.residual_variance_mm2,
                  1e-9 * full.residual_variance_mm2);
    }
  }
}

TEST(LeastSquaresEngine, HashedDuplicateSearchFindsWhatAPairSearchFinds) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  std::uniform_int_distribution<int> pick(0, 399);
  for (int trial = 0; trial < 40; ++trial) {
    Points3 p;
    for (int i = 0; i < 400; ++i) p.emplace_back(u(rng), u(rng), 0.3 * u(rng) + 0.01 * i);
    // Plant a near-duplicate in three trials of four: 0.6 pm apart, and straddling a 1 nm
    // cell face in x in one of them (the case the neighbour look-up exists for).
    const bool planted = trial % 2 == 0 || trial % 4 == 1;
    int a = pick(rng), b = pick(rng);
    if (a == b) b = (a + 1) % 400;
    if (planted) {
      p[b] = p[a] + Vector3d(0.6e-9, 0.0, 0.0);
      if (trial % 4 == 1) {
        const double face = std::floor(p[a].x() * 1e6) / 1e6;
        p[a].x() = face - 0.3e-9;
        p[b] = p[a] + Vector3d(0.6e-9, 0.0, 0.0);
      }
    }
    bool brute = false;
    for (std::size_t i = 0; i < p.size(); ++i)
      for (std::size_t j = i + 1; j < p.size(); ++j) brute = brute || (p[i] - p[j]).norm() <= 1e-9;
    bool refused = false;
    try {
      fitLeastSquares(ElementKind::Plane, p);
    } catch (const GeometryError& e) {
      refused = std::string(e.what()).find("coincide") != std::string::npos;
      if (refused) {
        const std::string want = std::to_string(std::min(a, b) + 1) + " and " +
                                 std::to_string(std::max(a, b) + 1);
        EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
      }
    }
    EXPECT_EQ(refused, brute) << "trial " << trial;
    EXPECT_EQ(brute, planted) << "trial " << trial;
  }
}

// Every cell face (x, y and z) and the planar kinds, whose points coincide when x and y do
// (z is not compared): a pair 0.6 pm apart straddling a face of the 1 nm grid is found and
// named, a pair 2 nm apart is not a duplicate.
TEST(LeastSquaresEngine, DuplicateSearchCoversEveryFaceAndThePlanarKinds) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto refusal = [](ElementKind kind, const Points3& p) -> std::string {
    try {
      fitLeastSquares(kind, p);
    } catch (const GeometryError& e) {
      return e.what();
    }
    return "";
  };
  for (int c = 0; c < 3; ++c) {
    for (int trial = 0; trial < 6; ++trial) {
      const bool planar = c < 2 && trial % 2 == 1;  // Circle2D: x and y faces only
      const ElementKind kind = planar ? ElementKind::Circle2D : ElementKind::Plane;
      Points3 p;
      for (int i = 0; i < 300; ++i) {
        const double a = 2.0 * M_PI * u(rng);
        if (planar)
          p.emplace_back(12.5 + 30.0 * std::cos(a), -7.25 + 30.0 * std::sin(a), 10.0 * u(rng));
        else
          p.emplace_back(100.0 * u(rng), 60.0 * u(rng), 0.02 * u(rng) + 0.001 * i);
      }
      // The point searched later (the higher index) lies below the face in some trials and
      // above it in others, so that both neighbour look-ups are needed.
      int a = 17 + 40 * trial, b = 5 + 13 * trial;
      if (trial >= 3) std::swap(a, b);
      Vector3d apart = Vector3d::Zero();
      apart(c) = 0.6e-9;
      p[a](c) = std::floor(p[a](c) * 1e6) / 1e6 - 0.3e-9;  // 0.3 pm below a cell face
      p[b] = p[a] + apart;
      if (planar) p[b].z() += 5.0;  // a different z does not matter for x, y only
      const std::string e = refusal(kind, p);
      SCOPED_TRACE(std::string(elementName(kind)) + " face " + "xyz"[c]);
      EXPECT_NE(e.find("points " + std::to_string(std::min(a, b) + 1) + " and " +
                       std::to_string(std::max(a, b) + 1) + " coincide"),
                std::string::npos)
          << e;
      p[b](c) = p[a](c) + 2e-9;  // 2 nm apart: two points
      EXPECT_EQ(refusal(kind, p).find("coincide"), std::string::npos);
    }
  }
}

TEST(LeastSquaresEngine, DuplicateSearchLimitIsAnOption) {
  Points3 p = noisyPoints(ElementKind::Plane, 5000, 3);
  p[4321] = p[17];
  EXPECT_NO_THROW(fitLeastSquares(ElementKind::Plane, p));  // 5000 > 4096: a scan
  LeastSquaresOptions o;
  o.duplicate_search_max_points = 10000;
  try {
    fitLeastSquares(ElementKind::Plane, p, o);
    ADD_FAILURE() << "the duplicate was not found";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("points 18 and 4322 coincide"), std::string::npos)
        << e.what();
  }
}

// A scan (coarse stage on a subsample, last Gauss-Newton step taken without a pass) lands on
// the optimum, against plain Gauss-Newton iterations written here (normal equations summed in
// long double, iterated until the step is below 1e-13 mm or rad, started from the truth).
// The cylinder's Jacobian is derived here from the radial vector v = w - (w.u) u of
// w = p - o: moving the axis point by e (e perpendicular to u) changes |v| by -n.e, tilting
// u toward e by -(w.u) n.e, the radius by -1 (n = v / |v|).
TEST(LeastSquaresEngine, ScanReachesTheOptimum) {
  using L = long double;
  using V3 = Eigen::Matrix<L, 3, 1>;
  const Points3 p = noisyPoints(ElementKind::Sphere, 200000, 5);
  LeastSquaresOptions o;
  o.keep_residuals = false;
  const FitResult fit = fitLeastSquares(ElementKind::Sphere, p, o);
  Vector3d c(412.5, -233.25, 118.0);
  double r = 25.0;
  bool converged = false;
  for (int it = 0; it < 50 && !converged; ++it) {
    Eigen::Matrix<L, 4, 4> a = Eigen::Matrix<L, 4, 4>::Zero();
    Eigen::Matrix<L, 4, 1> b = Eigen::Matrix<L, 4, 1>::Zero();
    for (const auto& q : p) {
      const Vector3d v = q - c;
      const double rho = v.norm();
      Eigen::Matrix<L, 4, 1> j;
      j << -v.x() / rho, -v.y() / rho, -v.z() / rho, -1.0;
      a += j * j.transpose();
      b += j * static_cast<L>(rho - r);
    }
    const Eigen::Matrix<L, 4, 1> step = -a.ldlt().solve(b);
    c += Vector3d(static_cast<double>(step(0)), static_cast<double>(step(1)),
                  static_cast<double>(step(2)));
    r += static_cast<double>(step(3));
    converged = step.cwiseAbs().maxCoeff() < 1e-13;
  }
  ASSERT_TRUE(converged);
  EXPECT_LT((fit.element.position_mm - c).norm(), 1e-10);
  EXPECT_LT(std::abs(fit.element.radius_mm - r), 1e-10);

  const Points3 q = noisyPoints(ElementKind::Cylinder, 200000, 6);
  const FitResult cyl = fitLeastSquares(ElementKind::Cylinder, q, o);
  V3 axis_point(412.5L, -233.25L, 118.0L), u(0.0L, 0.0L, 1.0L);
  L radius = 20.0L, ssr = 0.0L;
  converged = false;
  for (int it = 0; it < 50 && !converged; ++it) {
    // Any two unit vectors perpendicular to u.
    const V3 e1 = (std::abs(u.x()) < 0.9L ? V3(1, 0, 0) : V3(0, 1, 0)).cross(u).normalized();
    const V3 e2 = u.cross(e1);
    Eigen::Matrix<L, 5, 5> a = Eigen::Matrix<L, 5, 5>::Zero();
    Eigen::Matrix<L, 5, 1> b = Eigen::Matrix<L, 5, 1>::Zero();
    ssr = 0.0L;
    for (const auto& pt : q) {
      const V3 w = pt.cast<L>() - axis_point;
      const V3 v = w - w.dot(u) * u;
      const L rho = v.norm();
      const V3 n = v / rho;
      const L along = w.dot(u);
      Eigen::Matrix<L, 5, 1> j;
      j << -n.dot(e1), -n.dot(e2), -along * n.dot(e1), -along * n.dot(e2), -1.0L;
      a += j * j.transpose();
      b += j * (rho - radius);
      ssr += (rho - radius) * (rho - radius);
    }
    const Eigen::Matrix<L, 5, 1> step = -a.ldlt().solve(b);
    axis_point += step(0) * e1 + step(1) * e2;
    u = (u + step(2) * e1 + step(3) * e2).normalized();
    radius += step(4);
    converged = step.cwiseAbs().maxCoeff() < 1e-13L;  // ssr: at the last state but one
  }
  ASSERT_TRUE(converged);
  const Vector3d d = u.cast<double>();
  const Vector3d off = cyl.element.position_mm - axis_point.cast<double>();
  EXPECT_LT((off - d * d.dot(off)).norm(), 1e-9);  // the axes pass within 1 pm of each other
  EXPECT_LT(std::abs(cyl.element.radius_mm - static_cast<double>(radius)), 1e-9);
  EXPECT_LT(std::min((cyl.element.direction - d).norm(), (cyl.element.direction + d).norm()), 1e-10);
  EXPECT_NEAR(cyl.ssr_mm2, static_cast<double>(ssr), 1e-9 * static_cast<double>(ssr));

  // From a start 0.3 mm and 10 mrad away, the same optimum.
  LeastSquaresOptions poor = o;
  Element s = cyl.element;
  s.position_mm += Vector3d(0.3, -0.2, 0.25);
  s.radius_mm += 0.2;
  s.direction = (s.direction + Vector3d(0.01, -0.008, 0.0)).normalized();
  poor.start = s;
  const FitResult from_poor = fitLeastSquares(ElementKind::Cylinder, q, poor);
  const Vector3d off2 = from_poor.element.position_mm - axis_point.cast<double>();
  EXPECT_LT((off2 - d * d.dot(off2)).norm(), 1e-9);
  EXPECT_LT(std::abs(from_poor.element.radius_mm - static_cast<double>(radius)), 1e-9);
  EXPECT_LT(std::min((from_poor.element.direction - d).norm(), (from_poor.element.direction + d).norm()),
            1e-10);
  EXPECT_NEAR(from_poor.ssr_mm2, static_cast<double>(ssr), 1e-9 * static_cast<double>(ssr));
}
