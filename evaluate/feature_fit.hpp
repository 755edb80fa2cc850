// A single-feature fit as `probeloop fit` reports it: the element's parameters with
// standard uncertainties, form error and residual statistics, outliers dropped, tip
// compensation applied.
//
// Contract:
// - Parameters are reported in the element's representation (geometry/elements.hpp), plus
//   the derived size a metrologist asks for (diameter; cone apex angle in degrees).
// - Standard uncertainties (least squares only): u = sqrt(diag(J^T J)^-1 * s^2) with s^2 =
//   SSR / (n - p), type A with nu = n - p; with a point standard uncertainty given, type B
//   u = sqrt(diag(J^T J)^-1) * u_point instead (nu = inf). An exact fit (n = p) without
//   u_point has no uncertainty and says so. Chebyshev, inscribed and circumscribed fits
//   report no parameter uncertainty (their estimators are not linearisable in the GUM
//   sense); the report says so rather than printing a number.
// - The material side for tip compensation: per-point approach directions from the file
//   when present, else the side given by the user; neither with a tip radius > 0 is an
//   error.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "evaluate/point_cloud.hpp"
#include "geometry/fit.hpp"

namespace probeloop::evaluate {

struct FeatureFitRequest {
  geometry::ElementKind kind = geometry::ElementKind::Plane;
  geometry::FitOptions options;                // method, known radius, outliers
  double tip_radius_mm = 0.0;
  std::optional<geometry::MaterialSide> side;  // when the file has no approach directions
  std::optional<Eigen::Vector3d> approach;     // one nominal approach for every point
  std::optional<double> point_u_mm;            // type B point standard uncertainty
};

struct ReportedParameter {
  std::string name;  // with unit: x_mm, nx, r_mm, d_mm, half_angle_deg ...
  double value = 0.0;
  std::optional<double> u;  // standard uncertainty, same unit
};

struct FeatureFitReport {
  geometry::ElementKind kind;
  geometry::ElementFit fit;
  std::vector<ReportedParameter> parameters;
  std::string uncertainty_basis;
  double tip_radius_mm = 0.0;
  std::optional<geometry::MaterialSide> side_used;
  std::string side_source;  // "approach directions in the file", "--material", ...
  double residual_min_mm = 0, residual_max_mm = 0, residual_s_mm = 0;
  // What the user must know before trusting the u: too few degrees of freedom for a type A u
  // (nu < kMinDofForTypeA), or residuals at rounding level (s < kRoundingLevelMm).
  std::vector<std::string> warnings;
};

inline constexpr int kMinDofForTypeA = 5;          // t(95 %, nu = 5) = 2.57: already 28 % above k = 2
inline constexpr double kRoundingLevelMm = 1e-7;   // 0.1 nm: below any probe's resolution

FeatureFitReport fitFeature(const PointCloud& cloud, const FeatureFitRequest& request);
std::string featureFitJson(const PointCloud& cloud, const FeatureFitReport& report);
std::string featureFitText(const PointCloud& cloud, const FeatureFitReport& report);

}  // namespace probeloop::evaluate
