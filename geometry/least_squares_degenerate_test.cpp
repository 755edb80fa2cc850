// Degenerate input to the least-squares fits: each case is detected and explained with
// what would fix it; none returns NaN. (Accuracy is pinned by ls_reference_test.cpp and
// nist_reference_test.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/reference_sphere_fit_test_support.hpp"
#include "geometry/sphere_fit.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace {
std::string messageOf(ElementKind k, const Points3& p, const LeastSquaresOptions& o = {}) {
  try {
    const FitResult f = fitLeastSquares(k, p, o);
    return "no error; radius " + std::to_string(f.element.radius_mm);
  } catch (const GeometryError& e) {
    return e.what();
  }
}
#define EXPECT_MESSAGE(kind, points, fragment)                                  \
  do {                                                                          \
    const std::string m = messageOf(kind, points);                              \
    EXPECT_NE(m.find(fragment), std::string::npos) << "message: " << m;          \
  } while (0)

Points3 arc(double deg, int n, double r, double noise_um = 0.0) {
  Points3 p;
  for (int i = 0; i < n; ++i) {
    const double a = deg * M_PI / 180.0 * i / (n - 1);
    const double rr = r + (i % 2 ? noise_um : -noise_um) * 1e-3;
    p.emplace_back(1000 + rr * std::cos(a), -1000 + rr * std::sin(a), 500);
  }
  return p;
}
}  // namespace

TEST(LeastSquaresDegenerate, TooFewPointsNamesTheNeed) {
  EXPECT_MESSAGE(ElementKind::Sphere, (Points3{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}), "sphere needs >= 4");
  EXPECT_MESSAGE(ElementKind::Cylinder, (Points3{{0, 0, 0}, {1, 0, 0}}), "cylinder needs >= 5");
  EXPECT_MESSAGE(ElementKind::Plane, (Points3{{0, 0, 0}, {1, 0, 0}}), "plane needs >= 3");
}

TEST(LeastSquaresDegenerate, NonFiniteAndDuplicatedPointsAreNamed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_MESSAGE(ElementKind::Plane, (Points3{{0, 0, 0}, {1, 0, 0}, {nan, 1, 0}, {1, 1, 1}}), "point 3");
  const std::string m =
      messageOf(ElementKind::Sphere, Points3{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 1, 0}, {-1, 0, 0}});
  EXPECT_NE(m.find("2 and 4"), std::string::npos) << m;
}

TEST(LeastSquaresDegenerate, CollinearPlaneAndCircle) {
  const Points3 line{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
  EXPECT_MESSAGE(ElementKind::Plane, line, "collinear");
  EXPECT_MESSAGE(ElementKind::Circle2D, line, "collinear");
}

TEST(LeastSquaresDegenerate, CoplanarSphereSaysHowFarAndWhatToAdd) {
  Points3 p;
  for (int i = 0; i < 5; ++i)
    p.emplace_back(500 + 10 * std::cos(i * 1.2), 200 + 10 * std::sin(i * 1.2), 40 + (i == 2 ? 1e-10 : 0.0));
  const std::string m = messageOf(ElementKind::Sphere, p);
  EXPECT_NE(m.find("non-coplanar"), std::string::npos) << m;
  EXPECT_NE(m.find("of a plane"), std::string::npos) << m;
}

TEST(LeastSquaresDegenerate, ArcTooShortForARadiusAsksForSpreadOrKnownRadius) {
  // 0.01 deg of a 50 mm circle with 1 um alternating noise: the radius is not determined.
  const std::string m = messageOf(ElementKind::Circle2D, arc(0.01, 12, 50.0, 1.0));
  EXPECT_TRUE(m.find("radius") != std::string::npos && m.find("no error") == std::string::npos) << m;
  // With the known radius the same points give a centre.
  LeastSquaresOptions o;
  o.fixed_radius_mm = 50.0;
  EXPECT_NO_THROW(fitLeastSquares(ElementKind::Circle2D, arc(10.0, 12, 50.0, 1.0), o));
}

TEST(LeastSquaresDegenerate, KnownRadiusMustBePositiveAndApplicable) {
  LeastSquaresOptions o;
  o.fixed_radius_mm = -2.0;
  EXPECT_NE(messageOf(ElementKind::Circle2D, arc(90, 8, 5), o).find("positive"), std::string::npos);
  o.fixed_radius_mm = 2.0;
  EXPECT_NE(messageOf(ElementKind::Plane, Points3{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, o).find("known radius"),
            std::string::npos);
}

TEST(LeastSquaresDegenerate, ConeOfACylinderSuggestsACylinder) {
  Points3 p;
  for (int i = 0; i < 40; ++i)
    p.emplace_back(20 * std::cos(i * 0.7), 20 * std::sin(i * 0.7), -30 + 1.5 * i);
  const std::string m = messageOf(ElementKind::Cone, p);
  EXPECT_NE(m.find("cylinder"), std::string::npos) << m;
}

TEST(LeastSquaresSphere, AgreesWithTheSphereArtifactFit) {
  // The LS engine against a second, independent implementation of the same estimator
  // (reference_sphere_fit_test_support.hpp, the sphere-artifact evaluation's fit before
  // issue 29); they must agree on noisy probe data, and fitSphere (now the engine) with it.
  Points3 p;
  for (int i = 0; i < 9; ++i) {
    const double th = 0.3 + 1.2 * i / 8.0, ph = 2.4 * i;
    const double r = 18.0 + ((i * 7) % 5 - 2) * 0.4e-3;
    p.push_back(Vector3d(-160, 3, 75) + r * Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
  }
  const FitResult a = fitLeastSquares(ElementKind::Sphere, p);
  const SphereFit b = referenceSphereFit(p);
  EXPECT_LT((a.element.position_mm - b.centre_mm).norm(), 1e-10);
  EXPECT_NEAR(a.element.radius_mm, b.radius_mm, 1e-10);
  const SphereFit c = fitSphere(p);
  EXPECT_EQ(c.centre_mm, a.element.position_mm);
  EXPECT_EQ(c.radius_mm, a.element.radius_mm);
  EXPECT_TRUE(std::isfinite(a.rms_mm));
}
