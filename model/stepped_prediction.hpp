// Forward prediction of a stepped workpiece (seed 000 Ch. 6, Sec. 3.8-3.9) from the components
// one part separated (the evaluation.json of `probeloop evaluate … --probe-log`, docs/
// stepped-workpiece.md §6): each component becomes a function of its variable, chosen among
// regression families by leave-one-out backward prediction (model/regression_family.hpp), and
// the errors of a new part's features are their sum at the new part's conditions.
//
//   e_pos(L)    = k L per axis (the evaluation's line through 0, its u(k));
//   e_proc(F)   two walls, against the feed: polynomial(1) or (2) through 0, hyperbolic;
//   e_splz(T)   against the Temp state, with (0, 0) (the top, cut first, is the reference):
//               saturating exponential, polynomial(1) or (2) through 0, hyperbolic; at another
//               spindle speed S scaled by S / S_ref (the thesis's proportion method, Eq. 3.9/3.10;
//               one thermal stage is all one part gives);
//   width error = e_pos(size + tool d) + e_proc(F)  (+ e_pt: 0 from one part),
//   depth error = k_z depth - e_splz(T).
// u of a predicted component: sqrt(rms(u_i)^2 + loo^2), the measured points' own u and the
// family's leave-one-out RMS (its error out of sample), expanded with Student's t at the
// Welch-Satterthwaite dof (the points' u many, the leave-one-out RMS points - parameters); e_pos adds u(k) x (size + stylus d), its sensitivity to k once e_proc was
// separated with the same k (e_proc's points already carry u(k) x (tool d - stylus d)).
//
// Contract: GeometryError / InputError (naming the file) for an evaluation without the fields
// above, fewer than 3 steps, no family that fits; the prediction refuses a feed or a Temp state
// beyond twice the largest measured one (an extrapolation the part cannot support).
#pragma once
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/regression_family.hpp"

namespace probeloop::model {

struct SteppedComponent {
  std::string name;          // e_proc_x_um, e_proc_y_um, e_splz_um
  std::string variable;      // feed_mm_per_min, temp_state_min
  std::vector<double> x, y, u;  // the measured points (y, u in um)
  Selection selection;
  FamilyFit fit;              // the chosen family's fit
  double u_pred_um = 0;       // sqrt(rms(u)^2 + loo^2)
  double k95 = 2;             // Student's t (95 %) at the effective dof (see above)
  double x_max = 0;
  double at(double x) const;  // GeometryError beyond 2 x_max
};

// A campaign's thermal terms at (Temp state, spindle speed) (model/thermal_stages.hpp), U at k95.
struct ThermalTerms {
  double pt_x_um = 0, pt_y_um = 0, splz_um = 0, U_pt_x_um = 0, U_pt_y_um = 0, U_splz_um = 0;
  std::string basis;
};

struct SteppedPredictor {
  std::string file, experiment;
  double speed_ref_rpm = 0, tool_d_mm = 0, probe_d_mm = 0;
  double k_um_per_mm[3] = {0, 0, 0}, u_k_um_per_mm[3] = {0, 0, 0};  // x, y, z
  SteppedComponent proc_x, proc_y, splz;
  // From a campaign: the thermal terms; absent (one part): e_pt 0, e_splz scaled by S / S_ref.
  std::function<ThermalTerms(double temp_state_min, double spindle_rpm)> thermal;
  // e_proc against the feed per revolution, 1000 F / S in um (a campaign's, with the stages'
  // intercepts); else against the feed (one part, one speed).
  bool proc_per_rev = false;
  std::string thermal_summary;
};

// One component fitted: the best of `candidates` by leave-one-out, u_pred and k95 as above;
// GeometryError naming the file and the component when no candidate fits.
SteppedComponent fitSteppedComponent(std::string name, std::string variable, std::vector<double> x, std::vector<double> y,
                                     std::vector<double> u, const std::vector<Candidate>& candidates, const std::string& file);

// What every predictor reads of an evaluation: the file, the experiment, k and u(k) per axis,
// the tool's and the stylus's diameters (travels minus sizes); no component fitted.
SteppedPredictor steppedPredictorBase(const nlohmann::json& evaluation, const std::string& file);

SteppedPredictor steppedPredictorFromEvaluation(const nlohmann::json& evaluation, const std::string& file);

struct SteppedConditions {
  int step = 0;
  double size_mm = 0, depth_mm = 0, feed_mm_per_min = 0, spindle_rpm = 0, temp_state_min = 0;
};

struct SteppedPrediction {
  int step = 0;
  double width_x_um = 0, width_y_um = 0, depth_um = 0;     // predicted errors
  double U_width_x_um = 0, U_width_y_um = 0, U_depth_um = 0;  // k = 2
};

std::vector<SteppedPrediction> predictSteppedErrors(const SteppedPredictor& p, const std::vector<SteppedConditions>& steps);

// One component's line: its family, parameters (4 significant digits), leave-one-out RMS and u.
std::string steppedComponentSummary(const SteppedComponent& c);
// The sentence a report or plan prints: which family each component follows and why.
std::string steppedPredictorSummary(const SteppedPredictor& p);

}  // namespace probeloop::model
