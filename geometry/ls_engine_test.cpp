// The fast paths of the least-squares engine against the plain ones: statistics from the
// fit's last pass (keep_residuals = false) against the residual vector, the hashed
// duplicate search against a brute-force pair search, and scans that start far from the
// solution (coarse stage on a subsample, last step without a pass) against small sets
// fitted the verified way. Accuracy itself is pinned by ls_reference_test.cpp and
// nist_reference_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <optional>
#include <random>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/ls_detail.hpp"

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

// The least-squares cylinder by plain Gauss-Newton iterations (normal equations summed in long
// double, iterated until the step is below 1e-13 mm or rad). The Jacobian is derived here from
// the radial vector v = w - (w.u) u of w = p - o: moving the axis point by e (e perpendicular
// to u) changes |v| by -n.e, tilting u toward e by -(w.u) n.e, the radius by -1 (n = v / |v|).
struct CylinderOptimum {
  Vector3d point, direction;
  double radius = 0.0;
  long double ssr = 0.0L;
  bool converged = false;
};
CylinderOptimum cylinderOptimum(const Points3& q, const Vector3d& point, const Vector3d& direction,
                                double r) {
  using L = long double;
  using V3 = Eigen::Matrix<L, 3, 1>;
  V3 axis_point = point.cast<L>(), u = direction.cast<L>().normalized();
  L radius = r;
  CylinderOptimum out;
  for (int it = 0; it < 50 && !out.converged; ++it) {
    // Any two unit vectors perpendicular to u.
    const V3 e1 = (std::abs(u.x()) < 0.9L ? V3(1, 0, 0) : V3(0, 1, 0)).cross(u).normalized();
    const V3 e2 = u.cross(e1);
    Eigen::Matrix<L, 5, 5> a = Eigen::Matrix<L, 5, 5>::Zero();
    Eigen::Matrix<L, 5, 1> b = Eigen::Matrix<L, 5, 1>::Zero();
    out.ssr = 0.0L;
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
      out.ssr += (rho - radius) * (rho - radius);
    }
    const Eigen::Matrix<L, 5, 1> step = -a.ldlt().solve(b);
    axis_point += step(0) * e1 + step(1) * e2;
    u = (u + step(2) * e1 + step(3) * e2).normalized();
    radius += step(4);
    out.converged = step.cwiseAbs().maxCoeff() < 1e-13L;  // ssr: at the last state but one
  }
  out.point = axis_point.cast<double>();
  out.direction = u.cast<double>();
  out.radius = static_cast<double>(radius);
  return out;
}

