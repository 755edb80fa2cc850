#include "planner/predicted_compensation.hpp"

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "parts/json_file.hpp"
#include "model/stepped_prediction.hpp"
#include "model/thermal_stages.hpp"

namespace probeloop::planner {
namespace {

// The compensation the evaluation predicts for the experiment as first planned (micrometres).
parts::SwCompensation predictedCompensation(const TestPiecePlan& first, const std::string& evaluation_file) {
  const auto& m = first.manifest;
  if (parts::parsePieceKind(m.kind) != parts::PieceKind::SteppedWorkpiece)
    throw InputError(evaluation_file, 0, "--predict-from: only a stepped workpiece's finishing takes a predicted compensation");
  const nlohmann::json j = parts::readJsonFile(evaluation_file);
  model::SteppedPredictor predictor;
  if (j.is_object() && j.value("kind", "") == "stepped_separation") {
    const auto c = model::campaignFromSeparationJson(j, evaluation_file);
    if (c.process_evaluation.is_null())
      throw InputError(evaluation_file, 0, "process_evaluation: missing (run `probeloop separate` with --process: the part cut at changing feeds)");
    predictor = model::steppedPredictorFromCampaign(c.stages, c.process_evaluation, c.process_file);
  } else {
    predictor = model::steppedPredictorFromEvaluation(j, evaluation_file);
  }
  std::vector<model::SteppedConditions> conds;
  for (std::size_t i = 0; i < m.sw.steps.size() && i < m.sw.sizes_mm.size(); ++i) {
    const auto& s = m.sw.steps[i];
    const auto* floor = m.feature("S" + std::to_string(s.step) + "_F");
    if (!floor) throw InputError(m.file, 0, "features: no floor of step " + std::to_string(s.step));
    conds.push_back({s.step, m.sw.sizes_mm[i], -floor->nominal.point_mm.z(), s.feed_xy_mm_per_min, s.spindle_speed_rpm, s.temp_state_min});
  }
  parts::SwCompensation c;
  c.file = evaluation_file;
  c.experiment = m.sw.experiment;
  c.basis = model::steppedPredictorSummary(predictor);
  // A wall's error is half the width error (both walls of a step move); the floor takes the depth error.
  for (const auto& p : model::predictSteppedErrors(predictor, conds)) {
    parts::SwStepCompensation x;
    x.step = p.step;
    x.wall_um = {p.width_x_um / 2, p.width_x_um / 2, p.width_y_um / 2, p.width_y_um / 2};
    x.U_wall_um = {p.U_width_x_um / 2, p.U_width_x_um / 2, p.U_width_y_um / 2, p.U_width_y_um / 2};
    x.floor_um = p.depth_um;
    x.U_floor_um = p.U_depth_um;
    c.steps.push_back(x);
  }
  parts::validateSwCompensation(c);
  return c;
}

}  // namespace

PredictedPlan planWithPredictedCompensation(const parts::TestPiece& piece, const parts::Machine& machine,
                                            parts::Dialect dialect, const std::string& out_dir,
                                            const std::string& experiment, const std::string& evaluation_file) {
  PredictedPlan out;
  out.compensation = predictedCompensation(planTestPiece(piece, machine, dialect, out_dir, experiment), evaluation_file);
  out.plan = planTestPiece(piece, machine, dialect, out_dir, experiment, &out.compensation);
  return out;
}

}  // namespace probeloop::planner
