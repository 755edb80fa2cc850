// An evaluation's results as a QIF 3.0 Results document (results.qif beside errors.csv;
// docs/interop.md): the measured features with the points the evaluation read (part frame) and
// each feature's least-squares geometry (interop/measured_geometry.hpp), and every derived
// error of errors.csv as a characteristic: "<quantity> <cycle|step> <n>" (e.g. "EX cycle 3",
// "e_pos_x step 2"), a length (_um columns, written in mm) or an angle (_urad, in rad), with
// its combined standard uncertainty (the u_ column, else the U_ column / 2: errors.csv's U is
// for k = 2).
#pragma once
#include <string>

#include "evaluate/ttp_ingest.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

// points: the measured surface points (nullptr: none, e.g. dial-gauge readings or a sphere
// campaign, whose features are the controller's probe points, not a CMM's).
std::string evaluationQif(const parts::PlanManifest& m, const TtpPoints* points, const std::string& errors_csv);

}  // namespace probeloop::evaluate
