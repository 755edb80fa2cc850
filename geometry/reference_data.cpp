// NIST-method reference data. For every kind the construction is
//   1. foot points x_i on the reference element (layout below),
//   2. the Jacobian J of the orthogonal distances with respect to a minimal local
//      parametrisation of the element at the reference (one row per residual),
//   3. Gaussian draws e with the column space of J projected out (J^T e = 0), scaled to the
//      requested RMS,
//   4. points p_i = x_i + e_i n_i, n_i the outward normal at x_i.
// The orthogonal distance of p_i from the reference is then e_i exactly, and because the
// gradient of an orthogonal distance with respect to the element parameters is constant
// along the normal through a foot point (d = n . (p - x(params)) and dn/dparam is
// orthogonal to n), J at the points equals J at the feet: the gradient J^T e of the sum of
// squares vanishes at the reference. With deviations small against the radii (um against
// mm) the Gauss-Newton term J^T J dominates the Hessian, so the stationary point is the
// minimum; reference_data_test.cpp checks both with an independent numerical Jacobian.
//
// Per kind (u, v: an orthonormal pair perpendicular to the element direction d):
//   line2d   residual = signed distance along the left normal; J = [1, t] (offset, turn).
//   line3d   the distance is unsigned and not differentiable on the line, so the
//            deviation has two components, along u and along v, each orthogonal to
//            [1, t] (2 offsets + 2 tilts); distance = sqrt(e_u^2 + e_v^2), and the RMS and
//            SSR are those of the distances. The LS line is then exact: the centroid lies on
//            the axis and d is the principal direction of the scatter.
//   plane    J = [1, s, w] (offset + 2 tilts), (s, w) the in-plane coordinates.
//   circle2d J = [cos th, sin th, 1] (centre 2 + radius); z = 0 everywhere.
//   circle3d The project's circle3d LS is the LS plane of the points, then the 2D LS circle
//            of the points projected onto that plane. The radial deviations e (the
//            circle3d residuals) are orthogonal to [cos th, sin th, 1]; the out-of-plane
//            deviations h, along d, are orthogonal to [1, s', w'] where (s', w') are the
//            in-plane coordinates of the radially displaced points. Then the LS plane is the
//            reference plane exactly (centroid on it, d an eigenvector of the scatter) and
//            the projections are the circle2d construction. Both have RMS noise_mm; the SSR
//            is sum e^2 (circle3d residuals are radial only, elements.hpp).
//   sphere   J = [n_i, 1] (centre 3 + radius); the cap is centred on the input direction.
//   cylinder J = [cos ph, sin ph, t cos ph, t sin ph, 1] (2 axis offsets, 2 tilts, radius).
//   cone     as the cylinder with the tilt columns (t cos a + rho sin a)(cos ph, sin ph),
//            the radius column 1 and the half-angle column t (constant factors dropped:
//            only the column space matters).
// When n <= p the deviations are zero: the points determine the element exactly.
//
// Position convention (elements.hpp): the axial coordinates t of the feet have mean zero,
// and J contains the constant column, so sum e = 0 and the centroid of the points projects
// onto `position_mm` for lines, axes and planes.
#include "geometry/reference_data.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.hpp"

namespace probeloop::geometry {
namespace {

using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double kGoldenRatioFraction = 0.6180339887498948482;  // (sqrt 5 - 1) / 2
constexpr double kGoldenAngle = 2.3999632297286533222;          // pi (3 - sqrt 5)

// mt19937_64's output sequence is fixed by the standard but the distributions are not
// (uniform_real_distribution and normal_distribution differ between libstdc++, libc++ and
// MSVC), so both are done here: the data are the same with every standard library (up to
// the last bit of std::log / std::cos in the Box-Muller transform).
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1): the top 53 bits of one draw.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }

  // Standard normal by Box-Muller; both values of a pair are used.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(engine_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * kPi * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * kPi * u2);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Largest-magnitude component positive (elements.hpp contract; first index on ties).
Vector3d canonicalSign(const Vector3d& d) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(d(i)) > std::abs(d(k))) k = i;
  return d(k) < 0.0 ? Vector3d(-d) : d;
}

