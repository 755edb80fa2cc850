// Tests of the reference data generator itself, independent of any fitter: the reference
// element must be a stationary point (and a local minimum) of the sum of squared
// orthogonal distances of the generated points. The Jacobian here is numerical (central
// differences of elements.hpp's signedDistance) over an ambient parametrisation —
// position (3), direction (3, renormalised), radius, half angle — not the generator's
// minimal local one, so a wrong analytic column in the generator cannot hide.
#include "geometry/reference_data.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

namespace {

constexpr double kPi = 3.141592653589793238462643383279502884;

// Ambient parameters of an element a set depends on: 0-2 position, 3-5 direction, 6
// radius, 7 half angle. circle3d: the circle part only (centre, radius); its plane is
// checked as a Plane element.
std::vector<int> ambientParameters(ElementKind kind) {
  switch (kind) {
    case ElementKind::Line2D:
      return {0, 1, 3, 4};
    case ElementKind::Line3D:
    case ElementKind::Plane:
      return {0, 1, 2, 3, 4, 5};
    case ElementKind::Circle2D:
      return {0, 1, 6};
    case ElementKind::Circle3D:
    case ElementKind::Sphere:
      return {0, 1, 2, 6};
    case ElementKind::Cylinder:
      return {0, 1, 2, 3, 4, 5, 6};
    case ElementKind::Cone:
      return {0, 1, 2, 3, 4, 5, 6, 7};
  }
  return {};
}

// Step of each ambient parameter: lengths in mm, direction components and angles unitless
// (a direction step moves points ~200 mm away by 200 times as much).
double stepOf(int k, double length_step) {
  return (k < 3 || k == 6) ? length_step : 0.01 * length_step;
}

Element applied(const Element& e, const std::vector<int>& params, const VectorXd& delta) {
  Element x = e;
  for (size_t j = 0; j < params.size(); ++j) {
    const int k = params[j];
    if (k < 3)
      x.position_mm(k) += delta(j);
    else if (k < 6)
      x.direction(k - 3) += delta(j);
    else if (k == 6)
      x.radius_mm += delta(j);
    else
      x.half_angle_rad += delta(j);
  }
  x.direction.normalize();
  return x;
}

// Points and element moved so the centroid is the origin: distances are translation
// invariant, and the finite differences then do not lose digits to 1000 mm coordinates.
void centre(Element& e, Points3& p) {
  Vector3d g = Vector3d::Zero();
  for (const auto& x : p) g += x;
  g /= static_cast<double>(p.size());
  if (e.kind == ElementKind::Line2D || e.kind == ElementKind::Circle2D) g.z() = 0.0;
  for (auto& x : p) x -= g;
  e.position_mm -= g;
}

VectorXd residuals(const Element& e, const Points3& p) {
  VectorXd r(static_cast<Eigen::Index>(p.size()));
  for (size_t i = 0; i < p.size(); ++i) r(i) = signedDistance(e, p[i]);
  return r;
}

// Central differences of the residuals (one column per ambient parameter), or of their
// squares. The 1e-4 mm steps suit the Jacobian (truncation h^2/R^2, rounding 1e-14/h); the
// squares need 1e-6 mm: their central difference carries (d'' h^2 / 2) * J, which must stay
// small against d ~ 1 um.
MatrixXd numericalJacobian(const Element& e, const Points3& p, const std::vector<int>& params,
                           bool squared = false) {
  const double length_step = squared ? 1e-6 : 1e-4;
  MatrixXd J(static_cast<Eigen::Index>(p.size()), static_cast<Eigen::Index>(params.size()));
  for (size_t j = 0; j < params.size(); ++j) {
    VectorXd delta = VectorXd::Zero(static_cast<Eigen::Index>(params.size()));
    delta(j) = stepOf(params[j], length_step);
    VectorXd up = residuals(applied(e, params, delta), p);
    VectorXd down = residuals(applied(e, params, -delta), p);
    if (squared) {
      up = up.cwiseAbs2();
      down = down.cwiseAbs2();
    }
    J.col(j) = (up - down) / (2.0 * delta(j));
  }
  return J;
}

// How far the gradient of the sum of squares is from zero, scale free: the largest
// |sum_i g_ik| / sum_i |g_ik| over the parameters k, g_ik = d(r_i^2)/d(theta_k). 0 at a
// stationary point, ~1/sqrt(n) for deviations that were not projected. Differentiating r^2
// rather than r suits line3d, whose unsigned distance is a cone-shaped |.| around the line
// (its square is smooth).
double gradientCancellation(const Element& e, const Points3& p, const std::vector<int>& params) {
  const MatrixXd G = numericalJacobian(e, p, params, /*squared=*/true);
  double worst = 0.0;
  for (Eigen::Index k = 0; k < G.cols(); ++k) {
    const double scale = G.col(k).cwiseAbs().sum();
    if (scale > 0.0) worst = std::max(worst, std::abs(G.col(k).sum()) / scale);
  }
  return worst;
}

// The (element, parameters) problems a set poses: one per kind, two for circle3d (its LS
// plane, then the circle in it).
struct Problem {
  Element element;
  std::vector<int> params;
};
std::vector<Problem> problemsOf(const ReferenceDataSet& set, Points3& centred) {
  Element e = set.reference;
  centred = set.points;
  centre(e, centred);
  std::vector<Problem> out{{e, ambientParameters(e.kind)}};
  if (e.kind == ElementKind::Circle3D) {
    Element plane = e;
    plane.kind = ElementKind::Plane;
    out.push_back({plane, ambientParameters(ElementKind::Plane)});
  }
  return out;
}

double rms(const VectorXd& r) { return std::sqrt(r.squaredNorm() / static_cast<double>(r.size())); }

Vector3d centroid(const Points3& p) {
  Vector3d g = Vector3d::Zero();
  for (const auto& x : p) g += x;
  return g / static_cast<double>(p.size());
}

const std::vector<ReferenceDataSet>& suite() {
  static const std::vector<ReferenceDataSet> s = referenceSuite();
  return s;
}

}  // namespace

