#include "geometry/sphere_fit.hpp"

#include <cmath>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"

namespace probeloop::geometry {

// The sphere-artifact evaluation's fit in its own terms, computed by the one LS engine
// (least_squares.hpp, ls_sphere.cpp): one estimator, one implementation (issue 29). The
// engine's covariance (x, y, z and, free, r) is laid into the 4x4 of cx, cy, cz, r.
SphereFit fitSphere(const std::vector<Eigen::Vector3d>& points_mm, const SphereFitOptions& options) {
  if (options.fixed_radius_mm && !(std::isfinite(*options.fixed_radius_mm) && *options.fixed_radius_mm > 0.0))
    throw GeometryError("known sphere radius must be a positive number");
  LeastSquaresOptions o;
  o.fixed_radius_mm = options.fixed_radius_mm;
  o.max_iterations = options.max_iterations;
  const FitResult r = fitLeastSquares(ElementKind::Sphere, points_mm, o);
  SphereFit out;
  out.centre_mm = r.element.position_mm;
  out.radius_mm = r.element.radius_mm;
  out.radius_fixed = options.fixed_radius_mm.has_value();
  out.residuals_mm = r.residuals_mm;
  out.rms_mm = r.rms_mm;
  out.form_mm = r.form_mm;
  out.dof = r.dof;
  out.residual_variance_mm2 = r.residual_variance_mm2;
  out.iterations = r.iterations;
  const auto np = static_cast<Eigen::Index>(r.parameter_names.size());
  if (r.covariance_unscaled.rows() != np || np < 3 || np > 4)
    throw GeometryError("sphere fit: the least-squares engine gave no covariance of the centre");
  out.covariance_unscaled.setZero();
  out.covariance_unscaled.topLeftCorner(np, np) = r.covariance_unscaled;
  return out;
}

}  // namespace probeloop::geometry