// Orthonormal u, v with (u, v, d) right-handed; fixed rule so the layout is reproducible.
void perpendicularPair(const Vector3d& d, Vector3d& u, Vector3d& v) {
  const Vector3d a = std::abs(d.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  u = (a - d * d.dot(a)).normalized();
  v = d.cross(u);
}

// Stratified samples in [0, 1): one per bin of width 1/n, so layouts are irregular but
// cover the span evenly.
std::vector<double> stratified(int n, Random& rng) {
  std::vector<double> s(n);
  for (int i = 0; i < n; ++i) s[i] = (i + rng.uniform()) / n;
  return s;
}

// Axial coordinates over [-L/2, L/2] with mean exactly subtracted (position convention).
std::vector<double> centredAxial(int n, double length, Random& rng) {
  std::vector<double> t = stratified(n, rng);
  double mean = 0.0;
  for (double& x : t) {
    x = length * (x - 0.5);
    mean += x;
  }
  mean /= n;
  for (double& x : t) x -= mean;
  return t;
}

// Arc angles: a full circle is stratified; an arc keeps its two end points exactly so the
// requested span is the span of the data, interior points jittered within their bins.
std::vector<double> arcAngles(int n, double span, Random& rng) {
  const double start = 2.0 * kPi * rng.uniform();
  std::vector<double> th(n);
  if (span >= 2.0 * kPi) {
    for (int i = 0; i < n; ++i) th[i] = start + 2.0 * kPi * (i + rng.uniform()) / n;
  } else {
    for (int i = 0; i < n; ++i) {
      const double jitter = (i == 0 || i == n - 1) ? 0.0 : 0.5 * (rng.uniform() - 0.5);
      th[i] = start + span * (i + jitter) / (n - 1);
    }
  }
  return th;
}

// Sector angles for cylinders and cones, paired with stratified axial coordinates: a
// golden-ratio sequence spreads (t, phi) over the patch without a visible lattice.
std::vector<double> sectorAngles(int n, double span, Random& rng) {
  const double span_used = std::min(span, 2.0 * kPi);
  const double start = 2.0 * kPi * rng.uniform();
  const double offset = rng.uniform();
  std::vector<double> ph(n);
  for (int i = 0; i < n; ++i) {
    double f = offset + i * kGoldenRatioFraction;
    f -= std::floor(f);
    ph[i] = start + span_used * f;
  }
  return ph;
}

// Deviations e with J^T e = 0 and sqrt(sum e^2 / n) = rms. Always draws n normals so the
// random stream does not depend on the rank. Throws if the feet do not determine the
// element (rank(J) < p): then the least-squares solution is not unique.
VectorXd orthogonalDeviations(MatrixXd J, double rms, Random& rng, const std::string& what) {
  const Eigen::Index n = J.rows();
  const Eigen::Index p = J.cols();
  VectorXd e(n);
  for (Eigen::Index i = 0; i < n; ++i) e(i) = rng.normal();
  // Unit columns: the column space is unchanged and the rank test is scale free (tilt
  // columns are in mm, offsets dimensionless).
  for (Eigen::Index k = 0; k < p; ++k) {
    const double norm = J.col(k).norm();
    if (norm > 0.0) J.col(k) /= norm;
  }
  Eigen::ColPivHouseholderQR<MatrixXd> qr(J);
  qr.setThreshold(1e-13);
  if (qr.rank() < std::min(n, p))
    throw GeometryError("reference data: the foot points do not determine the " + what +
                        " (Jacobian rank " + std::to_string(qr.rank()) + " of " +
                        std::to_string(std::min(n, p)) + "); spread the points wider");
  if (n <= p || rms == 0.0) return VectorXd::Zero(n);
  const MatrixXd Q = qr.householderQ() * MatrixXd::Identity(n, p);
  // Projected twice: one pass leaves ~eps * cond components; the second removes them.
  for (int pass = 0; pass < 2; ++pass) e -= Q * (Q.transpose() * e);
  return e * (rms * std::sqrt(static_cast<double>(n)) / e.norm());
}

void require(bool ok, const std::string& message) {
  if (!ok) throw GeometryError("reference data: " + message);
}

// Optional layout beyond the public parameters: a plane patch of extent x width instead of
// a disc (the strip case of the suite).
struct Layout {
  int n = 0;
  double span_rad = 0.0;
  double extent_mm = 0.0;
  double plane_width_mm = 0.0;  // > 0: rectangle extent_mm x plane_width_mm
};

ReferenceDataSet generate(const Element& input, const Layout& layout, double noise,
                          std::uint64_t seed) {
  const int n = layout.n;
  const ElementKind kind = input.kind;
  const std::string kind_name(elementName(kind));
  require(n >= minimumPoints(kind), kind_name + " needs >= " + std::to_string(minimumPoints(kind)) +
                                        " points, got " + std::to_string(n));
  require(std::isfinite(noise) && noise >= 0.0, "noise must be finite and >= 0");
  require(input.position_mm.allFinite() && input.direction.allFinite() &&
              std::isfinite(input.radius_mm) && std::isfinite(input.half_angle_rad),
          "reference element has a NaN or infinite field");
  require(input.direction.norm() > 0.0, "reference direction is zero");

  Random rng(seed);
  ReferenceDataSet out;
  out.name = kind_name + "_n" + std::to_string(n);
  out.well_conditioned = true;
  out.points.resize(n);
  Element ref = input;
  ref.direction = input.direction.normalized();
  if (kind == ElementKind::Line2D || kind == ElementKind::Circle2D) {
    ref.position_mm.z() = 0.0;
    if (kind == ElementKind::Line2D) {
      ref.direction.z() = 0.0;
      require(ref.direction.norm() > 0.0, "line2d direction has no x-y component");
      ref.direction.normalize();
    } else {
      ref.direction = Vector3d::UnitZ();
    }
  }
  // Physical directions: the cone's points toward increasing radius, the sphere's is the cap
  // axis; the others carry the canonical sign of the contract.
  if (kind != ElementKind::Cone && kind != ElementKind::Sphere)
    ref.direction = canonicalSign(ref.direction);
  const Vector3d c = ref.position_mm;
  const Vector3d d = ref.direction;
  Vector3d u, v;
  perpendicularPair(d, u, v);

  const bool needs_extent = kind == ElementKind::Line2D || kind == ElementKind::Line3D ||
                            kind == ElementKind::Plane || kind == ElementKind::Cylinder ||
                            kind == ElementKind::Cone;
  const bool needs_span =
      !(kind == ElementKind::Line2D || kind == ElementKind::Line3D || kind == ElementKind::Plane);
  const bool needs_radius =
      !(kind == ElementKind::Line2D || kind == ElementKind::Line3D || kind == ElementKind::Plane);
  if (needs_extent) require(layout.extent_mm > 0.0, kind_name + " needs extent_mm > 0");
  if (needs_span) require(layout.span_rad > 0.0, kind_name + " needs span_rad > 0");
  if (needs_radius) require(ref.radius_mm > 0.0, kind_name + " needs radius_mm > 0");

  double ssr = 0.0;
  switch (kind) {
    case ElementKind::Line2D: {
      const std::vector<double> t = centredAxial(n, layout.extent_mm, rng);
      const Vector3d m(-d.y(), d.x(), 0.0);  // left normal: signedDistance > 0
      MatrixXd J(n, 2);
      for (int i = 0; i < n; ++i) J.row(i) << 1.0, t[i];
      const VectorXd e = orthogonalDeviations(J, noise, rng, kind_name);
      for (int i = 0; i < n; ++i) out.points[i] = c + t[i] * d + e(i) * m;
      ssr = e.squaredNorm();
      break;
    }
    case ElementKind::Line3D: {
      const std::vector<double> t = centredAxial(n, layout.extent_mm, rng);
      MatrixXd J(n, 2);
      for (int i = 0; i < n; ++i) J.row(i) << 1.0, t[i];
      // Each component gets unit RMS, then both are scaled together so the RMS distance is
      // `noise` (distance^2 = e_u^2 + e_v^2).
      const VectorXd eu = orthogonalDeviations(J, 1.0, rng, kind_name);
      const VectorXd ev = orthogonalDeviations(J, 1.0, rng, kind_name);
      const double scale = noise / std::sqrt(2.0);
      for (int i = 0; i < n; ++i)
        out.points[i] = c + t[i] * d + scale * eu(i) * u + scale * ev(i) * v;
      ssr = scale * scale * (eu.squaredNorm() + ev.squaredNorm());
      break;
    }
    case ElementKind::Plane: {
      std::vector<double> s(n), w(n);
      if (layout.plane_width_mm > 0.0) {
        const std::vector<double> a = stratified(n, rng);
        for (int i = 0; i < n; ++i) {
          s[i] = layout.extent_mm * (a[i] - 0.5);
          w[i] = layout.plane_width_mm * (rng.uniform() - 0.5);
        }
      } else {
        // Disc of diameter extent_mm with uniform area density (Vogel spiral, jittered).
        const double start = 2.0 * kPi * rng.uniform();
        const std::vector<double> a = stratified(n, rng);
        for (int i = 0; i < n; ++i) {
          const double r = 0.5 * layout.extent_mm * std::sqrt(a[i]);
          s[i] = r * std::cos(start + kGoldenAngle * i);
          w[i] = r * std::sin(start + kGoldenAngle * i);
        }
      }
      double ms = 0.0, mw = 0.0;
      for (int i = 0; i < n; ++i) {
        ms += s[i];
        mw += w[i];
      }
      ms /= n;
      mw /= n;
      MatrixXd J(n, 3);
      for (int i = 0; i < n; ++i) {
        s[i] -= ms;
        w[i] -= mw;
        J.row(i) << 1.0, s[i], w[i];
      }
      const VectorXd e = orthogonalDeviations(J, noise, rng, kind_name);
      for (int i = 0; i < n; ++i) out.points[i] = c + s[i] * u + w[i] * v + e(i) * d;
      ssr = e.squaredNorm();
      break;
    }
    case ElementKind::Circle2D:
    case ElementKind::Circle3D: {
      const std::vector<double> th = arcAngles(n, layout.span_rad, rng);
      const double R = ref.radius_mm;
      // Circle2D lives in x-y; u, v are then the x and y axes.
      const Vector3d eu = kind == ElementKind::Circle2D ? Vector3d::UnitX() : u;
      const Vector3d ev = kind == ElementKind::Circle2D ? Vector3d::UnitY() : v;
      MatrixXd J(n, 3);
      for (int i = 0; i < n; ++i) J.row(i) << std::cos(th[i]), std::sin(th[i]), 1.0;
      const VectorXd e = orthogonalDeviations(J, noise, rng, kind_name);
      std::vector<double> s(n), w(n);
      for (int i = 0; i < n; ++i) {
        s[i] = (R + e(i)) * std::cos(th[i]);
        w[i] = (R + e(i)) * std::sin(th[i]);
      }
      VectorXd h = VectorXd::Zero(n);
      if (kind == ElementKind::Circle3D) {
        MatrixXd P(n, 3);
        for (int i = 0; i < n; ++i) P.row(i) << 1.0, s[i], w[i];
        h = orthogonalDeviations(P, noise, rng, "circle3d plane");
      }
      for (int i = 0; i < n; ++i) out.points[i] = c + s[i] * eu + w[i] * ev + h(i) * d;
      ssr = e.squaredNorm();
      break;
    }
    case ElementKind::Sphere: {
      const double span = std::min(layout.span_rad, kPi);
      const double R = ref.radius_mm;
      const double start = 2.0 * kPi * rng.uniform();
      const std::vector<double> a = stratified(n, rng);
      std::vector<Vector3d> normal(n);
      MatrixXd J(n, 4);
      for (int i = 0; i < n; ++i) {
        // cos(polar) uniform over the cap: uniform area density.
        const double z = 1.0 - (1.0 - std::cos(span)) * a[i];
        const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
        const double az = start + kGoldenAngle * i;
        normal[i] = rho * std::cos(az) * u + rho * std::sin(az) * v + z * d;
        J.row(i) << normal[i].x(), normal[i].y(), normal[i].z(), 1.0;
      }
      const VectorXd e = orthogonalDeviations(J, noise, rng, kind_name);
      for (int i = 0; i < n; ++i) out.points[i] = c + (R + e(i)) * normal[i];
      ssr = e.squaredNorm();
      break;
    }
    case ElementKind::Cylinder:
    case ElementKind::Cone: {
      const bool cone = kind == ElementKind::Cone;
      const double a = cone ? ref.half_angle_rad : 0.0;
      if (cone) require(a > 0.0 && a < 0.5 * kPi, "cone needs 0 < half_angle_rad < pi/2");
      const std::vector<double> t = centredAxial(n, layout.extent_mm, rng);
      const std::vector<double> ph = sectorAngles(n, layout.span_rad, rng);
      const double ca = std::cos(a);
      const double sa = std::sin(a);
      const double ta = std::tan(a);
      MatrixXd J(n, cone ? 6 : 5);
      std::vector<Vector3d> radial(n);
      std::vector<double> rho(n);
      for (int i = 0; i < n; ++i) {
        radial[i] = std::cos(ph[i]) * u + std::sin(ph[i]) * v;
        rho[i] = ref.radius_mm + t[i] * ta;
        require(rho[i] > 0.0, "cone radius " + std::to_string(ref.radius_mm) +
                                  " mm at the position is too small for extent " +
                                  std::to_string(layout.extent_mm) +
                                  " mm: the data would cross the apex");
        const double tilt = t[i] * ca + rho[i] * sa;  // cylinder: t
        if (cone)
          J.row(i) << std::cos(ph[i]), std::sin(ph[i]), tilt * std::cos(ph[i]),
              tilt * std::sin(ph[i]), 1.0, t[i];
        else
          J.row(i) << std::cos(ph[i]), std::sin(ph[i]), tilt * std::cos(ph[i]),
              tilt * std::sin(ph[i]), 1.0;
      }
      const VectorXd e = orthogonalDeviations(J, noise, rng, kind_name);
      for (int i = 0; i < n; ++i) {
        const Vector3d normal = ca * radial[i] - sa * d;
        out.points[i] = c + t[i] * d + rho[i] * radial[i] + e(i) * normal;
      }
      ssr = e.squaredNorm();
      break;
    }
  }
  out.reference = ref;
  out.reference_ssr_mm2 = ssr;
  return out;
}

ReferenceDataSet named(ReferenceDataSet set, std::string name, bool well_conditioned) {
  set.name = std::move(name);
  set.well_conditioned = well_conditioned;
  return set;
}

Element element(ElementKind kind, const Vector3d& position, const Vector3d& direction,
                double radius = 0.0, double half_angle = 0.0) {
  Element e;
  e.kind = kind;
  e.position_mm = position;
  e.direction = direction.normalized();
  e.radius_mm = radius;
  e.half_angle_rad = half_angle;
  return e;
}

double deg(double degrees) { return degrees * kPi / 180.0; }

}  // namespace

