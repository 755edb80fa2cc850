// Least-squares cone (ls_axis.hpp).
#include "geometry/ls_axis.hpp"

namespace probeloop::geometry::ls {

FitResult fitCone(const Points3& pts, const Moments& m, const Axes& ax,
                  const LeastSquaresOptions& o) {
  checkNotCollinear(ElementKind::Cone, pts, m, ax, "points around its axis",
                    "probe at several angles around the cone");
  checkNotCoplanar(ElementKind::Cone, pts, m, ax, "points off a single plane",
                   "probe at two or more levels along the axis and around it");
  const auto run = fitAxisElement<ConeModel>(pts, m, ax, o, true);
  const auto cond = conditioning(run.lin);
  if (run.lin.ok && std::abs(run.state.psi) < kMinHalfAngle)
    fail("cone: the fitted half angle is " + num(std::abs(run.state.psi)) +
         " rad, i.e. the apex angle is 0: these points lie on a cylinder; fit a cylinder instead");
  if (!run.lin.ok || !(cond.condition <= kMaxCondition))
    fail(axisAdvice(ElementKind::Cone, pts, run.state, cond, false));
  if (!run.converged)
    fail("least-squares cone did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations, give a start (options.start) or check that the "
         "points outline one cone");
  const AxisState& s = run.state;
  if (!(s.r > 0.0))
    fail("cone: the fitted apex lies among the points (radius " + num(s.r) +
         " mm at their centroid): measure one side of the apex only");
  const Vector3d e3 = s.u.row(2).transpose();
  // The reported direction points toward increasing radius.
  const double sign = s.psi > 0.0 ? 1.0 : -1.0;
  Element e;
  e.kind = ElementKind::Cone;
  e.direction = sign * e3;
  e.position_mm = s.o + e3 * e3.dot(m.centroid - s.o);
  e.radius_mm = s.r;
  e.half_angle_rad = std::abs(s.psi);
  Eigen::MatrixXd g = axisJacobian(s, m.centroid, sign, 8, 6);
  // Radius at the moved foot point: r + (a w1 + b w2) tan(psi); half angle flips with the sign.
  const Vector3d w = m.centroid - s.o;
  g(6, 2) = s.u.row(0).dot(w) * std::tan(s.psi);
  g(6, 3) = s.u.row(1).dot(w) * std::tan(s.psi);
  g(6, 4) = 1.0;
  g(7, 5) = sign;
  const ResidualStats stats = statsOf(run.lin);
  return makeResult(e, pts, 6, {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz", "r_mm", "half_angle_rad"},
                    g * inverseNormal(run.lin) * g.transpose(), run.iterations, o, &stats);
}


}  // namespace probeloop::geometry::ls
