// A stepped workpiece's experiment planned with the compensation another part predicts for it
// (seed 000 Ch. 6; `probeloop plan ... --predict-from`).
//
// Contract: the experiment is planned once without compensation, for its conditions (each
// step's size, floor depth, feed, spindle speed and Temp state); the components of another
// part's evaluation.json, or of a campaign's separation.json (its process part with the
// thermal stages, `probeloop separate`), fitted against feed and Temp state
// (model/stepped_prediction.hpp), predict this experiment's wall and floor errors there; the
// experiment is planned again with those taken out of the finishing path. The offsets do not
// change the clock. InputError (naming the file) for another kind of piece, a file that is
// neither, or a separation without its process part.
#pragma once
#include <string>

#include "parts/sw_compensation.hpp"
#include "planner/piece_plan.hpp"

namespace probeloop::planner {

struct PredictedPlan {
  TestPiecePlan plan;                 // planned with the predicted compensation
  parts::SwCompensation compensation;  // what was taken out, with U
};

PredictedPlan planWithPredictedCompensation(const parts::TestPiece& piece, const parts::Machine& machine,
                                            parts::Dialect dialect, const std::string& out_dir,
                                            const std::string& experiment, const std::string& evaluation_file);

}  // namespace probeloop::planner