ReferenceDataSet makeReferenceData(const Element& reference, int n, double span_rad,
                                   double extent_mm, double noise_mm, std::uint64_t seed) {
  Layout layout;
  layout.n = n;
  layout.span_rad = span_rad;
  layout.extent_mm = extent_mm;
  return generate(reference, layout, noise_mm, seed);
}

std::vector<ReferenceDataSet> referenceSuite(std::uint64_t seed) {
  using K = ElementKind;
  const double um = 1e-3;
  const double full = 2.0 * kPi;
  std::vector<ReferenceDataSet> suite;
  // Each set has its own stream derived from the suite seed, so adding a set does not
  // change the others.
  std::uint64_t k = 0;
  auto add = [&](const std::string& name, bool easy, const Element& e, int n, double span,
                 double extent, double noise, double plane_width = 0.0) {
    Layout layout;
    layout.n = n;
    layout.span_rad = span;
    layout.extent_mm = extent;
    layout.plane_width_mm = plane_width;
    ++k;
    suite.push_back(
        named(generate(e, layout, noise, seed + 0x9E3779B97F4A7C15ULL * k), name, easy));
  };
  const Vector3d far1(1012.25, -987.5, 603.125);
  const Vector3d far2(-995.75, 1003.5, -1008.25);

  // line2d: well conditioned near and far; hard: 5 mm long at ~1400 mm from the origin.
  add("line2d_100mm", true,
      element(K::Line2D, {12.5, -7.25, 0}, {std::cos(deg(25)), std::sin(deg(25)), 0}), 25, 0, 100,
      1 * um);
  add("line2d_300mm_far", true,
      element(K::Line2D, {1020.4, -980.7, 0}, {std::cos(deg(140)), std::sin(deg(140)), 0}), 40, 0,
      300, 1 * um);
  add("line2d_5mm_far", false,
      element(K::Line2D, {-995.1, 1003.3, 0}, {std::cos(deg(70)), std::sin(deg(70)), 0}), 12, 0, 5,
      1 * um);

  // line3d
  add("line3d_150mm", true, element(K::Line3D, {5, 10, -20}, {1, 0.3, -0.2}), 30, 0, 150, 1 * um);
  add("line3d_400mm_far", true, element(K::Line3D, far1, {0.2, 1, 0.4}), 40, 0, 400, 2 * um);
  add("line3d_8mm_far", false, element(K::Line3D, far2, {0.6, -0.5, 1}), 10, 0, 8, 1 * um);

  // plane: disc patches; hard: a 6 mm patch and a 200 x 2 mm strip far from the origin.
  add("plane_100mm", true, element(K::Plane, {3, -4, 12}, {0.05, -0.1, 1}), 40, 0, 100, 1 * um);
  add("plane_250mm_far", true, element(K::Plane, far1, {1, 0.2, 0.3}), 60, 0, 250, 2 * um);
  add("plane_6mm_far", false, element(K::Plane, far2, {-0.3, 0.4, 1}), 15, 0, 6, 1 * um);
  add("plane_strip_200x2mm_far", false, element(K::Plane, far1, {0.1, 1, -0.2}), 30, 0, 200, 1 * um,
      2.0);

  // circle2d: full circles; hard: 10 and 5 degree arcs.
  add("circle2d_r25_full", true, element(K::Circle2D, {10, 5, 0}, {0, 0, 1}, 25), 24, full, 0,
      1 * um);
  add("circle2d_r80_full_far", true, element(K::Circle2D, {1003.7, -996.2, 0}, {0, 0, 1}, 80), 36,
      full, 0, 2 * um);
  add("circle2d_arc10_r50_far", false, element(K::Circle2D, {-1001.3, 998.6, 0}, {0, 0, 1}, 50), 15,
      deg(10), 0, 1 * um);
  add("circle2d_arc5_r40", false, element(K::Circle2D, {20, -30, 0}, {0, 0, 1}, 40), 12, deg(5), 0,
      0.5 * um);

  // circle3d: LS plane, then the 2D LS circle of the projections.
  add("circle3d_r30_full", true, element(K::Circle3D, {4, -6, 15}, {0.2, -0.3, 1}, 30), 24, full, 0,
      1 * um);
  add("circle3d_r60_full_far", true, element(K::Circle3D, far2, {1, 1, 0.5}, 60), 30, full, 0,
      1 * um);
  add("circle3d_arc10_r100_far", false, element(K::Circle3D, far1, {0.3, -1, 0.2}, 100), 15,
      deg(10), 0, 1 * um);

  // sphere: full and hemisphere; hard: small caps far out, and the 4-point exact fits.
  add("sphere_r12p7_full", true, element(K::Sphere, {1, 2, 3}, {0, 0, 1}, 12.7), 25, kPi, 0,
      1 * um);
  add("sphere_r25_full_far", true, element(K::Sphere, far1, {0.2, 0.1, 1}, 25), 40, kPi, 0, 1 * um);
  add("sphere_r15_hemisphere_far", true, element(K::Sphere, far2, {0, 0, 1}, 15), 30, deg(90), 0,
      1 * um);
  add("sphere_cap20_r50_far", false, element(K::Sphere, far1, {1, -0.5, 0.3}, 50), 30, deg(20), 0,
      1 * um);
  add("sphere_cap10_r25", false, element(K::Sphere, {30, -40, 50}, {-0.2, 0.1, 1}, 25), 20, deg(10),
      0, 0.5 * um);
  add("sphere_4pt_r10", false, element(K::Sphere, {-5, 7, 2}, {0, 0, 1}, 10), 4, kPi, 0, 0.0);
  add("sphere_4pt_r20_far", false, element(K::Sphere, far2, {0.3, 0.3, 1}, 20), 4, deg(80), 0, 0.0);

  // cylinder: full; hard: 90 and 60 degree sectors, a long thin cylinder far out.
  add("cylinder_r20_full", true, element(K::Cylinder, {5, 5, 0}, {0.1, 0.2, 1}, 20), 40, full, 60,
      1 * um);
  add("cylinder_r50_full_far", true, element(K::Cylinder, far1, {1, 0.3, 0.1}, 50), 60, full, 100,
      2 * um);
  add("cylinder_sector90_r40_far", false, element(K::Cylinder, far2, {0.2, -1, 0.3}, 40), 40,
      deg(90), 80, 1 * um);
  add("cylinder_sector60_r25", false, element(K::Cylinder, {-20, 35, 10}, {0.4, 0.1, 1}, 25), 30,
      deg(60), 50, 1 * um);
  add("cylinder_long_thin_r3_L300_far", false, element(K::Cylinder, far1, {0.05, 0.1, 1}, 3), 50,
      full, 300, 1 * um);

  // cone: full; hard: 90 degree sectors, one far from the origin, one with a narrow apex.
  add("cone_a30_full", true, element(K::Cone, {2, -3, 10}, {0.1, -0.1, 1}, 20, deg(30)), 48, full,
      30, 1 * um);
  add("cone_a15_full_far", true, element(K::Cone, far2, {-0.3, 1, 0.2}, 30, deg(15)), 60, full, 60,
      1 * um);
  add("cone_a30_sector90_far", false, element(K::Cone, far1, {0.5, 0.2, -1}, 25, deg(30)), 40,
      deg(90), 40, 1 * um);
  add("cone_a10_sector90", false, element(K::Cone, {-15, 25, 40}, {0.2, 0.3, 1}, 15, deg(10)), 40,
      deg(90), 50, 1 * um);
  return suite;
}

}  // namespace probeloop::geometry
