#include "geometry/fit.hpp"

#include <cmath>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/minimum_zone.hpp"

namespace probeloop::geometry {
namespace {

FitResult runMethod(ElementKind kind, const Points3& pts, const FitOptions& o) {
  if (o.fixed_radius_mm && o.method != FitMethod::LeastSquares)
    throw GeometryError("a known radius applies to least-squares fits only (method " +
                        std::string(methodName(o.method)) + " determines the radius itself)");
  switch (o.method) {
    case FitMethod::LeastSquares: {
      LeastSquaresOptions ls;
      ls.fixed_radius_mm = o.fixed_radius_mm;
      return fitLeastSquares(kind, pts, ls);
    }
    case FitMethod::MinimumZone:
      return fitMinimumZone(kind, pts);
    case FitMethod::MaximumInscribed:
      return fitMaximumInscribed(kind, pts);
    case FitMethod::MinimumCircumscribed:
      return fitMinimumCircumscribed(kind, pts);
  }
  throw GeometryError("unknown fit method");
}

Points3 subset(const Points3& pts, const std::vector<int>& idx) {
  Points3 out;
  out.reserve(idx.size());
  for (int i : idx) out.push_back(pts[static_cast<size_t>(i)]);
  return out;
}

}  // namespace

ElementFit fitElement(ElementKind kind, const Points3& points, const FitOptions& o) {
  ElementFit out;
  out.kept.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) out.kept[i] = static_cast<int>(i);

  if (o.outliers) {
    const OutlierOptions& oo = *o.outliers;
    if (!(oo.k_sigma > 0.0) || oo.max_rounds < 1 || !(oo.max_fraction >= 0.0 && oo.max_fraction < 1.0))
      throw GeometryError("outlier elimination needs k > 0, at least 1 round and a maximum "
                          "fraction in [0, 1)");
    LeastSquaresOptions ls;
    ls.fixed_radius_mm = o.fixed_radius_mm;
    const size_t limit = static_cast<size_t>(std::floor(oo.max_fraction * points.size()));
    for (int round = 1; round <= oo.max_rounds; ++round) {
      const Points3 kept_pts = subset(points, out.kept);
      const FitResult f = fitLeastSquares(kind, kept_pts, ls);
      if (f.dof <= 0) break;  // an exact fit has no scatter to judge outliers by
      const double s = std::sqrt(f.residual_variance_mm2);
      const double threshold = oo.k_sigma * s;
      std::vector<int> next;
      std::vector<DroppedPoint> dropped_now;
      for (size_t j = 0; j < out.kept.size(); ++j) {
        if (std::abs(f.residuals_mm[j]) > threshold)
          dropped_now.push_back({out.kept[j], round, 0.0});
        else
          next.push_back(out.kept[j]);
      }
      out.outlier_rounds = round;
      out.outlier_threshold_mm = threshold;
      if (dropped_now.empty()) break;
      if (out.dropped.size() + dropped_now.size() > limit) {
        std::ostringstream m;
        m << "outlier elimination at " << oo.k_sigma << " sigma would drop "
          << out.dropped.size() + dropped_now.size() << " of " << points.size()
          << " points (limit " << limit << " = " << oo.max_fraction * 100
          << " %): the points do not look like one " << elementName(kind)
          << " with a few outliers; check the element type or raise the limit";
        throw GeometryError(m.str());
      }
      if (static_cast<int>(next.size()) < minimumPoints(kind) + 1) {
        throw GeometryError("outlier elimination would leave " + std::to_string(next.size()) +
                            " points, fewer than a " + std::string(elementName(kind)) +
                            " needs to judge scatter (" + std::to_string(minimumPoints(kind) + 1) +
                            "); probe more points or raise k");
      }
      out.dropped.insert(out.dropped.end(), dropped_now.begin(), dropped_now.end());
      out.kept = std::move(next);
    }
  }

  out.fit = runMethod(kind, subset(points, out.kept), o);
  out.tip_centre_element = out.fit.element;
  for (auto& d : out.dropped)
    d.residual_mm = signedDistance(out.tip_centre_element, points[static_cast<size_t>(d.index)]);
  if (o.tip && o.tip->tip_radius_mm > 0.0)
    out.fit.element = compensateTipRadius(out.fit.element, o.tip->tip_radius_mm, o.tip->side);
  return out;
}

}  // namespace probeloop::geometry