TEST(ReferenceData, SuiteCoversEveryKindWithEasyAndHardSets) {
  std::map<ElementKind, std::pair<int, int>> count;  // well conditioned, hard
  std::set<std::string> names;
  for (const auto& s : suite()) {
    EXPECT_TRUE(names.insert(s.name).second) << "duplicate name " << s.name;
    EXPECT_GE(static_cast<int>(s.points.size()), minimumPoints(s.reference.kind)) << s.name;
    (s.well_conditioned ? count[s.reference.kind].first : count[s.reference.kind].second)++;
  }
  for (ElementKind k :
       {ElementKind::Line2D, ElementKind::Line3D, ElementKind::Plane, ElementKind::Circle2D,
        ElementKind::Circle3D, ElementKind::Sphere, ElementKind::Cylinder, ElementKind::Cone}) {
    EXPECT_GE(count[k].first, 2) << elementName(k) << ": near and far well-conditioned sets";
    EXPECT_GE(count[k].second, 1) << elementName(k) << ": at least one hard set";
  }
}

TEST(ReferenceData, GradientVanishesAtTheReference) {
  for (const auto& set : suite()) {
    Points3 p;
    for (const auto& problem : problemsOf(set, p)) {
      const VectorXd r = residuals(problem.element, p);
      if (r.norm() == 0.0 || set.reference_ssr_mm2 == 0.0) {
        // Exact fits (4-point sphere): every point on the reference.
        EXPECT_LT(r.cwiseAbs().maxCoeff(), 1e-12) << set.name;
        continue;
      }
      // Rounding of ~4e-14 mm in the centred distances over 2e-6 mm steps: ~1e-8 / sqrt(n).
      EXPECT_LT(gradientCancellation(problem.element, p, problem.params), 1e-7)
          << set.name << " (" << elementName(problem.element.kind) << " part)";
    }
  }
}

TEST(ReferenceData, GradientCheckDetectsUnprojectedDeviations) {
  // The check above has teeth: the same sets with extra deviations along the normals that
  // were not projected fail it by orders of magnitude.
  for (const auto& set : suite()) {
    if (set.reference_ssr_mm2 == 0.0) continue;
    ReferenceDataSet bad = set;
    for (size_t i = 0; i < bad.points.size(); ++i) {
      const double bump = (i % 3 == 0 ? 1.0 : -0.4) * 1e-3;
      bad.points[i] += bump * outwardNormal(set.reference, set.points[i]);
    }
    Points3 p;
    const auto problems = problemsOf(bad, p);
    EXPECT_GT(gradientCancellation(problems[0].element, p, problems[0].params), 1e-3) << set.name;
  }
}

