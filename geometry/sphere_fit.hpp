// Least-squares (Gaussian) sphere fit minimising the sum of squared orthogonal distances.
//
// Contract:
// - points are in mm; with the fixed-radius option the radius is known (e.g. R_sphere +
//   r_tip for stylus-tip centres) and only the centre is estimated.
// - needs >= 4 finite, distinct, non-coplanar points (free and fixed radius alike: a known
//   radius with coplanar points leaves a mirror ambiguity); otherwise GeometryError says
//   what is wrong and what would fix it. Never returns NaN.
// - covariance_unscaled = (J^T J)^-1 at the solution; multiply by a point standard
//   uncertainty squared (type B) or by residual_variance (type A, needs dof > 0).
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <vector>

namespace probeloop::geometry {

struct SphereFitOptions {
  std::optional<double> fixed_radius_mm;  // known radius; estimate the centre only
  int max_iterations = 100;
};

struct SphereFit {
  Eigen::Vector3d centre_mm;
  double radius_mm = 0.0;
  bool radius_fixed = false;
  std::vector<double> residuals_mm;  // signed orthogonal distance, outside positive
  double rms_mm = 0.0;
  double form_mm = 0.0;  // max - min residual (peak to valley)
  int dof = 0;           // n - parameters
  double residual_variance_mm2 = 0.0;  // SSR / dof, 0 when dof == 0
  Eigen::Matrix4d covariance_unscaled = Eigen::Matrix4d::Zero();  // cx, cy, cz, r
  int iterations = 0;
};

SphereFit fitSphere(const std::vector<Eigen::Vector3d>& points_mm,
                    const SphereFitOptions& options = {});

}  // namespace probeloop::geometry
