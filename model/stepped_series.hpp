// The stepped workpiece's error series for the model loop (seed 000 §9.1 item 10; docs/
// stepped-workpiece.md §9): several parts' evaluations and their machines' logged inputs ->
// one campaign on one clock that `probeloop model fit|diagnose|add` reads.
//
// errors.csv: one row per step of each part at the mid-time of its wall cuts (evaluation.json's
// cut_mid_s), channels the CMM's errors width_x_um, width_y_um, depth_um, U = 2 u of the CMM's
// measurement (separation[].u_cmm_…: its MPE at the length, its planes' residuals, the part's
// temperature at the CMM); a compensated part's rows add its offsets back (compensation_applied:
// the walls' sum per width, the floor's for the depth), so that every row is the machine's error.
// inputs.csv: the parts' logged inputs one after the other, each part shifted to start
// `gap_s` after the previous one's last sample (the machine stood between the experiments,
// which the thesis cut on different days): in the gap the speeds, the fluid and the tool
// changes are 0 and every other column (temperatures) goes linearly from its last value to
// the next part's first. Derived columns, the conditions of the step being cut (held from one
// step's start to the next's, through the gaps too: they are for static effects, read at the
// rows, each its own step's; their names are not speeds, so the diagnosis offers no lag of them):
//   travel_mm              size + tool d: the tool centre's travel between opposite walls
//                          (a position error proportional to the distance reads it);
//   depth_mm               the floor's nominal depth below the top;
//   cut_feed_mm_per_min    the step's XY feed (the thesis's process variable);
//   chip_load_um_per_rev   the feed per spindle revolution, 1000 F / S (the chip load);
//   transition_feed_mm_per_min  the feed of the moves that join the walls (evaluation.json's
//                          transition_feed; 0 for a continuous path, which has none): what winds
//                          the drives up before a wall, the thesis's control error (Sec. 3.6.2);
// model.yaml: the starting model "position error only": static(travel_mm) for the widths,
// static(depth_mm) for the depth, trained on the first 60 % of the rows, or on the first
// `training_parts` parts' rows when that is > 0.
//
// Contract: InputError naming the file: not a stepped evaluation, no transition (an evaluation
// older than the control separation), training_parts beyond the parts given, a step without cut_mid_s
// (an evaluation older than this series), inputs whose columns or step differ from the first
// part's, a cut time outside its part's inputs; parts in the order given.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/dataset.hpp"

namespace probeloop::model {

struct SteppedSeriesPart {
  nlohmann::json evaluation;
  std::string evaluation_file;
  InputSeries inputs;
};

struct SteppedSeries {
  std::string inputs_csv, errors_csv, model_yaml;
  int rows = 0;
  double training_fraction = 0.6;  // what model.yaml says
  std::string summary;
};

SteppedSeries buildSteppedSeries(const std::vector<SteppedSeriesPart>& parts, double gap_s = 24 * 3600.0, int training_parts = 0);

}  // namespace probeloop::model
