// The GUM budget of each location error of one cycle (docs/uncertainty.md#location-errors).
//
// The estimator is linear in the sphere centres (E = W (c_i - c_ref)), so every input is
// carried to each error through W or through the error's own formula:
// - probe point scatter, this cycle and the reference cycle: sigma^2 (J^T J)^-1 of each
//   sphere fit through W. sigma is the larger of the type B specification (2 sigma / 2) and
//   the type A pooled residual of every free-radius fit of the campaign (the other is listed
//   with 0 and says why: both estimate the same scatter);
// - coordinate resolution q (rectangular, q / sqrt 12) per point, the same way;
// - tool-change repeatability (when the probe is changed every cycle): a rigid translation of
//   all centres of a cycle, sigma per axis, in this and the reference cycle;
// - sphere form error: 0, the same points of the same sphere are probed every cycle;
// - artifact temperature and expansion: EZ0T += alpha (h + R) dT (stem and ball lift the
//   centre by alpha h dT; the known-radius fit reads the ball's growth alpha R dT as a further
//   lift), dT rectangular within the stated half-width;
// - d/2: the angular errors are displacements over d, so u = |E| u(d/2) / (d/2);
// - drift during the cycle: each position is probed at its own time; with the error rates r
//   (from neighbouring cycles) the centres carry A_k r tau_k, which W turns into a bias of
//   every error; E = W (c_i - c_ref), so the bias is b_i - b_ref (a steady drift probed with
//   the same timing cancels). Rectangular with that half-width.
// Point scatter and resolution enter once for both cycles (the same sigma; a type A s must
// not be counted twice with its dof); the tool change is an independent event per cycle.
// Inputs the description does not state are listed with 0 and "not stated: <where to set it>".
#pragma once
#include <array>
#include <vector>

#include "evaluate/feature_actuals.hpp"
#include "evaluate/location_errors.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

struct CycleBudgetInput {
  std::vector<Eigen::Matrix3d> centre_cov_unscaled;  // per least-squares position, from the fit
  std::vector<double> tau_s;                         // mean time of the position - cycle mean time
  std::array<double, 7> rate_per_s{};                // d(error)/dt, error unit per s
  bool rate_known = false;
  // Centres read from a feature file (no points; evaluate/feature_actuals.hpp): per position
  // the standard uncertainty of each coordinate and of the form term (mm), with their bases.
  // Empty on the point route; when set, they replace the point scatter and resolution terms
  // (carried through W like them), and the form term no longer cancels.
  std::vector<Eigen::Vector3d> stated_u_mm;
  std::vector<double> form_u_mm;
  std::string stated_basis, form_basis;
};

// What a feature row states about its centre: u per coordinate from u_x/u_y/u_z_um when the
// file has them, else the fallback: the probe's specified repeatability through the planned
// points' known-radius fit of that position (its (J^T J)^-1), scaled to the file's n_points
// (the point route's type B term when the CMM probed the planned points). The form term:
// form_um (or, not stated, the artifact's sphere form error), rectangular within +-form/2 on
// each coordinate of the centre.
struct FeatureCentreU {
  Eigen::Vector3d u_mm = Eigen::Vector3d::Zero();
  bool stated = false;
  double form_u_mm = 0;
  bool form_stated = false;
};
FeatureCentreU featureCentreU(const parts::PlanManifest& m, const FeatureActual& f, int position);
// The centre's own budget (x, y, z in um) for evaluation.json, as sphereCentreBudgets.
std::array<uncertainty::Budget, 3> featureCentreBudgets(const parts::PlanManifest& m, const Eigen::Vector3d& centre_mm,
                                                        const FeatureCentreU& u, double k = 2.0);

struct PointScatter {
  double type_b_sigma_mm = 0;  // specification
  double type_a_sigma_mm = 0;  // pooled known-radius fit residuals (0 = not available)
  double type_a_dof = 0;
};

// values: the cycle's errors (for the d/2 term); predicted: the planner's a-priori budget
// (no measured values, no rates: those terms say so).
std::array<uncertainty::Budget, 7> locationErrorBudgets(const LocationLeastSquares& ls, const parts::PlanManifest& m,
                                                        const CycleBudgetInput& cycle, const CycleBudgetInput& reference,
                                                        const std::array<double, 7>& values, const PointScatter& scatter,
                                                        double k, bool predicted = false);

// The budget of one sphere centre (x, y, z in um, value = centre in um): point scatter,
// resolution and form error through the fit's (J^T J)^-1, and the tool change. Unlike the
// location errors (differences of cycles), the form error does not cancel here.
std::array<uncertainty::Budget, 3> sphereCentreBudgets(const parts::PlanManifest& m, const Eigen::Vector3d& centre_mm,
                                                       const Eigen::Matrix3d& cov_unscaled, const PointScatter& scatter,
                                                       double k = 2.0);

// The planner's prediction: both cycles as planned (nominal points, planned times), the
// specification's scatter. The d/2 term scales with the measured value and drift needs
// measured cycles: both are listed, with 0, saying so.
std::array<uncertainty::Budget, 7> predictLocationErrorBudgets(const parts::PlanManifest& m, double k = 2.0);

// Seed 004 Table 5.3: the repeatability of a sphere centre from n repeated measurements:
// per axis s, U = 2 s (single measurement) and U = 2 s / sqrt(n) (mean), and the 3D
// root-sum-square of the per-axis U (Table 5.3's "3D" line).
struct CentreRepeatability {
  int n = 0;
  Eigen::Vector3d s_um = Eigen::Vector3d::Zero();
  Eigen::Vector3d U_single_um = Eigen::Vector3d::Zero(), U_mean_um = Eigen::Vector3d::Zero();
  double U_single_3d_um = 0, U_mean_3d_um = 0;
};
CentreRepeatability centreRepeatability(const std::vector<Eigen::Vector3d>& centres_mm);  // n >= 2
double rootSumSquare(const Eigen::Vector3d& v);

}  // namespace probeloop::evaluate
