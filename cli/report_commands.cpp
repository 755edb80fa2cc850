#include "cli/report_commands.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cli/input_option.hpp"
#include "parts/json_file.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "parts/plan_manifest.hpp"
#include "report/sphere_report.hpp"
#include "report/sw_report.hpp"
#include "report/ttp_report.hpp"
#include "report/scene_legend.hpp"
#include "report/ttp_scene.hpp"

namespace probeloop::cli {
using parts::readJsonFile;
namespace {

struct TtpArgs {
  std::string evaluation, second, r_test, inputs, html, scene, manifest;
  double exaggeration = 1000;
  report::TtpReportOptions options;
};


// The report and scene name no file in the errors they cannot place (the scene's evaluation).
template <class F>
auto naming(const std::string& file, F&& f) {
  try {
    return f();
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    throw InputError(file, 0, e.what());
  }
}

int runTtp(TtpArgs a) {
  if (a.html.empty() && a.scene.empty())
    throw InputError("", 0, "report ttp: nothing to write; give --html and/or --scene");
  const nlohmann::json evaluation = readJsonFile(a.evaluation);
  std::optional<nlohmann::json> second;
  if (!a.second.empty()) second = readJsonFile(a.second);
  std::optional<std::string> r_test;
  if (!a.r_test.empty()) r_test = readFile(a.r_test);
  a.options.evaluation_file = a.evaluation;
  a.options.second_file = a.second;
  a.options.r_test_file = a.r_test;
  if (!a.inputs.empty()) {
    a.options.inputs_csv_text = readFile(a.inputs);
    a.options.inputs_file = a.inputs;
  }

  // Both outputs are made in memory first: an error in either leaves no file written.
  std::string html, gltf, legend;
  if (!a.html.empty())
    html = report::thermalTestPieceReportHtml(evaluation, second ? &*second : nullptr, r_test ? &*r_test : nullptr,
                                              report::defaultVegaPath(), a.options);
  if (!a.scene.empty()) {
    const parts::PlanManifest manifest = parts::readManifest(a.manifest);
    gltf = naming(a.evaluation, [&] { return report::thermalTestPieceSceneGltf(manifest, evaluation, a.exaggeration); });
    // The page that numbers the scene's colours, as `evaluate --scene` writes it beside a scene.
    legend = report::sceneLegendHtml(gltf, std::filesystem::path(a.scene).filename().string());
  }

  if (!a.html.empty()) {
    writeFileAtomic(a.html, html);
    std::printf("Wrote %s (thermal-test-piece report: %s%s%s%s)\n", a.html.c_str(), a.evaluation.c_str(),
                second ? (" and " + a.second).c_str() : "", r_test ? (", R-test " + a.r_test).c_str() : "",
                a.inputs.empty() ? "" : (", inputs " + a.inputs).c_str());
  }
  if (!a.scene.empty()) {
    writeFileAtomic(a.scene, gltf);
    std::printf("Wrote %s (glTF scene of %s, deviation vectors x%g)\n", a.scene.c_str(), a.manifest.c_str(),
                a.exaggeration);
    writeFileAtomic(report::sceneLegendPath(a.scene), legend);
    std::printf("Wrote %s (the scene's colour scale in um, its exaggeration and objects)\n",
                report::sceneLegendPath(a.scene).c_str());
  }
  return 0;
}

struct SwArgs {
  std::string evaluation, compensated, html;
};

int runStepped(const SwArgs& a) {
  const nlohmann::json evaluation = readJsonFile(a.evaluation);
  std::optional<nlohmann::json> compensated;
  if (!a.compensated.empty()) compensated = readJsonFile(a.compensated);
  const std::string html = report::steppedWorkpieceReportHtml(evaluation, a.evaluation, report::defaultVegaPath(),
                                                              compensated ? &*compensated : nullptr, a.compensated);
  writeFileAtomic(a.html, html);
  std::printf("Wrote %s (stepped-workpiece report: %s%s)\n", a.html.c_str(), a.evaluation.c_str(),
              compensated ? (", compensated " + a.compensated).c_str() : "");
  return 0;
}

struct SphereArgs {
  std::string evaluation, inputs, manifest, scene, html;
};

// The scene's path as the page links it: relative to the page's folder, '/' separated.
std::string sceneHref(const std::string& scene, const std::string& html) {
  namespace fs = std::filesystem;
  const fs::path from = fs::weakly_canonical(fs::absolute(html)).parent_path();
  const fs::path rel = fs::weakly_canonical(fs::absolute(scene)).lexically_relative(from);
  return rel.empty() ? fs::path(scene).generic_string() : rel.generic_string();
}

int runSphere(const SphereArgs& a) {
  const nlohmann::json evaluation = readJsonFile(a.evaluation);
  std::optional<std::string> inputs;
  if (!a.inputs.empty()) inputs = readFile(a.inputs);
  std::optional<parts::PlanManifest> manifest;
  if (!a.manifest.empty()) manifest = parts::readManifest(a.manifest);
  report::SphereReportOptions o;
  o.evaluation_file = a.evaluation;
  o.inputs_file = a.inputs;
  o.manifest_file = a.manifest;
  if (!a.scene.empty()) o.scene_href = sceneHref(a.scene, a.html);
  const std::string html = report::sphereCampaignReportHtml(evaluation, inputs ? &*inputs : nullptr,
                                                            manifest ? &*manifest : nullptr, report::defaultVegaPath(), o);
  writeFileAtomic(a.html, html);
  std::printf("Wrote %s (sphere-campaign report: %s%s%s)\n", a.html.c_str(), a.evaluation.c_str(),
              inputs ? (", inputs " + a.inputs).c_str() : "", manifest ? (", plan " + a.manifest).c_str() : "");
  return 0;
}

}  // namespace

std::function<int()> addReportCommands(CLI::App& app, CLI::App*& group) {
  auto a = std::make_shared<TtpArgs>();
  group = app.add_subcommand("report", "Reports of evaluated test pieces: HTML pages and glTF scenes");
  group->require_subcommand(1);
  auto* ttp = group->add_subcommand(
      "ttp", "Thermal test piece (seed 004 Ch. 7): E_X, E_Y, E_Z, E_B, E_TTP and dT against time beside the R-test, "
             "spans, budgets (HTML); the piece with its deviations (glTF)");
  ttp->add_option("--evaluation", a->evaluation, "evaluation.json of `probeloop evaluate` (thermal test piece)")
      ->required()
      ->check(cli::inputFile());
  ttp->add_option("--second", a->second, "the other route's evaluation.json of the same piece (CMM vs on-machine)")
      ->check(cli::inputFile());
  ttp->add_option("--r-test", a->r_test, "errors.csv of an R-test (sphere cycle) on the same clock")
      ->check(cli::inputFile());
  ttp->add_option("--inputs", a->inputs,
                  "inputs.csv of the run (time_s, temperatures *_C, c_rpm): temperatures and C load against time")
      ->check(cli::inputFile());
  ttp->add_option("--html", a->html, "write the HTML report to this file");
  auto* manifest = ttp->add_option("--manifest", a->manifest, "plan.json of the test piece (for --scene)")
                       ->check(cli::inputFile());
  ttp->add_option("--scene", a->scene, "write a glTF scene of the piece with its deviations to this file")
      ->needs(manifest);
  ttp->add_option("--exaggeration", a->exaggeration,
                  "scale of the deviation vectors in the scene: 1000 draws a 1 um change as a 1 mm line")
      ->capture_default_str();
  ttp->add_option("--table-alpha", a->options.table_alpha_um_per_m_K,
                  "Eq. 7.10 for the table: expansion coefficient, um/(m K) (seed 004: cast iron)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  ttp->add_option("--r-test-radius", a->options.r_test_radius_mm,
                  "Eq. 7.10 for the table: the R-test sphere's radius from the C axis, mm")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  auto s = std::make_shared<SwArgs>();
  auto* sw = group->add_subcommand(
      "stepped", "Stepped workpiece (seed 000): the separated components with U against travel, feed and Temp state; "
                 "a compensated part's before/after per feature (HTML)");
  sw->add_option("--evaluation", s->evaluation,
                 "evaluation.json of `probeloop evaluate … --probe-log`: the part cut plain (or, alone, any part; "
                 "one evaluated with --compare shows its before/after)")
      ->required()
      ->check(cli::inputFile());
  sw->add_option("--compensated", s->compensated,
                 "evaluation.json of the same experiment cut compensated and evaluated with --compare against "
                 "--evaluation: both parts side by side, before/after with U")
      ->check(cli::inputFile());
  sw->add_option("--html", s->html, "write the HTML report to this file")->required();
  auto sp = std::make_shared<SphereArgs>();
  auto* sph = group->add_subcommand(
      "sphere", "Sphere-artifact campaign (seed 004 Ch. 5): the seven location errors of the C axis against time "
                "with U bands, every cycle's values, the budgets, the schedule, the temperatures and loads (HTML)");
  sph->add_option("--evaluation", sp->evaluation, "evaluation.json of `probeloop evaluate` (sphere artifact)")
      ->required()
      ->check(cli::inputFile());
  sph->add_option("--inputs", sp->inputs, "the run's inputs.csv (time_s, temperatures, speeds): drawn on the errors' time axis")
      ->check(cli::inputFile());
  sph->add_option("--manifest", sp->manifest, "the campaign's plan.json: the machine, the artifact and the schedule")
      ->check(cli::inputFile());
  sph->add_option("--scene", sp->scene, "a glTF scene of the campaign (`evaluate --scene`) the page links to")
      ->check(cli::inputFile());
  sph->add_option("--html", sp->html, "write the HTML report to this file")->required();
  return [a, ttp, s, sw, sp, sph]() -> int {
    if (*ttp) return runTtp(*a);
    if (*sw) return runStepped(*s);
    if (*sph) return runSphere(*sp);
    return 2;
  };
}

}  // namespace probeloop::cli
