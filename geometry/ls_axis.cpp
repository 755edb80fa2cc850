// Non-template parts of the cylinder and cone fits (ls_axis.hpp).
#include "geometry/ls_axis.hpp"

namespace probeloop::geometry::ls {

AxisState recentred(const Vector3d& o, const Vector3d& dir, double r, double psi,
                    const Vector3d& centroid) {
  AxisState s;
  const double t = dir.dot(centroid - o);
  s.o = o + t * dir;
  s.u = frameOf(dir);
  s.r = r + t * std::tan(psi);
  s.psi = psi;
  return s;
}

std::optional<AxisState> algebraicAxis(const Points3& pts, const Vector3d& centroid, double size,
                                       const Vector3d& dir, bool cone,
                                       const std::optional<double>& fixed) {
  const Matrix3d u = frameOf(dir);
  Mat<5> a = Mat<5>::Zero();
  Vec<5> b = Vec<5>::Zero();
  double s2 = 0.0;
  for (const auto& p : pts) {
    const Vector3d q = u * (p - centroid) / size;
    const double w = q.x() * q.x() + q.y() * q.y();
    const Vec<5> v(q.x(), q.y(), 1.0, q.z(), q.z() * q.z());
    a.selfadjointView<Eigen::Upper>().rankUpdate(v);
    b += v * w;
    s2 += w;
  }
  s2 /= static_cast<double>(pts.size());
  const int k = cone ? 5 : 3;
  const Eigen::MatrixXd full = Mat<5>(a.selfadjointView<Eigen::Upper>());
  const Eigen::VectorXd x = full.topLeftCorner(k, k).colPivHouseholderQr().solve(b.head(k));
  if (!x.allFinite()) return std::nullopt;
  Vector2d c(0.5 * x(0), 0.5 * x(1));
  const double r2 = x(2) + c.squaredNorm();
  if (!(r2 > 0.0)) return std::nullopt;
  double r = std::sqrt(r2);
  const double t = cone ? x(3) / (2.0 * r) : 0.0;
  c *= size;
  r *= size;
  if (fixed) {
    c = knownRadiusCentre<Vector2d>(Vector2d::Zero(), s2 * size * size, c, *fixed,
                                    Vector2d::UnitX());
    r = *fixed;
  }
  AxisState s;
  s.u = u;
  s.o = centroid + u.transpose() * Vector3d(c.x(), c.y(), 0.0);
  s.r = r;
  s.psi = std::atan(t);
  if (!s.o.allFinite() || !std::isfinite(s.r) || !std::isfinite(s.psi)) return std::nullopt;
  return s;
}

std::optional<AxisState> userAxisStart(const LeastSquaresOptions& o, const Points3& pts,
                                       const Moments& m, bool cone) {
  if (!o.start) return std::nullopt;
  const Element& s = *o.start;
  if (s.kind != ElementKind::Cylinder && s.kind != ElementKind::Cone &&
      s.kind != ElementKind::Line3D && s.kind != ElementKind::Circle3D)
    return std::nullopt;
  if (!s.position_mm.allFinite() || !s.direction.allFinite() || !(s.direction.norm() > 0.0))
    return std::nullopt;
  const Vector3d dir = s.direction.normalized();
  if (cone && s.kind == ElementKind::Cone && s.radius_mm > 0.0 && s.half_angle_rad > 0.0 &&
      s.half_angle_rad < 0.5 * kPi)
    return recentred(s.position_mm, dir, s.radius_mm, s.half_angle_rad, m.centroid);
  if (!cone && (s.kind == ElementKind::Cylinder || s.kind == ElementKind::Circle3D) &&
      (o.fixed_radius_mm || s.radius_mm > 0.0))
    return recentred(s.position_mm, dir, o.fixed_radius_mm ? *o.fixed_radius_mm : s.radius_mm,
                     0.0, m.centroid);
  return algebraicAxis(pts, m.centroid, rmsSize(m), dir, cone, o.fixed_radius_mm);
}

bool sameAxisElement(const AxisState& a, const AxisState& b, double size) {
  const Vector3d da = a.u.row(2).transpose(), db = b.u.row(2).transpose();
  const double dot = da.dot(db);
  const Vector3d off = b.o - a.o;
  return std::abs(dot) >= 1.0 - 1e-12 && (off - da * da.dot(off)).norm() <= 1e-6 * size &&
         std::abs(a.r - b.r) <= 1e-6 * size &&
         std::abs(a.psi - std::copysign(1.0, dot) * b.psi) <= 1e-6;
}

Eigen::MatrixXd axisJacobian(const AxisState& s, const Vector3d& centroid, double sign,
                             int rows, int cols) {
  const Vector3d e1 = s.u.row(0).transpose(), e2 = s.u.row(1).transpose(),
                 e3 = s.u.row(2).transpose();
  const Vector3d w = centroid - s.o;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(rows, cols);
  g.block<3, 1>(0, 0) = e1;
  g.block<3, 1>(0, 1) = e2;
  g.block<3, 1>(0, 2) = e1.dot(w) * e3;
  g.block<3, 1>(0, 3) = e2.dot(w) * e3;
  g.block<3, 1>(3, 2) = sign * e1;
  g.block<3, 1>(3, 3) = sign * e2;
  return g;
}

}  // namespace probeloop::geometry::ls
