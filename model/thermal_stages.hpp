// The stepped workpiece's thermal stages and the campaign's separation (seed 000 Sec. 3.5-3.6,
// 5.3-5.5; notes/seed000.md §4.4-4.6; docs/stepped-workpiece.md §8): several parts' one-part
// evaluations (evaluation.json of `probeloop evaluate … --probe-log`) -> the thermal position
// error and the spindle growth as functions of the Temp state T at each spindle speed, and the
// process error of a part cut at changing feeds with the thermal error taken out.
//
// A stage is a part cut at one feed and one speed on every step (W1, W4, W6, W7): its process and
// control errors are the same on every step (L806-808), so what changes from step to step is
// thermal. Parts at the same speed are pooled (W4 repeats W1 "for statistical significance").
//   e_pt_x(T), e_pt_y(T): each step's one-part e_proc (probe width error - e_pos over the tool
//     centre's travel, the thermal error taken as 0; two walls) against T, regressed with a free
//     intercept: the intercept is "the constant magnitude of errors other than thermal at actual
//     thermal zero" (L844), the stage's process and control error; e_pt(T) = f(T) - f(0).
//     Forms: polynomial(1), polynomial(2), saturating exponential; the best by leave-one-out.
//   e_splz(T): through (0, 0) (the top, cut first, is the reference), as for one part.
// Between stages the value is linear in S between the neighbouring stages' speeds, the weight
// (S - S_a) / (S_b - S_a) on stage b; the thesis's Eq. 3.7/3.8 and twelve of its instantiations
// print the weights swapped (notes §4.5: at S = 3500 they return the 5500 rpm stage). Outside
// the measured speeds the nearest stage is scaled by S / S_stage (Eq. 3.9/3.10, below the lowest
// with the lowest stage: the reading of Eq. 5.19, 5.27, ...). u of an interpolated value:
// sqrt((w_a u_a)^2 + (w_b u_b)^2), k the larger of the stages' Student t.
//
// The thermal error is the same function of T for every part cut after the same 3 h off: it holds
// for the procedure of the stages (T from the start of finishing), and for the steps' sizes at
// those times (the thesis's e_pt is a function of T alone, though a scale error also grows with
// the distance; docs/stepped-workpiece.md §8 states the limit).
//
// Contract: InputError naming the file: not a stepped evaluation; a stage part whose feed or
// speed changes between steps; GeometryError: no stage, a stage at 0 rpm or with fewer than 4
// steps (a line with a free intercept must leave 2 dof), no form that fits, a Temp state beyond
// twice a stage's largest.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/stepped_prediction.hpp"

namespace probeloop::model {

// The forms that leave two degrees of freedom on n points (GeometryError naming `what` when none
// does): a 3-parameter curve through 4 steps leaves one, and its leave-one-out fits are exact
// (Student's t 12.7).
std::vector<Candidate> leavingTwoDof(const std::vector<Candidate>& forms, std::size_t n, const std::string& what);

struct ThermalStage {
  double spindle_rpm = 0, feed_mm_per_min = 0;
  std::vector<std::string> experiments, files;
  std::vector<int> steps;     // per point: the step it came from
  std::vector<std::string> point_experiments;  // per point: its part's experiment
  SteppedComponent one_part_x, one_part_y;  // the one-part e_proc against T, with the intercept
  SteppedComponent splz;
  double intercept_x_um() const { return one_part_x.fit.function.evaluate(0); }
  double intercept_y_um() const { return one_part_y.fit.function.evaluate(0); }
};

enum class ThermalComponent { PtX, PtY, Splz };

struct ThermalValue {
  double value_um = 0, u_um = 0, k95 = 2;
  std::string basis;  // "stage 3500 rpm", "0.5 x 3500 rpm + 0.5 x 5500 rpm", "4500/5500 x 5500 rpm"
};

struct ThermalStages {
  std::vector<ThermalStage> stages;  // ascending speed
  // The parts they came from ({file, evaluation: {kind, experiment, separation}}), kept so that
  // separation.json can be refitted to exactly these stages.
  nlohmann::json sources = nlohmann::json::array();
  ThermalValue at(ThermalComponent c, double temp_state_min, double spindle_rpm) const;
};

// The stages from parts' evaluation.json (pairs of the parsed JSON and its file name).
ThermalStages thermalStagesFromEvaluations(const std::vector<std::pair<nlohmann::json, std::string>>& parts);

// A part cut at changing feeds (W8) with the stages' thermal error taken out of each step's
// one-part e_proc (L868, L1629): e_proc = one-part e_proc - e_pt(T, S).
struct ProcessStep {
  std::string experiment;
  int step = 0;
  double feed_mm_per_min = 0, spindle_rpm = 0, temp_state_min = 0;
  double one_part_x_um = 0, u_one_part_x_um = 0, one_part_y_um = 0, u_one_part_y_um = 0;
  ThermalValue pt_x, pt_y;
  double e_proc_x_um = 0, u_e_proc_x_um = 0, U_e_proc_x_um = 0;  // U: one-part at k = 2, e_pt at its k
  double e_proc_y_um = 0, u_e_proc_y_um = 0, U_e_proc_y_um = 0;
};
std::vector<ProcessStep> separateProcess(const ThermalStages& st, const nlohmann::json& evaluation, const std::string& file);

// The prediction of a new part (model/stepped_prediction.hpp) from a process part and the
// stages: e_proc(F) fitted to the process part's steps with the thermal error taken out, and the
// thermal terms e_pt(T, S), e_splz(T, S) of the stages.
SteppedPredictor steppedPredictorFromCampaign(const ThermalStages& st, const nlohmann::json& process_evaluation,
                                              const std::string& file);

// separation.json: the stages (their points and fitted forms), the process part's steps, the
// interpolation's weights stated, and the process part's evaluation.json embedded (so that
// `plan --predict-from separation.json` refits the same campaign); read back by
// campaignFromSeparationJson (InputError naming the file when it is not one).
// `control`: the control errors' block (model/control_errors.hpp controlJson), or null.
std::string separationJson(const ThermalStages& st, const std::vector<ProcessStep>& process,
                           const nlohmann::json* process_evaluation, const std::string& process_file,
                           const nlohmann::json* control = nullptr);
std::string separationCsv(const ThermalStages& st, const std::vector<ProcessStep>& process);
std::string separationSummary(const ThermalStages& st, const std::vector<ProcessStep>& process);
struct SeparationCampaign {
  ThermalStages stages;
  nlohmann::json process_evaluation;  // null when the campaign had no process part
  std::string process_file;
};
SeparationCampaign campaignFromSeparationJson(const nlohmann::json& j, const std::string& file);

}  // namespace probeloop::model
