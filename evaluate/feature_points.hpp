// Stated features as points (issue 34, docs/formats.md#evaluating-from-features): when a CMM file
// holds only the fitted features, the plan's points of each matched feature are placed on the
// feature as the file states it:
// - plane: each planned point projected along the stated normal onto the stated plane;
// - cylinder or circle: moved radially (perpendicular to the stated axis) onto the surface of
//   the stated diameter about the stated axis;
// - sphere: moved along the ray from the stated centre onto the stated diameter.
// A least-squares fit of the placed points returns the stated feature exactly, so every formula
// of a point route gives, from them, what it gives from the CMM's own least-squares fit; and
// the budget's sensitivities come from the planned layout, the points the CMM was asked for.
//
// What this cannot know (said in every output that uses it): the CMM's fitting criterion (taken
// as least squares; a minimum-zone or Chebyshev fit differs by a fraction of the form), the
// points' real layout and residuals (the type A scatter is estimated from the stated form by
// sigmaFromForm), outliers, and the line of each point.
//
// Contract: InputError naming the row (file:line) for a matched feature the plan has no points
// for, a circle/cylinder/sphere without a positive diameter, and a planned point on the stated
// axis or at the stated centre (no radial direction).
#pragma once
#include <Eigen/Dense>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "evaluate/feature_match.hpp"
#include "evaluate/ttp_ingest.hpp"

namespace probeloop::evaluate {

// What the file states about one feature's points, for the budget.
struct StatedScatter {
  std::string id;     // manifest id
  std::string row;    // the file's id and line, "PLN_7 (f.csv:12)"
  int n_stated = 0;   // the file's point count (0: not stated)
  int n_planned = 0;  // the plan's points placed on it
  double form_um = 0;                   // NaN: not stated
  double sigma_from_form_mm = 0;        // NaN: no form or too few points to estimate
  std::optional<Eigen::Vector3d> u_um;  // the stated standard uncertainty of the location
  // Each placed point stands for n_stated / n_planned measured ones: per-point scatter times
  // sqrt(n_planned / n_stated) gives the u of the stated fit (1 when n is not stated).
  double point_scale = 1.0;
};

struct PointsOnStatedFeatures {
  TtpPoints points;                              // labelled with manifest ids, line = the row's
  std::map<std::string, StatedScatter> scatter;  // by manifest id
};

// planned: manifest feature id -> its planned surface points in the part frame (the frame the
// file states the features in).
PointsOnStatedFeatures pointsOnStatedFeatures(const FeatureMatch& match,
                                              const std::map<std::string, std::vector<Eigen::Vector3d>>& planned,
                                              const std::string& file, const std::string& format);

// What the file says about how its features were fitted, as one sentence for the notes: all
// stated least squares (the point route's criterion), some another criterion (named, with their
// ids: their values differ from least squares' by a fraction of their form, taken as stated),
// none stated (taken as least squares). A name counts as least squares when, case, spaces, '_'
// and '-' ignored, it is LEASTSQUARES, LSQ or LS.
std::string fittingCriterionNote(const FeatureMatch& match);
bool isLeastSquares(const std::string& algorithm);

// d2(n): the expected range of n independent standard normal deviates (n >= 2), by numerical
// integration of E[R] = int (1 - Phi(x)^n - (1 - Phi(x))^n) dx (ISO 8258 / ASTM E2587 tabulate
// it: d2(2) = 1.128, d2(5) = 2.326, d2(10) = 3.078).
double expectedRangeOfNormals(int n);

// The standard deviation of a point's deviation estimated from a least-squares fit's form (the
// range of its residuals) over n points with p fitted parameters: form / (d2(n) sqrt((n - p)/n)),
// the residuals' range taken as that of n - p dof scaled to n points (an approximation: the
// residual range of a fit is a little below the errors' range). NaN for n <= p or no form.
double sigmaFromForm(double form_mm, int n, int parameters);

}  // namespace probeloop::evaluate
