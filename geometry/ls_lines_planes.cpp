// Closed-form least-squares lines and planes (ls_detail.hpp): one pass of moments, then the
// eigenvectors of the 3x3 (2x2) scatter matrix give the exact LS line/plane through the
// centroid (orthogonal regression; Forbes, NPL DITC 140/89, sections 3-4; Shakarji, J. Res.
// NIST 103 (1998)).
#include "geometry/ls_detail.hpp"

namespace probeloop::geometry::ls {
namespace {

// Sum of squares and range of n.(p - c), four points at a time, in blocks (in an AVX2 and a
// default version, ls_detail.hpp).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
[[gnu::always_inline]] inline ResidualStats planeResidualStatsWith(const Points3& pts,
                                                                   const Vector3d& c,
                                                                   const Vector3d& nrm) {
  const std::size_t n = pts.size();
  const double* base = pts.front().data();
  ResidualStats out;
  const double inf = std::numeric_limits<double>::infinity();
  Quad lo = constant<Quad>(inf), hi = constant<Quad>(-inf);
  double tail_lo = inf, tail_hi = -inf;
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    Quad ss = constant<Quad>(0.0);
    double tail = 0.0;
    std::size_t i = b0;
    for (; i + 4 <= b1; i += 4) {
      const Quad d = (gather<Quad>(base, i, 3, 0) - c.x()) * nrm.x() +
                     (gather<Quad>(base, i, 3, 1) - c.y()) * nrm.y() +
                     (gather<Quad>(base, i, 3, 2) - c.z()) * nrm.z();
      ss += d * d;
      lo = lowerOf(lo, d);
      hi = higherOf(hi, d);
    }
    for (; i < b1; ++i) {
      const double d = (base[3 * i] - c.x()) * nrm.x() + (base[3 * i + 1] - c.y()) * nrm.y() +
                       (base[3 * i + 2] - c.z()) * nrm.z();
      tail += d * d;
      tail_lo = std::min(tail_lo, d);
      tail_hi = std::max(tail_hi, d);
    }
    out.ssr += ((ss[0] + ss[1]) + (ss[2] + ss[3])) + tail;
  }
  out.min = std::min({tail_lo, lo[0], lo[1], lo[2], lo[3]});
  out.max = std::max({tail_hi, hi[0], hi[1], hi[2], hi[3]});
  return out;
}
[[gnu::target("avx2")]] ResidualStats planeResidualStatsAvx2(const Points3& pts,
                                                             const Vector3d& c,
                                                             const Vector3d& nrm) {
  return planeResidualStatsWith(pts, c, nrm);
}
ResidualStats planeResidualStats(const Points3& pts, const Vector3d& c, const Vector3d& nrm) {
  return useAvx2Passes() ? planeResidualStatsAvx2(pts, c, nrm)
                         : planeResidualStatsWith(pts, c, nrm);
}
#pragma GCC diagnostic pop

}  // namespace

FitResult fitLine2D(const Points3& pts, const Moments& m, const LeastSquaresOptions& o) {
  const std::size_t n = pts.size();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(m.cov.topLeftCorner<2, 2>());
  const Vector2d lam = es.eigenvalues().cwiseMax(0.0);
  if (std::sqrt(lam(1)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " line2d points coincide in x, y (within " +
         num(kCoincidentMm) + " mm): probe points spread along the line");
  if (lam(1) - lam(0) <= 1e-12 * lam(1))
    fail("line2d: the " + std::to_string(n) + " points spread equally in every direction, so no "
         "line is preferred: probe points along the line");
  Vector2d d = es.eigenvectors().col(1);
  d = canonical(Vector3d(d.x(), d.y(), 0.0)).head<2>();
  const Vector2d nrm(-d.y(), d.x());
  Element e;
  e.kind = ElementKind::Line2D;
  e.position_mm = Vector3d(m.centroid.x(), m.centroid.y(), 0.0);
  e.direction = Vector3d(d.x(), d.y(), 0.0);
  // Local parameters: offset t along the normal, rotation a (d' = d + a nrm). J_i = [-1,
  // -s_i] with s_i the coordinate along the line, so J^T J = diag(n, n var_along).
  const double dn = static_cast<double>(n);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(4, 2);
  g.block<2, 1>(0, 0) = nrm;
  g.block<2, 1>(2, 1) = nrm;
  const Eigen::Vector2d local(1.0 / dn, 1.0 / (dn * lam(1)));
  return makeResult(e, pts, 2, {"x_mm", "y_mm", "dx", "dy"},
                    g * local.asDiagonal() * g.transpose(), 0, o);
}

FitResult fitLine3D(const Points3& pts, const Moments& m, const Axes& ax,
                    const LeastSquaresOptions& o) {
  const std::size_t n = pts.size();
  checkNotCoincident(ElementKind::Line3D, ax, n);
  if (ax.value(2) - ax.value(1) <= 1e-12 * ax.value(2))
    fail("line3d: the " + std::to_string(n) + " points spread equally in two directions, so no "
         "line is preferred: probe points along the line");
  Element e;
  e.kind = ElementKind::Line3D;
  e.position_mm = m.centroid;
  e.direction = canonical(ax.vec.col(2));
  // Local parameters: axis point offsets u, v along the other principal axes ea, eb and
  // tilts a, b toward them. The distance components are ea.q - u - a s, eb.q - v - b s, so
  // J^T J = diag(n, n, n var_along, n var_along).
  const double sign = e.direction.dot(ax.vec.col(2)) > 0 ? 1.0 : -1.0;
  const Vector3d ea = ax.vec.col(1), eb = ax.vec.col(0);
  const double dn = static_cast<double>(n);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6, 4);
  g.block<3, 1>(0, 0) = ea;
  g.block<3, 1>(0, 1) = eb;
  g.block<3, 1>(3, 2) = sign * ea;
  g.block<3, 1>(3, 3) = sign * eb;
  const Eigen::Vector4d local(1.0 / dn, 1.0 / dn, 1.0 / (dn * ax.value(2)),
                              1.0 / (dn * ax.value(2)));
  return makeResult(e, pts, 4, {"x_mm", "y_mm", "z_mm", "dx", "dy", "dz"},
                    g * local.asDiagonal() * g.transpose(), 0, o);
}

FitResult fitPlane(const Points3& pts, const Moments& m, const Axes& ax,
                   const LeastSquaresOptions& o) {
  checkPlaneDetermined(ElementKind::Plane, pts, m, ax);
  Element e;
  e.kind = ElementKind::Plane;
  e.position_mm = m.centroid;  // the LS plane contains the centroid: it is its own foot
  e.direction = canonical(ax.vec.col(0));
  const double sign = e.direction.dot(ax.vec.col(0)) > 0 ? 1.0 : -1.0;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6, 3);
  g.block<3, 1>(0, 0) = ax.vec.col(0);
  g.block<3, 1>(3, 1) = sign * ax.vec.col(2);
  g.block<3, 1>(3, 2) = sign * ax.vec.col(1);
  const Eigen::Vector3d local = planeLocalCovariance(ax, pts.size());
  ResidualStats stats;
  if (!o.keep_residuals) stats = planeResidualStats(pts, e.position_mm, e.direction);
  return makeResult(e, pts, 3, {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"},
                    g * local.asDiagonal() * g.transpose(), 0, o,
                    o.keep_residuals ? nullptr : &stats);
}

}  // namespace probeloop::geometry::ls
