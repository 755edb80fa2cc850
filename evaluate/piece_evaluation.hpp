// `probeloop evaluate` and the prediction of `probeloop plan`, by the manifest's kind: the CLI
// reads the manifest, calls these, writes the returned texts (writeFileAtomic) and prints
// stdout_text. No mathematics in the CLI.
//
// Kinds: sphere_artifact (seed 004 Ch. 5: evaluate/sphere_campaign.hpp; the writers of
// evaluate/outputs.cpp, as before the dispatch), thermal_test_piece (seed 004 Ch. 7:
// evaluate/thermal_test_piece.hpp) and stepped_workpiece (seed 000: its CMM export and probe
// log together, evaluate/stepped_workpiece.hpp; when the CMM file is a feature-actuals CSV or a
// QIF/DMIS file with features and no points, from the stated planes, evaluate/sw_features.hpp).
#pragma once
#include <optional>
#include <string>

#include "evaluate/sphere_campaign.hpp"
#include "evaluate/stepped_workpiece.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

struct EvaluateRequest {
  std::string input_file;
  // auto | linuxcnc | fanuc | csv (both kinds) | cmm | gauge (thermal test piece) | features
  // (sphere artifact, stepped workpiece) | qif | dmis
  std::string format = "auto";
  bool free_radius = false;      // sphere artifact: centres from the free-radius fit
  std::string compare_with;      // thermal test piece: another evaluation.json -> Table 7.2 reductions
  std::string out_dir = ".";     // only for the file names printed in stdout_text
  double gauge_resolution_um = 1.0;  // thermal test piece, dial-gauge route (not stated in the thesis)
  std::string probe_log;         // stepped workpiece: the on-machine probe log beside the CMM export (input_file)
  std::string cycle_starts;      // sphere artifact: a user's cycle start times (ingest.hpp applyCycleStarts)
  bool strict = false;           // QIF/DMIS inputs: refuse what the lenient reader would warn about
};

struct EvaluationFiles {
  // File names the CLI writes these to, in out_dir.
  static constexpr const char* kErrorsCsv = "errors.csv";
  static constexpr const char* kEvaluationJson = "evaluation.json";
  static constexpr const char* kReportMd = "report.md";
  static constexpr const char* kResultsQif = "results.qif";
  static constexpr const char* kRotaryJson = "rotary_calibration.json";
  static constexpr const char* kRotaryCsv = "rotary_errors.csv";
  std::string errors_csv, evaluation_json, report_md, stdout_text;
  std::string compensation_json;  // stepped workpiece: compensation.json (empty for the other kinds)
  std::string results_qif;        // results.qif: the measured features and the errors as QIF 3.0 (qif_results.hpp)
  // Sphere artifact with tilted positions: every rotary axis on the chain (rotary_calibration.hpp).
  std::string rotary_json, rotary_csv;
  // Sphere artifact: the campaign, for --scene (per-cycle sphere centres, reference cycle).
  std::optional<CampaignEvaluation> sphere;
  std::optional<TtpEvaluation> thermal_test_piece;
  std::optional<SwEvaluation> stepped_workpiece;
};

// InputError for bad input (file, line, feature, what was expected); kinds other than the
// three above are refused naming the manifest.
EvaluationFiles evaluateTestPiece(const parts::PlanManifest& manifest, const EvaluateRequest& request);

// The sphere campaign's summary as `probeloop evaluate` has always printed it (without the
// --scene line, which the CLI prints after writing the scene).
std::string sphereEvaluationStdout(const CampaignEvaluation& e, const std::string& out_dir);

// What `probeloop plan` prints after the planner's summary: for the sphere artifact the
// resolution (seed 004 Table 5.4) for this coordinate step and the predicted U of each location
// error; for the thermal test piece the predicted U (k = 2) of E_X, E_Y, E_Z, E_B, E_TTP and dT
// for the CMM and the on-machine route from the planned points and the specifications alone.
std::string planPrediction(const parts::PlanManifest& manifest, double coordinate_step_mm);
// The sphere's two parts separately (`probeloop resolution` prints both for a step in um).
std::string sphereResolutionText(const Resolution& r, double step_um);
std::string spherePredictionText(const parts::PlanManifest& m);

}  // namespace probeloop::evaluate
