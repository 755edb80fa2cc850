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

// What the file states about one feature's points, for the budget. Sigmas are per measured
// point; a placed point carries sigma x point_scale.
struct StatedScatter {
  std::string id;     // manifest id
  std::string row;    // the file's id and line, "PLN_7 (f.csv:12)"
  std::string kind;   // the row's kind (plane, circle, cylinder, sphere)
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // the stated normal or axis
  int n_stated = 0;   // the file's point count (0: not stated)
  int n_planned = 0;  // the plan's points placed on it
  double form_um = 0;                   // NaN: not stated
  double sigma_from_form_mm = 0;        // NaN: no form or too few points to estimate
  double form_dof = 0;                  // its degrees of freedom, min(rangeDof(n), n - p) (0: no form)
  std::optional<Eigen::Vector3d> u_um;  // the stated standard uncertainty of the location
  // The points the scatter averages over: the stated count, but never more than the plan's. A
  // scanning CMM states thousands of strongly correlated points, and the MPE, mostly systematic,
  // does not average down with them: U is never taken below the planned layout's.
  int nFit() const { return n_stated > 0 ? n_stated : n_planned; }
  int nAveraging() const { return nFit() < n_planned ? nFit() : n_planned; }
  // sqrt(n_planned / nAveraging()) >= 1: each placed point stands for that many measured ones.
  double point_scale = 1.0;
  // The sigma per measured point a stated u of the location implies over nAveraging() points:
  // a plane's offset is sigma / sqrt(n) along its normal; a circle's or cylinder's centre sigma
  // sqrt(2 / n) across its axis; a sphere's centre sigma sqrt(3 / n). NaN: no u stated.
  double sigmaFromStatedU_mm() const;
};

struct PointsOnStatedFeatures {
  TtpPoints points;                              // labelled with manifest ids, line = the row's
  std::map<std::string, StatedScatter> scatter;  // by manifest id
};

// planned: manifest feature id -> its planned surface points in the part frame (the frame the
// file states the features in).
// A row that fits no feature of the plan, as the notes and outputs list it:
// "file:line: kind 'id' (nearest F, d mm: why)".
std::string unmatchedText(const UnmatchedFeature& u);
// The notes every features route adds after its own: features stating more points than the plan
// (not averaged below the planned layout), features without a stated form or u (U may be below
// the point route's: a rough surface is invisible without its form). Empty when neither.
std::vector<std::string> statedScatterNotes(const std::map<std::string, StatedScatter>& s);
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

// d3(n): the standard deviation of the range of n standard normal deviates, by numerical
// integration of E[R^2] = 2 int int_{x<y} (1 - Phi(y)^n - (1 - Phi(x))^n + (Phi(y) - Phi(x))^n)
// (ASTM E2587 tabulates it: d3(2) = 0.853, d3(12) = 0.778).
double rangeStdOfNormals(int n);
// The degrees of freedom of a sigma estimated from one range of n points: 1/2 (d2/d3)^2 (the
// relative standard deviation of the estimate is d3/d2; JCGM 100 G.4.2). 0 for n < 2.
double rangeDof(int n);

}  // namespace probeloop::evaluate
