// One entry point for every element and method, with the options a CMM user sets:
// known radius, probe-tip compensation and outlier elimination.
//
// Contract:
// - fitElement dispatches to least squares, minimum zone, maximum inscribed or minimum
//   circumscribed (least_squares.hpp, minimum_zone.hpp).
// - Outlier elimination works as CMM software does it (Calypso "outlier elimination",
//   PC-DMIS "filter"): fit by least squares, drop every point whose |residual| exceeds
//   k times the standard deviation of the residuals s = sqrt(SSR / (n - p)), refit, and
//   repeat until no point is dropped or `max_rounds` is reached. The chosen method then
//   runs on the kept points. It refuses to drop more than `max_fraction` of the points or
//   to leave fewer than the element needs + 1: that is not an outlier any more but a
//   wrong element, and the error says so. Every dropped point is reported with its
//   residual to the final element.
// - Tip compensation (tip_compensation.hpp) is applied last, to the element only; the
//   residuals and form stay those of the tip-centre points.
#pragma once
#include <optional>
#include <vector>

#include "geometry/elements.hpp"
#include "geometry/tip_compensation.hpp"

namespace probeloop::geometry {

struct OutlierOptions {
  double k_sigma = 3.0;      // threshold in standard deviations of the residuals
  int max_rounds = 10;       // refits at most
  double max_fraction = 0.2; // refuse to drop more than this fraction of the points
};

struct TipCompensation {
  double tip_radius_mm = 0.0;
  MaterialSide side = MaterialSide::Inside;
};

struct FitOptions {
  FitMethod method = FitMethod::LeastSquares;
  std::optional<double> fixed_radius_mm;  // least squares only: a known radius
  std::optional<OutlierOptions> outliers;
  std::optional<TipCompensation> tip;
};

struct DroppedPoint {
  int index = 0;              // 0-based index into the input points
  int round = 0;              // 1-based elimination round that dropped it
  double residual_mm = 0.0;   // signed distance to the final element
};

struct ElementFit {
  FitResult fit;                    // on the kept points (indices in `kept`)
  Element tip_centre_element;       // before tip compensation (== fit.element without tip)
  std::vector<int> kept;            // input indices used in the final fit
  std::vector<DroppedPoint> dropped;
  int outlier_rounds = 0;
  double outlier_threshold_mm = 0.0;  // k * s of the last round (0 without elimination)
};

ElementFit fitElement(ElementKind kind, const Points3& points, const FitOptions& options);

}  // namespace probeloop::geometry
