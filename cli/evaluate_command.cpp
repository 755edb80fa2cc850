// `probeloop evaluate`: a test piece's errors with their budgets from probe logs, points CSV,
// a CMM export (CSV, QIF 3.0 Results, DMIS output) or dial-gauge readings, by the manifest's
// kind (evaluate/piece_evaluation.hpp); optionally its glTF scene (report/evaluation_scene.hpp).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/paths.hpp"
#include "evaluate/piece_evaluation.hpp"
#include "parts/plan_manifest.hpp"
#include "report/evaluation_scene.hpp"
#include "report/scene_legend.hpp"

namespace probeloop::cli {
namespace {

struct EvaluateArgs {
  std::string points, manifest, out = ".", format = "auto", scene, compare_with, probe_log, cycle_starts;
  bool free_radius = false, strict = false;
  std::optional<double> exaggeration;
  double gauge_resolution_um = 1.0;
};

int runEvaluate(const EvaluateArgs& a) {
  const auto m = parts::readManifest(a.manifest);
  evaluate::EvaluateRequest req;
  req.input_file = a.points;
  req.format = a.format;
  req.free_radius = a.free_radius;
  req.compare_with = a.compare_with;
  req.probe_log = a.probe_log;
  req.cycle_starts = a.cycle_starts;
  req.out_dir = a.out;
  req.gauge_resolution_um = a.gauge_resolution_um;
  req.strict = a.strict;
  const auto f = evaluate::evaluateTestPiece(m, req);
  const double exaggeration = a.exaggeration.value_or(report::defaultSceneExaggeration(f));
  const std::string scene = a.scene.empty() ? "" : report::evaluationSceneGltf(m, f, a.points, exaggeration);
  // Beside the scene, the page that numbers its colours (report/scene_legend.hpp).
  const std::string legend =
      scene.empty() ? "" : report::sceneLegendHtml(scene, std::filesystem::path(a.scene).filename().string());
  writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kErrorsCsv), f.errors_csv);
  writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kEvaluationJson), f.evaluation_json);
  writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kReportMd), f.report_md);
  if (!f.compensation_json.empty()) writeFileAtomic(pathIn(a.out, "compensation.json"), f.compensation_json);
  if (!f.results_qif.empty()) writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kResultsQif), f.results_qif);
  if (!f.rotary_json.empty()) writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kRotaryJson), f.rotary_json);
  if (!f.rotary_csv.empty()) writeFileAtomic(pathIn(a.out, evaluate::EvaluationFiles::kRotaryCsv), f.rotary_csv);
  std::fputs(f.stdout_text.c_str(), stdout);
  if (!scene.empty()) {
    writeFileAtomic(a.scene, scene);
    std::printf("Wrote %s (%s x%s)\n", a.scene.c_str(), f.sphere ? "error vectors" : "deviation vectors",
                formatNumber(exaggeration).c_str());
    writeFileAtomic(report::sceneLegendPath(a.scene), legend);
    std::printf("Wrote %s (the scene's colour scale in um, its exaggeration and objects)\n",
                report::sceneLegendPath(a.scene).c_str());
  }
  return 0;
}

}  // namespace

Subcommand addEvaluateCommand(CLI::App& app) {
  auto a = std::make_shared<EvaluateArgs>();
  auto* ev = app.add_subcommand("evaluate", "Errors of a test piece from probe logs, points CSV, a CMM export or dial-gauge readings");
  ev->add_option("measurements", a->points, "LinuxCNC log, Fanuc DPRNT output, points CSV, CMM export (CSV, QIF 3.0 Results or DMIS output) or gauge CSV")
      ->required()->check(inputFile("the probe log or CMM export to evaluate"));
  ev->add_option("--manifest", a->manifest, "plan manifest (plan.json)")->required()
      ->check(inputFile("the plan.json that `probeloop plan` wrote"));
  ev->add_option("--out", a->out, "output folder")->capture_default_str();
  ev->add_option("--format", a->format, "auto, linuxcnc, fanuc, csv, features (the fitted features a CMM reports, docs/formats.md), cmm, qif, dmis or gauge")
      ->check(CLI::IsMember({"auto", "linuxcnc", "fanuc", "csv", "features", "cmm", "qif", "dmis", "gauge"}))->capture_default_str();
  ev->add_flag("--free-radius", a->free_radius, "sphere centres from the free-radius fit (default: known radius)");
  ev->add_flag("--strict", a->strict, "QIF or DMIS input: refuse what the lenient reader reads with a warning (docs/interop.md)");
  ev->add_option("--scene", a->scene, "also write a glTF scene (the sphere campaign, or the test piece with its deviations)");
  ev->add_option("--exaggeration", a->exaggeration, "scale of the error vectors in the scene (default: 10000 sphere campaign, 1000 test piece)");
  ev->add_option("--gauge-resolution-um", a->gauge_resolution_um,
                 "thermal test piece, dial-gauge readings: the gauge's resolution (rectangular; not stated in the thesis)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  ev->add_option("--probe-log", a->probe_log, "stepped workpiece: the on-machine probe log, evaluated with the CMM export (seed 000: CMM - probe)")
      ->check(inputFile());
  ev->add_option("--cycle-starts", a->cycle_starts, "sphere campaign: a CSV cycle,start_s of when each cycle started (s, the inputs' "
                 "clock), for a log without clocks; replaces the plan's schedule")->check(inputFile());
  ev->add_option("--compare", a->compare_with, "another run's evaluation.json: thermal test piece, seed 004 Table 7.2 reductions; stepped workpiece, the part before its compensation (before/after)")
      ->check(inputFile());
  return {ev, [a] { return runEvaluate(*a); }};
}

}  // namespace probeloop::cli
