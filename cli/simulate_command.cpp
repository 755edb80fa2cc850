// `probeloop simulate`: programs run back to back on the virtual machine; its logs, points,
// inputs, truth, cuts and CMM results written to --out.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "cli/commands.hpp"
#include "campaign/dashboard.hpp"
#include "campaign/live_loop.hpp"
#include "campaign/sim_link.hpp"
#include "cli/input_option.hpp"
#include "cli/talc_options.hpp"
#include "report/vega.hpp"
#include "core/atomic_file.hpp"
#include "core/paths.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "sim/machine_truth.hpp"
#include "sim/run_inputs.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::cli {
namespace {

struct SimulateArgs {
  std::vector<std::string> programs;
  std::string machine, part, truth, out = ".", cmm_points, schedule;
  std::uint64_t seed = 1;
  bool trace = false;
  // The live loop closed on the virtual machine.
  std::string live_store, talc_inputs;
  campaign::LiveOptions live;
  double until_h = 0;
};

int runSimulate(const SimulateArgs& a) {
  const auto machine = parts::loadMachine(a.machine);
  const auto truth = sim::loadMachineTruth(a.truth);
  const auto piece = parts::loadTestPiece(a.part);
  sim::SimulationPart part;
  part.test_piece = &piece;
  if (!a.cmm_points.empty()) sim::loadCmmRequest(part, a.cmm_points);
  part.trace = a.trace;
  std::vector<sim::ProgramSource> programs;
  for (const auto& f : a.programs) programs.push_back({f, readProgramFile(f), std::nullopt});
  if (!a.schedule.empty()) sim::scheduleFromManifest(programs, a.schedule);
  if (a.until_h > 0) part.until_s = a.until_h * 3600.0;
  // The live loop on the controller side: its store follows the log and the inputs as the
  // machine writes them, its offsets move the axes, its wait paces the cycles.
  std::unique_ptr<campaign::CampaignStore> store;
  std::unique_ptr<campaign::LiveLoop> loop;
  std::unique_ptr<campaign::StoreLiveLink> link;
  const std::string live_dir = pathIn(a.out, "live");
  if (!a.live_store.empty()) {
    store = std::make_unique<campaign::CampaignStore>(a.live_store);
    campaign::LiveOptions o = a.live;
    o.talc.inputs = talcInputsFrom(a.talc_inputs);
    o.offsets_applied = true;
    loop = std::make_unique<campaign::LiveLoop>(*store, o);
    link = std::make_unique<campaign::StoreLiveLink>(*store, *loop, live_dir, &machine);
    part.live = link.get();
  }
  const auto s = sim::simulatePrograms(programs, machine, part, truth, a.seed);
  if (link) link->finish();
  std::string written;
  for (const auto& l : s.logs) {
    const std::string name = std::filesystem::path(l.name).filename().string();
    writeFileAtomic(pathIn(a.out, name), l.text);
    written += name + " (controller log), ";
  }
  writeFileAtomic(pathIn(a.out, "points.csv"), s.points_csv);
  writeFileAtomic(pathIn(a.out, "inputs.csv"), s.inputs_csv);
  writeFileAtomic(pathIn(a.out, "truth.json"), s.truth_json);
  std::string extra;
  if (!piece.sphereArtifact()) {
    writeFileAtomic(pathIn(a.out, "cuts.json"), s.cuts_json);
    extra += ", cuts.json";
  }
  if (a.trace) {
    writeFileAtomic(pathIn(a.out, "trace.csv"), s.trace_csv);
    extra += ", trace.csv";
  }
  if (!s.cmm_csv.empty()) {
    writeFileAtomic(pathIn(a.out, "cmm_export.csv"), s.cmm_csv);
    extra += ", cmm_export.csv";
  }
  if (!s.cmm_qif.empty()) {
    writeFileAtomic(pathIn(a.out, "cmm_results.qif"), s.cmm_qif);
    writeFileAtomic(pathIn(a.out, "cmm_results.dmo"), s.cmm_dmo);
    extra += ", cmm_results.qif, cmm_results.dmo";
  }
  const std::string what = a.programs.size() == 1 ? a.programs.front() : std::to_string(a.programs.size()) + " programs";
  std::printf("Simulated %s on %s (seed %llu): %ld blocks, %ld probe events, %.1f h of machine time\n", what.c_str(),
              machine.name.c_str(), static_cast<unsigned long long>(a.seed), s.blocks, s.probe_events, s.end_time_s / 3600.0);
  std::printf("  wrote %spoints.csv, inputs.csv, truth.json%s in %s\n", written.c_str(), extra.c_str(), a.out.c_str());
  if (loop) {
    const std::string dashboard = pathIn(live_dir, "dashboard.html");
    writeFileAtomic(dashboard, campaign::liveDashboardHtml(*store, *loop, report::defaultVegaPath()));
    std::printf("Live TALC loop on the controller side (%d syncs): store %s, dashboard %s\n", link->syncs(),
                a.live_store.c_str(), dashboard.c_str());
    std::fputs(campaign::liveSummaryText(*loop).c_str(), stdout);
  }
  return 0;
}

}  // namespace

Subcommand addSimulateCommand(CLI::App& app) {
  auto a = std::make_shared<SimulateArgs>();
  auto* simc = app.add_subcommand("simulate", "Run emitted programs, one after the other, on a virtual machine with known error effects");
  simc->add_option("programs", a->programs, "G-code programs (.ngc LinuxCNC, .nc Fanuc macro B), run back to back")
      ->required()->check(inputFile());
  simc->add_option("--machine", a->machine, "machine description (YAML)")->required()->check(inputFile());
  simc->add_option("--part", a->part, "what stands on the table: a sphere artifact, a thermal test piece or a workpiece (YAML)")->required()->check(inputFile());
  simc->add_option("--truth", a->truth, "the machine's error effects (YAML, kind: machine_truth)")->required()->check(inputFile());
  simc->add_option("--out", a->out, "output folder")->capture_default_str();
  simc->add_option("--seed", a->seed, "random seed")->capture_default_str();
  simc->add_option("--cmm-points", a->cmm_points, "machined part: CMM points to measure after the programs "
                   "(feature,point,x_mm,y_mm,z_mm,nx,ny,nz; or a QIF 3.0 plan or a DMIS program: then cmm_results.qif and .dmo too)")->check(inputFile());
  simc->add_flag("--trace", a->trace, "also write trace.csv: every motion, dwell and tool change with its time and line");
  simc->add_option("--live", a->live_store, "campaign store (campaign init): run the live TALC loop while the machine runs, "
                   "its offsets applied and its interval read by the program (Fanuc #500, LinuxCNC analog input 0)")->check(inputFile());
  addTalcOptions(simc, a->live.talc, a->talc_inputs);
  simc->add_option("--grid-s", a->live.grid_s, "with --live: the prediction grid, s (default: the plan's cycle period)")->check(CLI::PositiveNumber);
  simc->add_flag("--requested-only", a->live.requested_only, "with --live: feed TALC only the cycles it asks for (a dense "
                 "program measuring for visualisation, as the thesis did: every cycle compensated and scored)");
  simc->add_option("--until-h", a->until_h, "stop the machine at this time, h (a live campaign's program may run longer)")->check(CLI::PositiveNumber);
  simc->add_option("--schedule", a->schedule, "plan manifest (plan.json): start each program at its planned time, the machine "
                   "off in between (the stepped workpiece's 3 h waits)")->check(inputFile());
  return {simc, [a] { return runSimulate(*a); }};
}

}  // namespace probeloop::cli
