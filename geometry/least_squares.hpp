// Least-squares (Gaussian) fits of every element: minimise the sum of squared orthogonal
// distances (ISO 10360-6, ASME B89.4.10).
//
// Contract:
// - Works relative to the centroid so data ~1000 mm from the origin with um noise keep
//   their digits; algebraic (linear) start, then Gauss-Newton / Levenberg-Marquardt on the
//   orthogonal distances, one pass over the points per iteration, solved by QR on the
//   Jacobian (not normal equations) where the conditioning needs it. Stable on short arcs
//   (<= 10 deg), spherical caps, 4-point spheres, cylinders and cones given as partial
//   surfaces.
// - Degenerate input (too few points for the kind, NaN/inf, duplicated points in sets up to
//   options.duplicate_search_max_points, collinear
//   points for a plane or circle, coplanar points for a sphere, a cap or arc too small to
//   fix a radius, a cone with zero apex angle...) throws GeometryError saying what is wrong
//   and what would fix it, e.g. "sphere needs >= 4 non-coplanar points; these 5 lie within
//   0.3 um of a plane: ...". Never returns NaN.
// - Result per elements.hpp, with parameter_names / covariance_unscaled filled.
#pragma once
#include <cstddef>
#include <optional>

#include "geometry/elements.hpp"

namespace probeloop::geometry {

struct LeastSquaresOptions {
  // Circle, sphere, cylinder: a known radius (only location/orientation are estimated).
  std::optional<double> fixed_radius_mm;
  int max_iterations = 100;
  // Optional start for the iterative fits (sphere, cylinder, cone); otherwise an algebraic
  // or PCA-based start is used. Only kind-compatible fields are read.
  std::optional<Element> start;
  // Fill FitResult::residuals_mm (signedDistance of every point). When false, ssr, rms,
  // form and dof come from the fit's last pass over the points and no per-point vector is
  // allocated (the iterative fits then read the points once per iteration, nothing more).
  bool keep_residuals = true;
  // Coincident points (within 1e-9 mm) are searched for in sets up to this size: probed
  // features, where a repeated point is a probing mistake that counts twice and can leave a
  // small set degenerate. Larger sets are scans, where repeated coordinates are legitimate
  // samples and the rank and conditioning checks still catch a degenerate cloud. The search
  // is a hash over a 1 nm grid, expected O(n) (about 10 ns a point); raise the limit to
  // search every set.
  std::size_t duplicate_search_max_points = 4096;
};

FitResult fitLeastSquares(ElementKind kind, const Points3& points,
                          const LeastSquaresOptions& options = {});

}  // namespace probeloop::geometry
