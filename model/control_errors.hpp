// The stepped workpiece's control errors (seed 000 Sec. 3.6.2, Eq. 3.11-3.15; notes/seed000.md
// §4.7; docs/stepped-workpiece.md §10): what a part whose walls were joined differently from the
// process part (W8, non-cutting transitions at 100 mm/min, the thesis's zero of control error,
// L1629) adds to its widths, once its thermal error and its process error at its own feeds are
// taken out.
//
//   reference: W8's process error with e_pt taken out (model/thermal_stages.hpp separateProcess),
//     regressed on the feed at W8's speed (forms leaving 2 dof: a line through 4 steps), e_ref(F).
//   transitions (W2, fast at F_t): e_ctrl(k) = one-part e_proc - e_pt(T, S) - e_ref(F_k), the
//     bracket of Eq. 3.11/3.12 per step (e_pos is out of each part's one-part value already: each
//     part's own CMM - probe). Eq. 3.13/3.14's feed scaling is reported as the slope
//     e_ctrl / (F_t - F_ref), F_ref the reference's transition feed.
//   force (W5, one continuous path at the cutting feed): e_cpr(k) = one-part e_proc - e_pt - e_ref(F_k).
//     Eq. 3.15 reaches the same through W2: (W2 - W5) - differences - e_ctrl(W2 - W8) = W8 - W5
//     term by term; going to W8 directly leaves out W2's terms and their uncertainty. The sign is
//     what the continuous path adds to W5's widths. e_cpr is then regressed on the feed (Eq. 5.56).
// u: the three terms' u in quadrature (e_pt enters both this part's and the reference's values,
// partly correlated: counted twice, so u is on the safe side); U = sqrt((2 u_part)^2 + (k u_pt)^2
// + (k u_ref)^2). A feed beyond the reference's is extrapolated (flagged), u_ref growing with the
// line's leverage there, up to twice the largest reference feed; further is refused.
//
// Contract: InputError naming the file: not a stepped evaluation or no steps; no transition
// recorded (an evaluation.json from before this field: evaluate again) or an unknown one; a
// reference joined by a continuous path; a feed beyond twice the reference's largest; a transitions part that is continuous or no faster than the reference; a force part that
// is not continuous; a step at a speed other than the reference's (e_ref holds at its speed).
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/thermal_stages.hpp"

namespace probeloop::model {

struct ControlStep {
  std::string experiment, quantity;  // quantity: e_ctrl (transitions) | e_cpr (force)
  int step = 0;
  double feed_mm_per_min = 0, spindle_rpm = 0, temp_state_min = 0;
  double one_part_x_um = 0, u_one_part_x_um = 0, one_part_y_um = 0, u_one_part_y_um = 0;
  ThermalValue pt_x, pt_y, ref_x, ref_y;  // e_pt and the reference's process error at this feed
  bool extrapolated = false;              // the feed lies outside the reference's feeds
  double x_um = 0, u_x_um = 0, U_x_um = 0, y_um = 0, u_y_um = 0, U_y_um = 0;
  // Transitions only: Eq. 3.13/3.14's slope, value / (F_t - F_ref) (um per mm/min).
  double x_um_per_mm_per_min = 0, y_um_per_mm_per_min = 0;
};

struct ControlSeparation {
  std::string reference_experiment;
  double reference_transition_feed_mm_per_min = 0, reference_spindle_rpm = 0;
  double reference_feed_min = 0, reference_feed_max = 0;
  SteppedComponent reference_x, reference_y;  // e_ref(F): the reference's process error on the feed
  std::string transitions_experiment;
  double transition_feed_mm_per_min = 0;
  std::vector<ControlStep> transitions;  // e_ctrl per step
  std::string force_experiment;
  std::vector<ControlStep> force;        // e_cpr per step
  bool has_force_fit = false;
  SteppedComponent force_x, force_y;     // e_cpr regressed on the feed (Eq. 5.56)
};

// `transitions` and `force` may be null (not given); the reference is required.
ControlSeparation separateControl(const ThermalStages& st, const nlohmann::json& reference, const std::string& reference_file,
                                  const nlohmann::json* transitions, const std::string& transitions_file,
                                  const nlohmann::json* force, const std::string& force_file);

nlohmann::json controlJson(const ControlSeparation& c);
std::string controlCsv(const ControlSeparation& c);
std::string controlSummary(const ControlSeparation& c);

}  // namespace probeloop::model