TEST(ReferenceData, ReferenceIsALocalMinimum) {
  // Along every eigenvector v of J^T J (numerical, ambient parameters) the sum of squares
  // grows like the Gauss-Newton model |J v t|^2: the curvature of the distances times the
  // um deviations does not make the Hessian indefinite. Directions in the null space of the
  // ambient parametrisation (direction along itself, an axis point sliding along the axis)
  // must simply not decrease the sum. line3d is left to the principal-axis test below: its
  // unsigned distance has a Hessian term d * grad^2 d of order 1, so the Gauss-Newton model
  // of the distances does not predict its sum of squares.
  for (const auto& set : suite()) {
    if (set.reference_ssr_mm2 == 0.0 || set.reference.kind == ElementKind::Line3D) continue;
    Points3 p;
    for (const auto& problem : problemsOf(set, p)) {
      const VectorXd r0 = residuals(problem.element, p);
      const double ssr0 = r0.squaredNorm();
      const MatrixXd J = numericalJacobian(problem.element, p, problem.params);
      Eigen::SelfAdjointEigenSolver<MatrixXd> eig(J.transpose() * J);
      const double lmax = eig.eigenvalues().maxCoeff();
      const double target = 1e-4 * ssr0;  // increase probed, well above rounding (~1e-12)
      for (Eigen::Index k = 0; k < eig.eigenvalues().size(); ++k) {
        const double lambda = eig.eigenvalues()(k);
        const bool null_direction = lambda < 1e-12 * lmax;
        const double t = std::sqrt(target / std::max(lambda, 1e-12 * lmax));
        const VectorXd step = t * eig.eigenvectors().col(k);
        const double up =
            residuals(applied(problem.element, problem.params, step), p).squaredNorm();
        const double down =
            residuals(applied(problem.element, problem.params, -step), p).squaredNorm();
        const double rise = 0.5 * (up + down) - ssr0;
        if (null_direction) {
          EXPECT_GT(rise, -1e-9 * ssr0) << set.name << " null direction " << k;
        } else {
          EXPECT_GT(rise / (lambda * t * t), 0.5) << set.name << " eigen-direction " << k;
          EXPECT_LT(rise / (lambda * t * t), 2.0) << set.name << " eigen-direction " << k;
        }
      }
    }
  }
}

TEST(ReferenceData, LinesAndPlanesArePrincipalAxes) {
  // Lines and planes have a closed-form global LS solution: through the centroid, along the
  // largest (line) or the smallest (plane, circle3d's plane) principal direction of the
  // scatter. The reference must be it, with a clear eigenvalue gap.
  for (const auto& set : suite()) {
    const ElementKind kind = set.reference.kind;
    if (kind != ElementKind::Line2D && kind != ElementKind::Line3D && kind != ElementKind::Plane &&
        kind != ElementKind::Circle3D)
      continue;
    const Vector3d g = centroid(set.points);
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (const auto& x : set.points) scatter += (x - g) * (x - g).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);  // ascending eigenvalues
    const Vector3d d = set.reference.direction;
    const Vector3d w = g - set.reference.position_mm;
    const bool line = kind == ElementKind::Line2D || kind == ElementKind::Line3D;
    // Line2D: the scatter's z row is zero, so the line is the largest of the x-y ones.
    const Vector3d principal = eig.eigenvectors().col(line ? 2 : 0);
    const double angle = std::atan2(principal.cross(d).norm(), std::abs(principal.dot(d)));
    EXPECT_LT(angle, 1e-12) << set.name;
    if (line) {
      EXPECT_LT((w - d * d.dot(w)).norm(), 1e-10) << set.name << ": centroid on the line";
      EXPECT_GT(eig.eigenvalues()(2), 100.0 * eig.eigenvalues()(1)) << set.name;
    } else {
      EXPECT_LT(std::abs(d.dot(w)), 1e-10) << set.name << ": centroid on the plane";
      EXPECT_GT(eig.eigenvalues()(1), 100.0 * eig.eigenvalues()(0)) << set.name;
    }
  }
}

TEST(ReferenceData, SsrIsTheSumOfSquaredDistancesAtTheReference) {
  for (const auto& set : suite()) {
    // Raw coordinates, as a user of the data would compute it.
    const double ssr = residuals(set.reference, set.points).squaredNorm();
    EXPECT_LE(std::abs(ssr - set.reference_ssr_mm2), 1e-10 * set.reference_ssr_mm2 + 1e-22)
        << set.name << ": " << ssr << " vs " << set.reference_ssr_mm2;
  }
}

