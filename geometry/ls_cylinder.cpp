// Least-squares cylinder (ls_axis.hpp).
#include "geometry/ls_axis.hpp"

namespace probeloop::geometry::ls {
namespace {

template <bool Fixed>
FitResult fitCylinderWith(const Points3& pts, const Moments& m, const Axes& ax,
                          const LeastSquaresOptions& o) {
  using Model = CylinderModel<Fixed>;
  const auto run = fitAxisElement<Model>(pts, m, ax, o, false);
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition))
    fail(axisAdvice(ElementKind::Cylinder, pts, run.state, cond, Fixed));
  if (!run.converged)
    fail("least-squares cylinder did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations, give a start (options.start) or check that the "
         "points outline one cylinder");
  const AxisState& s = run.state;
  const Vector3d e3 = s.u.row(2).transpose();
  Element e;
  e.kind = ElementKind::Cylinder;
  e.direction = canonical(e3);
  e.position_mm = s.o + e3 * e3.dot(m.centroid - s.o);
  e.radius_mm = Fixed ? *o.fixed_radius_mm : s.r;
  const double sign = e.direction.dot(e3) > 0 ? 1.0 : -1.0;
  Eigen::MatrixXd g = axisJacobian(s, m.centroid, sign, Fixed ? 6 : 7, Model::P);
  if (!Fixed) g(6, 4) = 1.0;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
  if (!Fixed) names.push_back("r_mm");
  const ResidualStats stats = statsOf(run.lin);
  return makeResult(e, pts, Model::P, names, g * inverseNormal(run.lin) * g.transpose(),
                    run.iterations, o, &stats);
}

}  // namespace

FitResult fitCylinder(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkNotCollinear(ElementKind::Cylinder, pts, m, ax, "points around its axis",
                    "probe at several angles around the cylinder");
  checkNotCoplanar(ElementKind::Cylinder, pts, m, ax, "points off a single plane",
                   "probe at two or more levels along the axis and around it");
  return o.fixed_radius_mm ? fitCylinderWith<true>(pts, m, ax, o)
                           : fitCylinderWith<false>(pts, m, ax, o);
}


}  // namespace probeloop::geometry::ls
