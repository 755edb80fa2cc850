// probeloop: plan -> synth (test generator) -> evaluate -> scene. Thin: every decision is
// in the libraries; this file parses arguments, prints summaries and writes files.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <unistd.h>

#include "cli/input_option.hpp"
#include "cli/model_commands.hpp"
#include "cli/report_commands.hpp"
#include "cli/json_file.hpp"
#include "cli/separate_command.hpp"
#include "model/thermal_stages.hpp"
#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/feature_fit.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/point_cloud.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "evaluate/test_piece.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "interop/summary.hpp"
#include "model/stepped_prediction.hpp"
#include "parts/gum_model.hpp"
#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/sphere_artifact.hpp"
#include "parts/test_piece.hpp"
#include "planner/sphere_cycle.hpp"
#include "planner/test_piece.hpp"
#include "report/scene.hpp"
#include "report/ttp_scene.hpp"
#include "sim/rigid_campaign.hpp"
#include "sim/virtual_machine.hpp"
#include "verify/safety.hpp"

using namespace probeloop;
namespace fs = std::filesystem;

namespace {

std::string join(const std::string& dir, const std::string& file) {
  return (fs::path(dir) / file).string();
}

// A stepped workpiece's compensation predicted for the planned experiment (seed 000 Ch. 6): the
// experiment planned once for its conditions (each step's size, floor depth, feed, speed and
// Temp state), the components of another part's evaluation summed there
// (model/stepped_prediction.hpp); the offsets do not change the clock (micrometres).
parts::SwCompensation predictedCompensation(const planner::TestPiecePlan& first, const std::string& evaluation_file) {
  const auto& m = first.manifest;
  if (m.kind != "stepped_workpiece")
    throw InputError(evaluation_file, 0, "--predict-from: only a stepped workpiece's finishing takes a predicted compensation");
  const nlohmann::json j = cli::readJsonFile(evaluation_file);
  // A campaign's separation.json (`probeloop separate`): its process part with the thermal
  // stages; else one part's evaluation.json.
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

int cmdPlan(const std::string& piece_file, const std::string& machine_file, const std::string& out_dir,
            const std::string& dialect_opt, const std::string& experiment, const std::string& compensation_file,
            const std::string& predict_from) {
  const auto piece = parts::loadTestPiece(piece_file);
  std::optional<parts::SwCompensation> comp;
  if (!compensation_file.empty() && !predict_from.empty())
    throw InputError(predict_from, 0, "--predict-from and --compensate: give one (a prediction, or offsets already predicted)");
  if (!compensation_file.empty()) comp = parts::loadSwCompensation(compensation_file);
  const auto machine = parts::loadMachine(machine_file);
  const bool linux = dialect_opt == "linuxcnc" || (dialect_opt == "machine" && machine.dialect == parts::Dialect::LinuxCnc);
  const auto dialect = linux ? parts::Dialect::LinuxCnc : parts::Dialect::FanucMacroB;
  if (!predict_from.empty()) {
    comp = predictedCompensation(planner::planTestPiece(piece, machine, dialect, out_dir, experiment), predict_from);
    std::fputs(comp->basis.c_str(), stdout);
  }
  const auto plan = planner::planTestPiece(piece, machine, dialect, out_dir, experiment, comp ? &*comp : nullptr);
  // The safety verifier reads every program as a controller would (independent of the planner):
  // any finding refuses the plan before anything is written.
  std::vector<verify::ProgramText> texts;
  for (const auto& p : plan.programs) texts.push_back({p.file, p.text});
  const auto safety = verify::checkPrograms(texts, machine, piece);
  if (!safety.safe()) {
    std::fprintf(stderr, "probeloop: error: plan refused: the safety verifier found %zu problem(s) in the programs; nothing written\n%s",
                 safety.findings.size(), verify::reportText(safety).c_str());
    return 3;
  }
  // Everything is planned and checked before the first file is written.
  for (const auto& p : plan.programs) writeFileAtomic(join(out_dir, p.file), p.text);
  for (const auto& [name, content] : plan.files) writeFileAtomic(join(out_dir, name), content);
  writeFileAtomic(join(out_dir, "plan.json"), parts::manifestToJson(plan.manifest));
  std::fputs(plan.summary.c_str(), stdout);
  std::fputs(evaluate::planPrediction(plan.manifest, machine.x.resolution_mm).c_str(), stdout);
  return 0;
}

// Exit 0: safe; 3: findings (listed); 2: input the verifier cannot read (file:line: field).
int cmdCheck(const std::vector<std::string>& program_files, const std::string& machine_file, const std::string& part_file,
             bool json) {
  try {
    const auto machine = parts::loadMachine(machine_file);
    const auto piece = parts::loadTestPiece(part_file);
    std::vector<verify::ProgramText> texts;
    for (const auto& f : program_files) texts.push_back({f, readFile(f, kProgramInput)});
    const auto r = verify::checkPrograms(texts, machine, piece);
    if (json) {
      std::fputs(verify::reportJson(r).c_str(), stdout);
    } else {
      std::fputs(verify::reportText(r).c_str(), stdout);
      std::printf("%s: %zu finding(s) in %zu program(s)\nmodel: %s\n", r.safe() ? "safe" : "UNSAFE", r.findings.size(),
                  r.programs.size(), r.model.c_str());
    }
    return r.safe() ? 0 : 3;
  } catch (const InputError& e) {
    std::fprintf(stderr, "probeloop: error: %s\n", e.what());
    return 2;
  }
}

int cmdResolution(const std::string& artifact_file, const std::string& machine_file, double step_um) {
  const auto plan = planner::planSphereCycle(parts::loadSphereArtifact(artifact_file),
                                             parts::loadMachine(machine_file));
  std::fputs((evaluate::sphereResolutionText(evaluate::locationErrorResolution(plan.manifest, step_um * 1e-3), step_um) +
              evaluate::spherePredictionText(plan.manifest))
                 .c_str(),
             stdout);
  return 0;
}

int cmdSynth(const std::string& manifest_file, const std::string& truth_file,
             const std::string& out_dir, std::uint64_t seed) {
  const auto m = parts::readManifest(manifest_file);
  const auto truth = sim::loadRigidTruth(truth_file);
  const auto s = sim::synthesiseSphereCampaign(m, truth, seed);
  writeFileAtomic(join(out_dir, "sphere_probe.log"), s.linuxcnc_log);
  writeFileAtomic(join(out_dir, "sphere_probe_dprnt.txt"), s.fanuc_dprnt);
  writeFileAtomic(join(out_dir, "points.csv"), s.points_csv);
  writeFileAtomic(join(out_dir, "truth.json"), s.truth_json);
  std::printf("Synthesised %d cycles x %zu points (seed %llu) into %s: sphere_probe.log (LinuxCNC), "
              "sphere_probe_dprnt.txt (Fanuc), points.csv, truth.json\n",
              m.cycles, m.points.size(), static_cast<unsigned long long>(seed), out_dir.c_str());
  return 0;
}

int cmdSimulate(const std::vector<std::string>& program_files, const std::string& machine_file,
                const std::string& part_file, const std::string& truth_file, const std::string& out_dir,
                std::uint64_t seed, const std::string& cmm_file, bool trace, const std::string& schedule_file) {
  const auto machine = parts::loadMachine(machine_file);
  const auto truth = sim::loadMachineTruth(truth_file);
  const auto piece = parts::loadTestPiece(part_file);
  sim::SimulationPart part;
  part.test_piece = &piece;
  if (!cmm_file.empty()) {
    const std::string text = readFile(cmm_file);
    if (interop::looksLikeQif(text) || interop::looksLikeDmis(text)) {  // a QIF plan or a DMIS program: answered in both
      part.cmm_plan = interop::looksLikeQif(text) ? interop::parseQifPlan(text, cmm_file) : interop::parseDmisProgram(text, cmm_file);
      part.cmm_points = sim::cmmPointsOfQifPlan(*part.cmm_plan);
    } else {
      part.cmm_points = sim::readCmmPoints(cmm_file);
    }
    part.cmm_points_file = cmm_file;
  }
  part.trace = trace;
  std::vector<sim::ProgramSource> programs;
  for (const auto& f : program_files) programs.push_back({f, readFile(f, kProgramInput), std::nullopt});
  if (!schedule_file.empty()) {
    // Each program starts at its planned time; the machine is off in between.
    const auto m = parts::readManifest(schedule_file);
    for (auto& p : programs) {
      const std::string name = fs::path(p.file).filename().string();
      std::string planned;
      for (const auto& mp : m.programs) {
        if (mp.file == name) p.start_s = mp.start_s;
        planned += (planned.empty() ? "" : ", ") + mp.file;
      }
      if (!p.start_s)
        throw InputError(schedule_file, 0, "programs[].file: '" + name + "' is not planned here (the manifest plans " + planned + ")");
    }
  }
  const auto s = sim::simulatePrograms(programs, machine, part, truth, seed);
  std::string written;
  for (const auto& l : s.logs) {
    const std::string name = fs::path(l.name).filename().string();
    writeFileAtomic(join(out_dir, name), l.text);
    written += name + " (controller log), ";
  }
  writeFileAtomic(join(out_dir, "points.csv"), s.points_csv);
  writeFileAtomic(join(out_dir, "inputs.csv"), s.inputs_csv);
  writeFileAtomic(join(out_dir, "truth.json"), s.truth_json);
  std::string extra;
  if (!piece.sphereArtifact()) {
    writeFileAtomic(join(out_dir, "cuts.json"), s.cuts_json);
    extra += ", cuts.json";
  }
  if (trace) {
    writeFileAtomic(join(out_dir, "trace.csv"), s.trace_csv);
    extra += ", trace.csv";
  }
  if (!s.cmm_csv.empty()) {
    writeFileAtomic(join(out_dir, "cmm_export.csv"), s.cmm_csv);
    extra += ", cmm_export.csv";
  }
  if (!s.cmm_qif.empty()) {
    writeFileAtomic(join(out_dir, "cmm_results.qif"), s.cmm_qif);
    writeFileAtomic(join(out_dir, "cmm_results.dmo"), s.cmm_dmo);
    extra += ", cmm_results.qif, cmm_results.dmo";
  }
  const std::string what = program_files.size() == 1 ? program_files.front() : std::to_string(program_files.size()) + " programs";
  std::printf("Simulated %s on %s (seed %llu): %ld blocks, %ld probe events, %.1f h of machine time\n", what.c_str(),
              machine.name.c_str(), static_cast<unsigned long long>(seed), s.blocks, s.probe_events, s.end_time_s / 3600.0);
  std::printf("  wrote %spoints.csv, inputs.csv, truth.json%s in %s\n", written.c_str(), extra.c_str(), out_dir.c_str());
  return 0;
}

int cmdEvaluate(const std::string& points_file, const std::string& manifest_file, const std::string& out_dir,
                const std::string& format, bool free_radius, const std::string& scene_file,
                std::optional<double> exaggeration_opt, const std::string& compare_with, double gauge_resolution_um,
                const std::string& probe_log, const std::string& cycle_starts) {
  const auto m = parts::readManifest(manifest_file);
  evaluate::EvaluateRequest req;
  req.input_file = points_file;
  req.format = format;
  req.free_radius = free_radius;
  req.compare_with = compare_with;
  req.probe_log = probe_log;
  req.cycle_starts = cycle_starts;
  req.out_dir = out_dir;
  req.gauge_resolution_um = gauge_resolution_um;
  const auto f = evaluate::evaluateTestPiece(m, req);
  // Errors of a few um: x10000 puts them on the scale of a sphere campaign's table (0.3 m),
  // x1000 on the scale of a 0.2 m test piece (docs/report-thermal-test-piece.md).
  const double exaggeration = exaggeration_opt.value_or(f.sphere ? 10000.0 : 1000.0);
  if (!scene_file.empty() && f.thermal_test_piece && f.thermal_test_piece->route == evaluate::TtpRoute::Gauge)
    throw InputError(points_file, 0, "--scene: dial-gauge readings give no measured surfaces to draw (use a CMM export or an on-machine log)");
  std::string scene;
  if (!scene_file.empty() && f.sphere) {
    std::vector<report::CycleCentres> cc;
    for (const auto& c : f.sphere->cycles) {
      report::CycleCentres x;
      x.cycle = c.cycle;
      for (const auto& s : c.spheres) x.centre_mm.push_back(s.centre_mm());
      cc.push_back(x);
    }
    scene = report::campaignSceneGltf(m, cc, f.sphere->reference_cycle, exaggeration);
  } else if (!scene_file.empty()) {
    scene = report::thermalTestPieceSceneGltf(m, nlohmann::json::parse(f.evaluation_json), exaggeration);
  }
  writeFileAtomic(join(out_dir, evaluate::EvaluationFiles::kErrorsCsv), f.errors_csv);
  writeFileAtomic(join(out_dir, evaluate::EvaluationFiles::kEvaluationJson), f.evaluation_json);
  writeFileAtomic(join(out_dir, evaluate::EvaluationFiles::kReportMd), f.report_md);
  if (!f.compensation_json.empty()) writeFileAtomic(join(out_dir, "compensation.json"), f.compensation_json);
  if (!f.results_qif.empty()) writeFileAtomic(join(out_dir, evaluate::EvaluationFiles::kResultsQif), f.results_qif);
  std::fputs(f.stdout_text.c_str(), stdout);
  if (!scene.empty()) {
    writeFileAtomic(scene_file, scene);
    std::printf("Wrote %s (%s x%s)\n", scene_file.c_str(), f.sphere ? "error vectors" : "deviation vectors",
                formatNumber(exaggeration).c_str());
  }
  return 0;
}

// Results when the file has any; a plan (its nominal features and planned points) otherwise.
int cmdRead(const std::string& file, bool json) {
  const std::string text = readFile(file);
  if (interop::looksLikeDmis(text)) {  // a program (DMISMN: its nominals and PTMEAS points) or output (FILNAM)
    const bool program = interop::isDmisProgram(text);
    const auto d = program ? interop::parseDmisProgram(text, file) : interop::parseDmisOutput(text, file);
    std::fputs((json ? interop::cmmDocumentJson(d) : interop::cmmDocumentText(d)).c_str(), stdout);
    return 0;
  }
  auto d = interop::parseQifResults(text, file);
  if (d.runs == 0 && d.features.empty()) {
    try {
      d = interop::parseQifPlan(text, file);
    } catch (const InputError&) {  // no feature nominals either: the empty results say so
    }
  }
  std::fputs((json ? interop::cmmDocumentJson(d) : interop::cmmDocumentText(d)).c_str(), stdout);
  return 0;
}

int cmdGum(const std::string& model_file, bool mcm, long trials, std::uint64_t seed, int digits,
           const std::string& json_file) {
  const auto model = parts::loadGumModel(model_file);
  std::optional<uncertainty::McmOptions> mo;
  if (mcm) {
    uncertainty::McmOptions o;
    o.fixed_trials = trials;
    o.seed = seed;
    o.significant_digits = digits;
    if (isatty(STDERR_FILENO))  // a progress line on long runs, only for a person watching
      o.progress = [](long done) { std::fprintf(stderr, "\rMonte Carlo: %ld trials", done); };
    mo = o;
  }
  const auto r = uncertainty::evaluateTextModel(model, mo);
  if (mo && mo->progress) std::fprintf(stderr, "\r%40s\r", "");
  if (!json_file.empty()) writeFileAtomic(json_file, uncertainty::textModelJson(model, r));
  std::fputs(uncertainty::textModelReport(model, r).c_str(), stdout);
  if (!json_file.empty()) std::printf("\nWrote %s\n", json_file.c_str());
  return 0;
}

struct FitArgs {
  std::string kind, points, method = "ls", format = "auto", feature, material, approach, out;
  double tip_radius_mm = 0.0;
  std::optional<double> radius_mm, outliers_k, point_u_um;
  int outlier_rounds = 10;
  double outlier_max_fraction = 0.2;
  bool json = false;
};

Eigen::Vector3d parseVector(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    double x = 0;
    if (!parseFiniteNumber(part, x))
      throw InputError("", 0, option + " expects nx,ny,nz; '" + part + "' is not a number");
    v.push_back(x);
  }
  if (v.size() != 3 || Eigen::Vector3d(v[0], v[1], v[2]).norm() == 0.0)
    throw InputError("", 0, option + " expects three numbers nx,ny,nz, not all zero");
  return Eigen::Vector3d(v[0], v[1], v[2]).normalized();
}

int cmdFit(const FitArgs& a) {
  evaluate::FeatureFitRequest req;
  req.kind = *geometry::parseElementKind(a.kind);  // checked by CLI11
  req.options.method = *geometry::parseFitMethod(a.method);
  req.options.fixed_radius_mm = a.radius_mm;
  if (a.outliers_k)
    req.options.outliers = geometry::OutlierOptions{*a.outliers_k, a.outlier_rounds, a.outlier_max_fraction};
  req.tip_radius_mm = a.tip_radius_mm;
  if (!a.material.empty())
    req.side = a.material == "inside" ? geometry::MaterialSide::Inside : geometry::MaterialSide::Outside;
  if (!a.approach.empty()) req.approach = parseVector(a.approach, "--approach");
  if (a.point_u_um) req.point_u_mm = *a.point_u_um / 1000.0;
  const auto cloud = evaluate::readPointCloud(a.points, a.format, a.feature);
  const auto rep = evaluate::fitFeature(cloud, req);
  const std::string json = evaluate::featureFitJson(cloud, rep);
  if (!a.out.empty()) writeFileAtomic(a.out, json);
  std::fputs(a.json ? json.c_str() : evaluate::featureFitText(cloud, rep).c_str(), stdout);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  probeloop::removeTemporaryFileOnInterrupt();
  CLI::App app{"probeloop: plan, simulate and evaluate touch-probe cycles for machine-tool metrology"};
  app.require_subcommand(1);

  std::string artifact, machine, out = ".", dialect = "machine", experiment, manifest, truth, points,
              format = "auto", scene;
  double step_um = 1.0, gauge_resolution_um = 1.0;
  std::optional<double> exaggeration;
  std::uint64_t seed = 1;
  bool free_radius = false;

  auto* plan = app.add_subcommand("plan", "Programs (G-code) and the plan manifest for a test piece: sphere artifact, thermal test piece, stepped workpiece");
  plan->add_option("piece", artifact, "test-piece description (YAML, kind: sphere_artifact | thermal_test_piece | stepped_workpiece)")->required()->check(cli::inputFile());
  plan->add_option("--machine", machine, "machine description (YAML)")->required()->check(cli::inputFile());
  plan->add_option("--out", out, "output folder")->capture_default_str();
  plan->add_option("--dialect", dialect, "machine (from the machine file), linuxcnc or fanuc")
      ->check(CLI::IsMember({"machine", "linuxcnc", "fanuc"}))->capture_default_str();
  plan->add_option("--experiment", experiment, "stepped workpiece: the experiment to plan (W1 ... W8, Table 4.1)");
  std::string compensate;
  std::string predict_from;
  plan->add_option("--predict-from", predict_from, "stepped workpiece: another part's evaluation.json; its separated components, "
                   "fitted against feed and Temp state, predict this experiment's wall and floor errors, which the finishing "
                   "path takes out (seed 000 Ch. 6)")->check(cli::inputFile());
  plan->add_option("--compensate", compensate, "stepped workpiece: compensation.json (from evaluate): the predicted wall and "
                   "floor errors taken out of the finishing path (seed 000 Ch. 6)")->check(cli::inputFile());

  std::string read_file;
  bool read_json = false;
  auto* rd = app.add_subcommand("read", "What probeloop reads in a CMM exchange file (QIF 3.0 Results or Plan, DMIS output or "
                                "program): features, points, units");
  rd->add_option("file", read_file, "QIF 3.0 or DMIS file")->required()->check(cli::inputFile());
  rd->add_flag("--json", read_json, "print JSON (every feature with its geometry and points, in mm)");

  auto* res = app.add_subcommand("resolution", "Resolution of the location errors (seed 004 Table 5.4)");
  res->add_option("artifact", artifact, "sphere artifact description (YAML)")->required()->check(cli::inputFile());
  res->add_option("--machine", machine, "machine description (YAML)")->required()->check(cli::inputFile());
  res->add_option("--step-um", step_um, "coordinate step, um")->capture_default_str()->check(CLI::PositiveNumber);

  auto* syn = app.add_subcommand("synth", "Test generator: logs of a campaign with known rigid-body C-axis errors");
  syn->add_option("manifest", manifest, "plan manifest (plan.json)")->required()->check(cli::inputFile());
  syn->add_option("--truth", truth, "truth description (YAML)")->required()->check(cli::inputFile());
  syn->add_option("--out", out, "output folder")->capture_default_str();
  syn->add_option("--seed", seed, "random seed")->capture_default_str();

  std::vector<std::string> sim_programs;
  std::string part;
  auto* simc = app.add_subcommand("simulate", "Run emitted programs, one after the other, on a virtual machine with known error effects");
  simc->add_option("programs", sim_programs, "G-code programs (.ngc LinuxCNC, .nc Fanuc macro B), run back to back")
      ->required()->check(cli::inputFile());
  simc->add_option("--machine", machine, "machine description (YAML)")->required()->check(cli::inputFile());
  std::string cmm_points;
  bool sim_trace = false;
  simc->add_option("--part", part, "what stands on the table: a sphere artifact, a thermal test piece or a workpiece (YAML)")->required()->check(cli::inputFile());
  simc->add_option("--truth", truth, "the machine's error effects (YAML, kind: machine_truth)")->required()->check(cli::inputFile());
  simc->add_option("--out", out, "output folder")->capture_default_str();
  simc->add_option("--seed", seed, "random seed")->capture_default_str();
  simc->add_option("--cmm-points", cmm_points, "machined part: CMM points to measure after the programs "
                   "(feature,point,x_mm,y_mm,z_mm,nx,ny,nz; or a QIF 3.0 plan or a DMIS program: then cmm_results.qif and .dmo too)")->check(cli::inputFile());
  simc->add_flag("--trace", sim_trace, "also write trace.csv: every motion, dwell and tool change with its time and line");
  std::string schedule;
  simc->add_option("--schedule", schedule, "plan manifest (plan.json): start each program at its planned time, the machine "
                   "off in between (the stepped workpiece's 3 h waits)")->check(cli::inputFile());

  std::vector<std::string> check_programs;
  bool check_json = false;
  auto* chk = app.add_subcommand("check", "Safety verifier: travel, collisions, probe protection, rotary moves and spindle "
                                          "checked from the program text (exit 0 safe, 3 findings, 2 bad input)");
  chk->add_option("programs", check_programs, "G-code programs (.ngc LinuxCNC, .nc Fanuc macro B), run back to back "
                  "(material cut by one is gone for the next)")->required()->check(cli::inputFile());
  chk->add_option("--machine", machine, "machine description (YAML)")->required()->check(cli::inputFile());
  chk->add_option("--part", part, "what stands on the table: a sphere artifact, a thermal test piece, a stepped workpiece "
                  "or a workpiece (YAML)")->required()->check(cli::inputFile());
  chk->add_flag("--json", check_json, "the report as JSON");

  std::string compare_with;
  auto* ev = app.add_subcommand("evaluate", "Errors of a test piece from probe logs, points CSV, a CMM export or dial-gauge readings");
  ev->add_option("points", points, "LinuxCNC log, Fanuc DPRNT output, points CSV, CMM export (CSV, QIF 3.0 Results or DMIS output) or gauge CSV")->required()->check(cli::inputFile());
  ev->add_option("--manifest", manifest, "plan manifest (plan.json)")->required()->check(cli::inputFile());
  ev->add_option("--out", out, "output folder")->capture_default_str();
  ev->add_option("--format", format, "auto, linuxcnc, fanuc, csv, cmm, qif, dmis or gauge")
      ->check(CLI::IsMember({"auto", "linuxcnc", "fanuc", "csv", "cmm", "qif", "dmis", "gauge"}))->capture_default_str();
  ev->add_flag("--free-radius", free_radius, "sphere centres from the free-radius fit (default: known radius)");
  ev->add_option("--scene", scene, "also write a glTF scene (the sphere campaign, or the test piece with its deviations)");
  ev->add_option("--exaggeration", exaggeration, "scale of the error vectors in the scene (default: 10000 sphere campaign, 1000 test piece)");
  ev->add_option("--gauge-resolution-um", gauge_resolution_um,
                 "thermal test piece, dial-gauge readings: the gauge's resolution (rectangular; not stated in the thesis)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  std::string probe_log;
  ev->add_option("--probe-log", probe_log, "stepped workpiece: the on-machine probe log, evaluated with the CMM export (seed 000: CMM - probe)")
      ->check(cli::inputFile());
  std::string cycle_starts;
  ev->add_option("--cycle-starts", cycle_starts, "sphere campaign: a CSV cycle,start_s of when each cycle started (s, the inputs' "
                 "clock), for a log without clocks; replaces the plan's schedule")->check(cli::inputFile());
  ev->add_option("--compare", compare_with, "another run's evaluation.json: thermal test piece, seed 004 Table 7.2 reductions; stepped workpiece, the part before its compensation (before/after)")
      ->check(cli::inputFile());

  FitArgs fa;
  auto* fit = app.add_subcommand("fit", "Fit one geometric element to a point cloud (CSV, NIST .ds, XYZ, PLY)");
  fit->add_option("kind", fa.kind, "line2d, line3d, plane, circle2d, circle3d, sphere, cylinder or cone")
      ->required()->check(CLI::IsMember({"line2d", "line3d", "plane", "circle2d", "circle3d", "sphere", "cylinder", "cone"}));
  fit->add_option("points", fa.points, "points file")->required()->check(cli::inputFile());
  fit->add_option("--method", fa.method, "ls (least squares), mz (minimum zone), mi (maximum inscribed), mc (minimum circumscribed)")
      ->check(CLI::IsMember({"ls", "mz", "mi", "mc"}))->capture_default_str();
  fit->add_option("--format", fa.format, "auto, csv, ds, xyz or ply")
      ->check(CLI::IsMember({"auto", "csv", "ds", "xyz", "ply"}))->capture_default_str();
  fit->add_option("--feature", fa.feature, "points CSV: use the rows of this feature only");
  fit->add_option("--tip-radius", fa.tip_radius_mm, "stylus tip radius, mm: the points are tip centres")->capture_default_str();
  fit->add_option("--material", fa.material, "material side for tip compensation when the file has no approach directions: inside (ball, shaft) or outside (bore)")
      ->check(CLI::IsMember({"inside", "outside"}));
  fit->add_option("--approach", fa.approach, "one nominal approach direction nx,ny,nz for all points (planes, lines)");
  fit->add_option("--radius", fa.radius_mm, "known radius, mm (least squares: circle, sphere, cylinder)");
  fit->add_option("--outliers", fa.outliers_k, "eliminate outliers beyond k standard deviations (iterated)");
  fit->add_option("--outlier-rounds", fa.outlier_rounds, "at most this many elimination rounds")->capture_default_str();
  fit->add_option("--outlier-max-fraction", fa.outlier_max_fraction, "refuse to drop more than this fraction")->capture_default_str();
  fit->add_option("--point-u", fa.point_u_um, "point standard uncertainty, um (type B parameter uncertainties)");
  fit->add_flag("--json", fa.json, "print the JSON report instead of the text summary");
  fit->add_option("--out", fa.out, "also write the JSON report to this file");

  std::string gum_model, gum_json;
  bool gum_mcm = false;
  long gum_trials = 0;
  int gum_digits = 2;
  auto* gum = app.add_subcommand("gum", "Uncertainty of a user measurement model (YAML): GUM budget, Monte Carlo, validation");
  gum->add_option("model", gum_model, "measurement model (YAML, kind: gum_model)")->required()->check(cli::inputFile());
  gum->add_flag("--mcm", gum_mcm, "also run the Monte Carlo method (JCGM 101) and validate the GUF against it");
  gum->add_option("--trials", gum_trials, "Monte Carlo trials (0: adaptive, JCGM 101 7.9)")->capture_default_str()->check(CLI::NonNegativeNumber);
  gum->add_option("--digits", gum_digits, "adaptive stop: significant digits of u (n_dig)")->capture_default_str()->check(CLI::Range(1, 4));
  gum->add_option("--seed", seed, "random seed")->capture_default_str();
  gum->add_option("--json", gum_json, "also write the results as JSON to this file");

  CLI::App* model_group = nullptr;
  const auto run_model = cli::addModelCommands(app, model_group);
  CLI::App* report_group = nullptr;
  const auto run_report = cli::addReportCommands(app, report_group);
  CLI::App* separate_cmd = nullptr;
  const auto run_separate = cli::addSeparateCommand(app, separate_cmd);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11's own codes (105 for a file option, 106 for a number...) are not ours: every usage
    // error, an input path that is not a readable regular file included, exits 2 (cli/README.md).
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  const auto dispatch = [&]() -> int {
    if (*model_group) return run_model();
    if (*report_group) return run_report();
    if (*separate_cmd) return run_separate();
    if (*plan) return cmdPlan(artifact, machine, out, dialect, experiment, compensate, predict_from);
    if (*res) return cmdResolution(artifact, machine, step_um);
    if (*rd) return cmdRead(read_file, read_json);
    if (*syn) return cmdSynth(manifest, truth, out, seed);
    if (*chk) return cmdCheck(check_programs, machine, part, check_json);
    if (*simc) return cmdSimulate(sim_programs, machine, part, truth, out, seed, cmm_points, sim_trace, schedule);
    if (*fit) return cmdFit(fa);
    if (*gum) return cmdGum(gum_model, gum_mcm || gum_trials > 0, gum_trials, seed, gum_digits, gum_json);
    if (*ev)
      return cmdEvaluate(points, manifest, out, format, free_radius, scene, exaggeration, compare_with, gauge_resolution_um, probe_log, cycle_starts);
    return 2;
  };
  try {
    // All of a command's outputs or none (docs/reliability.md#all-or-nothing): the files are
    // written as temporaries and renamed into place only after the command succeeded.
    OutputBatch outputs;
    const int code = dispatch();
    if (code == 0) outputs.commit();
    return code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "probeloop: error: %s\n", e.what());
    return 1;
  }
}
