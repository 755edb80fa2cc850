// Evaluation of a sphere-artifact campaign (seed 004 Ch. 5): probe records -> one sphere
// fit per (cycle, position) -> location errors of every complete cycle relative to the
// reference cycle, by both estimators, each value with its GUM budget.
//
// Contract:
// - A cycle is complete when every position has >= 4 points; incomplete cycles are listed
//   with the reason and left out (a partial campaign still evaluates).
// - The reference is the first complete cycle (cycle 1 when it is complete).
// - The least-squares estimator uses the positions that are not repeats (the 5th position
//   of the thesis repeats the 1st and is reported as a repeatability indicator).
// - Every least-squares value carries the budget of evaluate/location_budget.hpp (probe
//   scatter type A/B, resolution, tool change, form, artifact expansion, d/2, drift during
//   the cycle), for this cycle and the reference cycle; the reference cycle's errors are 0
//   by definition and carry an empty budget.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "evaluate/feature_actuals.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/location_budget.hpp"
#include "geometry/location_errors.hpp"
#include "geometry/sphere_fit.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

// One sphere's share of the pooled type-A point scatter: rms^2 x points of its free-radius
// fit (mm^2) and its degrees of freedom.
struct ScatterTerm {
  int cycle = 0, position = 0;
  double ssr_mm2 = 0, dof = 0;
};

struct EvaluateOptions {
  bool known_radius = true;  // centre from the known-radius fit (R_sphere + r_tip)
  double coverage_k = 2.0;
  // Terms of cycles evaluated before and not passed in (a campaign store evaluates each new
  // cycle with the reference cycle alone), in cycle order: pooled in cycle order with those of
  // the cycles passed in, so that the result is the one of evaluating all those cycles at once,
  // to the last bit.
  std::vector<ScatterTerm> prior_scatter;
};

struct SphereMeasurement {
  int position = 0;
  int points = 0;
  double time_s = 0;  // mean (logged or planned) time of its points
  std::array<uncertainty::Budget, 3> centre_budgets;  // x, y, z of the centre used (um)
  geometry::SphereFit known_radius;       // radius fixed to R_sphere + r_tip
  std::optional<geometry::SphereFit> free_radius;  // absent when not determinable
  std::string free_radius_note;
  bool use_free_radius = false;  // --free-radius: centres from the free fit
  // The centre read from a feature file instead of a fit (the fits above are then empty).
  std::optional<StatedCentre> stated;
  FeatureCentreU stated_u;
  const geometry::SphereFit& used() const { return use_free_radius ? *free_radius : known_radius; }
  Eigen::Vector3d centre_mm() const { return stated ? stated->feature.location_mm : used().centre_mm; }
  Eigen::Matrix3d centre_cov_unscaled() const {
    return stated ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(used().covariance_unscaled.topLeftCorner<3, 3>());
  }
};

struct RepeatIndicator {
  int position = 0, repeat_of = 0;
  Eigen::Vector3d difference_um = Eigen::Vector3d::Zero();  // centre(position) - centre(repeat_of)
};

struct CycleEvaluation {
  int cycle = 0;
  double time_s = 0;  // mean planned (or logged) time of the cycle's points
  std::vector<SphereMeasurement> spheres;  // manifest order
  geometry::LocationErrors least_squares;
  std::optional<geometry::LocationErrors> formulas;  // seed 004 Eqs. 5.4-5.10
  std::array<uncertainty::Budget, 7> budgets;        // for the least-squares values
  double model_residual_xy_um = 0, model_residual_z_um = 0;
  std::vector<RepeatIndicator> repeats;
};

struct CampaignEvaluation {
  std::string manifest_file, points_file;
  bool from_features = false;  // centres read from a feature file (evaluateSphereCampaignFromFeatures)
  int other_features = 0;      // rows of other kinds in it, not used
  int reference_cycle = 0;
  std::vector<int> ls_positions;          // positions used by least squares
  std::array<int, 4> formula_positions{};  // position of formula index 1..4, 0 if absent
  bool formulas_applicable = false;
  std::vector<CycleEvaluation> cycles;    // complete cycles, ascending
  std::vector<std::pair<int, std::string>> incomplete;  // cycle, reason
  PointScatter point_scatter;  // what the budgets used (type B spec, type A pooled)
  // Per position, over the complete cycles: seed 004 Table 5.3's statistics (they include
  // the drift between cycles; Table 5.3 measured one position continuously).
  std::vector<std::pair<int, CentreRepeatability>> centre_repeatability;
};

// The terms a cycle adds to the pooled scatter, in manifest order (spheres whose free-radius fit
// has dof > 0).
std::vector<ScatterTerm> scatterTerms(const CycleEvaluation& c);

CampaignEvaluation evaluateSphereCampaign(const parts::PlanManifest& manifest,
                                          const std::vector<ProbeRecord>& records,
                                          const EvaluateOptions& options = {});

// The same evaluation from sphere centres a CMM package reports (no points): each position's
// centre per cycle from `centres` (evaluate/feature_actuals.hpp), its budget from what the file
// states (location_budget.hpp FeatureCentreU). A position without a centre makes its cycle
// incomplete, listed as the point route lists a position without points. The time of a centre
// is its time_s, else the mean planned time of its position's points; the cycle's, their mean
// weighted by n_points. --free-radius (options.known_radius false) chose how the centres of a
// file of points only were fitted (featureActualsFromCmm); with a centre the file states (no fit
// of ours) it is refused, naming the row's line.
CampaignEvaluation evaluateSphereCampaignFromFeatures(const parts::PlanManifest& manifest, const SphereCentresFromFeatures& centres,
                                                      const std::string& file, const EvaluateOptions& options = {});

// Error series CSV (docs/architecture.md#data-contracts): time_s,cycle,<7 errors>,U_<7 errors>.
std::string errorSeriesCsv(const CampaignEvaluation& e);
std::string evaluationJson(const CampaignEvaluation& e, const parts::PlanManifest& m);
// A Markdown report: the range of U per error, the full budgets of the last cycle, the
// centre repeatability table.
std::string evaluationReport(const CampaignEvaluation& e, const parts::PlanManifest& m);

// Theoretical resolution of each error (seed 004 L1444, Table 5.4): the largest change of
// the error when one centre coordinate of the cycle changes by one step, for the formulas
// (when applicable) and for the least squares.
struct Resolution {
  std::optional<std::array<double, 7>> formulas;
  std::array<double, 7> least_squares{};
};
Resolution locationErrorResolution(const parts::PlanManifest& m, double step_mm);

}  // namespace probeloop::evaluate