// The fit's axis passes within 1 pm of the optimum's, with the same radius, direction and sum
// of squares.
void expectAtCylinderOptimum(const FitResult& fit, const CylinderOptimum& best) {
  const Vector3d& d = best.direction;
  const Vector3d off = fit.element.position_mm - best.point;
  EXPECT_LT((off - d * d.dot(off)).norm(), 1e-9);
  EXPECT_LT(std::abs(fit.element.radius_mm - best.radius), 1e-9);
  EXPECT_LT(std::min((fit.element.direction - d).norm(), (fit.element.direction + d).norm()), 1e-10);
  EXPECT_NEAR(fit.ssr_mm2, static_cast<double>(best.ssr), 1e-9 * static_cast<double>(best.ssr));
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
  const Points3 p = noisyPoints(ElementKind::Sphere, 200000, 5);
  LeastSquaresOptions o;
  o.keep_residuals = false;
  const FitResult fit = fitLeastSquares(ElementKind::Sphere, p, o);
  Vector3d c(412.5, -233.25, 118.0);
  double r = 25.0;
  bool converged = false;
  Eigen::Matrix<L, 4, 4> a;
  for (int it = 0; it < 50 && !converged; ++it) {
    a.setZero();
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
  // On a scan the covariance is (J^T J)^-1 from the last full pass, here at the coarse
  // stage's solution some 1e-5 mm away (a chord pass then accepts the solution). On this 2 x 69 deg cap that
  // moves (J^T J)^-1 by about 1e-5 relatively (measured); bounded here at 1e-4, two orders
  // below the two significant digits an uncertainty is quoted with.
  const Eigen::Matrix<L, 4, 4> cov = a.inverse();
  ASSERT_EQ(fit.covariance_unscaled.rows(), 4);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      EXPECT_NEAR(fit.covariance_unscaled(i, j), static_cast<double>(cov(i, j)),
                  1e-4 * std::sqrt(static_cast<double>(cov(i, i) * cov(j, j))))
          << i << ", " << j;

  const Points3 q = noisyPoints(ElementKind::Cylinder, 200000, 6);
  const FitResult cyl = fitLeastSquares(ElementKind::Cylinder, q, o);
  const CylinderOptimum best =
      cylinderOptimum(q, Vector3d(412.5, -233.25, 118.0), Vector3d::UnitZ(), 20.0);
  ASSERT_TRUE(best.converged);
  expectAtCylinderOptimum(cyl, best);

  // From a start 0.3 mm and 10 mrad away, the same optimum.
  LeastSquaresOptions poor = o;
  Element s = cyl.element;
  s.position_mm += Vector3d(0.3, -0.2, 0.25);
  s.radius_mm += 0.2;
  s.direction = (s.direction + Vector3d(0.01, -0.008, 0.0)).normalized();
  poor.start = s;
  expectAtCylinderOptimum(fitLeastSquares(ElementKind::Cylinder, q, poor), best);
}

// A horizontal axis (x), scanned with 4096 < n < 32 000 points (no coarse stage; chord
// passes), from a start 0.3 mm and 10 mrad away and from no start: the axis direction moves
// across the xy plane while iterating, where the local frame turns by 180 degrees (frameOf;
// twice in the fit from the given start, checked by instrumenting when this was written), and
// J^T J from before a turn must not be reused after it.
TEST(LeastSquaresEngine, HorizontalCylinderScanFromAFarStart) {
  const Vector3d o(412.5, -233.25, 118.0);
  Points3 q = noisyPoints(ElementKind::Cylinder, 20000, 7);
  for (auto& p : q) {  // the axis z -> x, through o
    const Vector3d d = p - o;
    p = o + Vector3d(d.z() - 40.0, d.y(), -d.x());
  }
  const CylinderOptimum best = cylinderOptimum(q, o, Vector3d::UnitX(), 20.0);
  ASSERT_TRUE(best.converged);
  EXPECT_LT(std::abs(best.direction.z()), 1e-4);  // the optimum's axis lies close to the xy plane
  LeastSquaresOptions poor;
  poor.keep_residuals = false;
  Element s;
  s.kind = ElementKind::Cylinder;
  s.position_mm = o + Vector3d(0.0, 0.3, -0.25);
  s.direction = Vector3d(1.0, 0.008, -0.01).normalized();  // below the plane, the optimum near it
  s.radius_mm = 20.2;
  poor.start = s;
  expectAtCylinderOptimum(fitLeastSquares(ElementKind::Cylinder, q, poor), best);
  LeastSquaresOptions none;
  none.keep_residuals = false;
  expectAtCylinderOptimum(fitLeastSquares(ElementKind::Cylinder, q, none), best);
}

// The AVX2 and the default versions of the passes give the same fit to the last bit
// (ls_detail.hpp): parameters, covariance, statistics, residuals and iterations, for every
// element family that has a pass (and the known-radius models), on sets whose size and last
// block are not multiples of four (the scalar tail, blocks shorter than four rows), small sets
// (dense polish), scans with chord passes and scans with a coarse stage.
TEST(LeastSquaresEngine, Avx2AndDefaultPassesGiveTheSameBits) {
  if (!__builtin_cpu_supports("avx2"))
    GTEST_SKIP() << "this CPU has no AVX2: the default passes are the only ones it runs";
  struct Restore {
    ~Restore() { ls::defaultPassesOnly = false; }
  } restore;
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  struct Case {
    ElementKind kind, data;
    std::optional<double> radius;
  };
  const Case cases[] = {
      {ElementKind::Line2D, ElementKind::Plane, std::nullopt},
      {ElementKind::Plane, ElementKind::Plane, std::nullopt},
      {ElementKind::Circle2D, ElementKind::Circle3D, std::nullopt},
      {ElementKind::Circle2D, ElementKind::Circle3D, 30.0},
      {ElementKind::Circle3D, ElementKind::Circle3D, std::nullopt},
      {ElementKind::Sphere, ElementKind::Sphere, std::nullopt},
      {ElementKind::Sphere, ElementKind::Sphere, 25.0},
      {ElementKind::Cylinder, ElementKind::Cylinder, std::nullopt},
      {ElementKind::Cylinder, ElementKind::Cylinder, 20.0},
      {ElementKind::Cone, ElementKind::Cone, std::nullopt},
  };
  for (const Case& c : cases) {
    for (std::size_t n : {std::size_t{7}, std::size_t{301}, std::size_t{9003}, std::size_t{40003}}) {
      const Points3 p = noisyPoints(c.data, n, 11);
      LeastSquaresOptions o;
      o.fixed_radius_mm = c.radius;
      ls::defaultPassesOnly = false;
      ASSERT_TRUE(ls::useAvx2Passes());
      const FitResult avx2 = fitLeastSquares(c.kind, p, o);
      ls::defaultPassesOnly = true;
      ASSERT_FALSE(ls::useAvx2Passes());
      const FitResult plain = fitLeastSquares(c.kind, p, o);
      ls::defaultPassesOnly = false;
      SCOPED_TRACE(std::string(elementName(c.kind)) + (c.radius ? " known radius" : "") +
                   " n = " + std::to_string(n));
      for (int k = 0; k < 3; ++k) {
        EXPECT_TRUE(same(avx2.element.position_mm(k), plain.element.position_mm(k)));
        EXPECT_TRUE(same(avx2.element.direction(k), plain.element.direction(k)));
      }
      EXPECT_TRUE(same(avx2.element.radius_mm, plain.element.radius_mm));
      EXPECT_TRUE(same(avx2.element.half_angle_rad, plain.element.half_angle_rad));
      EXPECT_TRUE(same(avx2.ssr_mm2, plain.ssr_mm2));
      EXPECT_TRUE(same(avx2.form_mm, plain.form_mm));
      EXPECT_EQ(avx2.iterations, plain.iterations);
      ASSERT_EQ(avx2.covariance_unscaled.size(), plain.covariance_unscaled.size());
      EXPECT_EQ(std::memcmp(avx2.covariance_unscaled.data(), plain.covariance_unscaled.data(),
                            sizeof(double) * static_cast<std::size_t>(avx2.covariance_unscaled.size())),
                0);
      ASSERT_EQ(avx2.residuals_mm.size(), n);
      ASSERT_EQ(plain.residuals_mm.size(), n);
      EXPECT_EQ(std::memcmp(avx2.residuals_mm.data(), plain.residuals_mm.data(), sizeof(double) * n), 0);
    }
  }
}
