// The glTF scene of an evaluation (`probeloop evaluate ... --scene`): a sphere campaign's
// error vectors (scene.hpp) or a test piece's deviation vectors (ttp_scene.hpp), chosen by
// what the evaluation holds.
//
// Contract: exaggeration defaults to x10000 for a sphere campaign (errors of a few um on the
// scale of a 0.3 m table) and x1000 for a test piece (docs/report-thermal-test-piece.md).
// Dial-gauge readings give no measured surfaces: InputError naming the input file.
#pragma once
#include <optional>
#include <string>

#include "evaluate/piece_evaluation.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::report {

double defaultSceneExaggeration(const evaluate::EvaluationFiles& f);

std::string evaluationSceneGltf(const parts::PlanManifest& manifest, const evaluate::EvaluationFiles& f,
                                const std::string& input_file, double exaggeration);

}  // namespace probeloop::report