TEST(ReferenceData, RmsNoiseAsRequested) {
  const double noise = 2.5e-3;
  const Vector3d far(950.5, -1020.25, 730.0);
  std::vector<Element> refs(8);
  refs[0] = {ElementKind::Line2D, {10, 20, 0}, Vector3d(1, 2, 0).normalized()};
  refs[1] = {ElementKind::Line3D, far, Vector3d(1, 2, 3).normalized()};
  refs[2] = {ElementKind::Plane, far, Vector3d(-1, 0.2, 0.5).normalized()};
  refs[3] = {ElementKind::Circle2D, {5, 6, 0}, Vector3d::UnitZ(), 30.0};
  refs[4] = {ElementKind::Circle3D, far, Vector3d(0.3, 0.4, 1).normalized(), 40.0};
  refs[5] = {ElementKind::Sphere, far, Vector3d::UnitZ(), 20.0};
  refs[6] = {ElementKind::Cylinder, far, Vector3d(0.1, 1, 0).normalized(), 15.0};
  refs[7] = {ElementKind::Cone, far, Vector3d(0.1, 1, 0).normalized(), 15.0, 0.4};
  for (const Element& e : refs) {
    const int n = 17;
    const auto set = makeReferenceData(e, n, 2.0 * kPi, 50.0, noise, 99);
    SCOPED_TRACE(std::string(elementName(e.kind)));
    ASSERT_EQ(set.points.size(), static_cast<size_t>(n));
    EXPECT_NEAR(rms(residuals(set.reference, set.points)), noise, 1e-9 * noise);
    EXPECT_NEAR(set.reference_ssr_mm2, n * noise * noise, 1e-12 * n * noise * noise);
    if (e.kind == ElementKind::Circle3D) {
      Element plane = set.reference;
      plane.kind = ElementKind::Plane;
      EXPECT_NEAR(rms(residuals(plane, set.points)), noise, 1e-9 * noise) << "out of plane";
    }
  }
  // As many points as parameters: only the exact fit satisfies J^T e = 0.
  const auto exact = makeReferenceData(refs[5], 4, kPi, 0.0, noise, 5);
  EXPECT_EQ(exact.reference_ssr_mm2, 0.0);
  EXPECT_LT(residuals(exact.reference, exact.points).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ReferenceData, DeterministicForASeed) {
  const auto a = referenceSuite(42);
  const auto b = referenceSuite(42);
  const auto c = referenceSuite(43);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  bool any_difference = false;
  for (size_t s = 0; s < a.size(); ++s) {
    EXPECT_EQ(a[s].name, b[s].name);
    EXPECT_EQ(a[s].reference_ssr_mm2, b[s].reference_ssr_mm2) << a[s].name;
    ASSERT_EQ(a[s].points.size(), b[s].points.size());
    for (size_t i = 0; i < a[s].points.size(); ++i) {
      EXPECT_EQ(a[s].points[i], b[s].points[i]) << a[s].name << " point " << i;
      any_difference = any_difference || a[s].points[i] != c[s].points[i];
    }
  }
  EXPECT_TRUE(any_difference) << "another seed must give other data";
}

TEST(ReferenceData, SameNumbersOnEveryStandardLibrary) {
  // The generator draws its own uniforms and normals from mt19937_64 (whose sequence the
  // standard fixes), so these values must not change with the platform. Pinned to 1e-9 mm:
  // only the last bits of std::log/std::cos may differ between math libraries.
  const auto set = makeReferenceData({ElementKind::Sphere, {1, 2, 3}, Vector3d::UnitZ(), 10.0}, 6,
                                     kPi, 0.0, 1e-3, 7);
  const Vector3d p0(1.201084299140508, -5.2960642115884538, 9.8356159407127581);
  EXPECT_LT((set.points[0] - p0).norm(), 1e-9) << set.points[0].transpose();
  EXPECT_NEAR(signedDistance(set.reference, set.points[5]), 0.0012956257992637887, 1e-12);
}

TEST(ReferenceData, PositionsAndDirectionsFollowTheElementContract) {
  for (const auto& set : suite()) {
    const Element& e = set.reference;
    EXPECT_NEAR(e.direction.norm(), 1.0, 1e-15) << set.name;
    if (e.kind != ElementKind::Cone && e.kind != ElementKind::Sphere &&
        e.kind != ElementKind::Circle2D) {
      Eigen::Index k;
      e.direction.cwiseAbs().maxCoeff(&k);
      EXPECT_GT(e.direction(k), 0.0) << set.name << ": canonical sign";
    }
    const bool axis_or_plane = e.kind == ElementKind::Line2D || e.kind == ElementKind::Line3D ||
                               e.kind == ElementKind::Cylinder || e.kind == ElementKind::Cone ||
                               e.kind == ElementKind::Plane;
    if (!axis_or_plane) continue;
    // Lines and axes: the point nearest the centroid; planes: the foot of the centroid.
    const Vector3d g = centroid(set.points);
    const Vector3d foot =
        e.kind == ElementKind::Plane
            ? Vector3d(g - e.direction * e.direction.dot(g - e.position_mm))
            : Vector3d(e.position_mm + e.direction * e.direction.dot(g - e.position_mm));
    EXPECT_LT((foot - e.position_mm).norm(), 1e-9) << set.name;
  }
}

TEST(ReferenceData, HardCasesAreAsAdvertised) {
  // The spans the suite promises: short arcs, small caps, 4-point exact spheres, partial
  // cylinders and cones, data ~1000 mm from the origin.
  bool short_arc = false, small_cap = false, four_points = false, partial_cylinder = false,
       partial_cone = false, far = false;
  for (const auto& set : suite()) {
    const Element& e = set.reference;
    const Vector3d g = centroid(set.points);
    if (!set.well_conditioned && g.norm() > 1000.0) far = true;
    if (e.kind == ElementKind::Sphere && set.points.size() == 4) {
      four_points = true;
      EXPECT_EQ(set.reference_ssr_mm2, 0.0) << set.name;
    }
    // Largest angle subtended at the centre / axis, from the points themselves.
    double widest = 0.0;
    for (const auto& p : set.points)
      for (const auto& q : set.points) {
        Vector3d a = p - e.position_mm, b = q - e.position_mm;
        if (e.kind == ElementKind::Cylinder || e.kind == ElementKind::Cone ||
            e.kind == ElementKind::Circle3D) {
          a -= e.direction * e.direction.dot(a);
          b -= e.direction * e.direction.dot(b);
        }
        widest = std::max(widest, std::atan2(a.cross(b).norm(), a.dot(b)));
      }
    const double deg = 180.0 / kPi;
    if ((e.kind == ElementKind::Circle2D || e.kind == ElementKind::Circle3D) &&
        widest * deg <= 10.0 + 1e-6)
      short_arc = true;
    if (e.kind == ElementKind::Sphere && widest * deg <= 2 * 20.0 + 1e-6) small_cap = true;
    if (e.kind == ElementKind::Cylinder && widest * deg <= 90.0 + 1e-6) partial_cylinder = true;
    if (e.kind == ElementKind::Cone && widest * deg <= 90.0 + 1e-6) partial_cone = true;
  }
  EXPECT_TRUE(short_arc);
  EXPECT_TRUE(small_cap);
  EXPECT_TRUE(four_points);
  EXPECT_TRUE(partial_cylinder);
  EXPECT_TRUE(partial_cone);
  EXPECT_TRUE(far);
}

TEST(ReferenceData, RejectsRequestsWithoutAUniqueSolution) {
  const Element sphere{ElementKind::Sphere, {0, 0, 0}, Vector3d::UnitZ(), 10.0};
  EXPECT_THROW(makeReferenceData(sphere, 3, kPi, 0.0, 1e-3, 1), GeometryError);  // < 4 points
  EXPECT_THROW(makeReferenceData(sphere, 10, kPi, 0.0, -1e-3, 1), GeometryError);
  EXPECT_THROW(makeReferenceData(sphere, 10, 0.0, 0.0, 1e-3, 1), GeometryError);
  const Element cone{ElementKind::Cone, {0, 0, 0}, Vector3d::UnitZ(), 2.0, 0.5};
  try {
    makeReferenceData(cone, 20, 2.0 * kPi, 50.0, 1e-3, 1);  // crosses the apex
    FAIL();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("apex"), std::string::npos) << e.what();
  }
}
