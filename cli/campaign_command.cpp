// `probeloop campaign init | ingest | status | export`: a campaign followed in its store
// (campaign/store.hpp) while the machine runs.
#include <cstdio>
#include <filesystem>
#include <memory>

#include <chrono>
#include <cmath>
#include <csignal>
#include <nlohmann/json.hpp>
#include <thread>

#include "campaign/dashboard.hpp"
#include "campaign/live_loop.hpp"
#include "campaign/store.hpp"
#include "cli/talc_options.hpp"
#include "model/indicators.hpp"
#include "report/vega.hpp"
#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/paths.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::cli {
namespace {

struct CampaignArgs {
  std::string store, manifest, inputs, out = ".";
  std::vector<std::string> logs, stores;
  bool finished = false;
  CLI::App *init = nullptr, *ingest = nullptr, *status = nullptr, *exporter = nullptr, *run = nullptr,
           *add_input = nullptr;
  std::string input_name;
  // run
  campaign::LiveOptions live;
  std::string talc_inputs, dashboard, controller_file;
  bool follow = false;
  double poll_s = 2, idle_exit_s = 0;
};

volatile std::sig_atomic_t g_stop = 0;
extern "C" void onStopSignal(int) { g_stop = 1; }

// What the controller side reads (a HAL component, a FOCAS writer): replaced atomically.
void writeControllerFile(const std::string& path, const campaign::LiveLoop& loop, double now_s, bool live) {
  nlohmann::ordered_json j;
  j["time_s"] = now_s;
  j["phase"] = model::talcPhaseName(loop.phase());
  j["wait_s"] = loop.waitSeconds(now_s);
  const auto c = loop.compensationAt(now_s);
  if (c) {
    nlohmann::ordered_json e;
    for (int i = 0; i < geometry::LocationErrors::kCount; ++i) e[geometry::LocationErrors::names()[i]] = (*c)[i];
    j["compensation"] = e;
  } else {
    j["compensation"] = nullptr;
  }
  // Following, the controller side reads it while the loop runs: it cannot wait for the
  // command's commit (core/atomic_file.hpp). A single pass writes it with the other outputs.
  if (live) {
    writeLiveFileAtomic(path, j.dump(1) + "\n");
  } else {
    writeFileAtomic(path, j.dump(1) + "\n");
  }
}

int runLive(const CampaignArgs& a) {
  campaign::CampaignStore store(a.store);
  campaign::LiveOptions o = a.live;
  o.talc.inputs = talcInputsFrom(a.talc_inputs);
  campaign::LiveLoop loop(store, o);
  if (a.follow) {
    std::signal(SIGINT, onStopSignal);
    std::signal(SIGTERM, onStopSignal);
  }
  double idle_s = 0;
  for (;;) {
    int added = 0;
    bool pending = false;
    if (!a.inputs.empty()) added += store.ingestInputs(a.inputs);
    for (const auto& log : a.logs) {
      const auto r = store.ingestLog(log, a.finished);
      added += r.lines;
      pending = pending || r.waiting_bytes > 0;
      for (int c : r.incomplete) std::printf("cycle %d incomplete\n", c);
    }
    const auto p = loop.advance(a.finished, pending);
    for (const auto& e : p.events)
      std::printf("t = %s h  %s%s\n", formatNumber(e.t_s / 3600.0, 3).c_str(),
                  e.channel.empty() ? "" : (e.channel + " residual " + formatNumber(e.residual, 2) + ": ").c_str(),
                  e.action.c_str());
    const auto s = store.status();
    double now = s.inputs_last_time_s;
    for (const auto& c : s.cycles) now = std::max(now, c.time_s);
    if (!a.dashboard.empty()) {
      const std::string html = campaign::liveDashboardHtml(store, loop, report::defaultVegaPath());
      if (a.follow) {
        writeLiveFileAtomic(a.dashboard, html);
      } else {
        writeFileAtomic(a.dashboard, html);
      }
    }
    if (!a.controller_file.empty()) writeControllerFile(a.controller_file, loop, now, a.follow);
    if (!a.follow || g_stop) break;
    idle_s = added > 0 || p.ticks > 0 || p.measurements > 0 ? 0 : idle_s + a.poll_s;
    if (a.idle_exit_s > 0 && idle_s >= a.idle_exit_s) break;
    for (double slept = 0; slept < a.poll_s && !g_stop; slept += 0.05) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (g_stop) break;
  }
  std::fputs(campaign::liveSummaryText(loop).c_str(), stdout);
  if (!loop.latestDiagnosis().empty()) std::printf("diagnosis at the latest update: %s\n", loop.latestDiagnosis().c_str());
  return 0;
}

std::string latestErrors(const campaign::CycleStatus& c) {
  std::string s;
  for (int i = 0; i < geometry::LocationErrors::kCount; ++i)
    s += std::string(i == 0 ? "" : ", ") + geometry::LocationErrors::names()[i] + " " + formatNumber(c.values[i], 2) +
         " +- " + formatNumber(c.U[i], 2);
  return s;
}

void printStatus(const campaign::StoreStatus& s) {
  int evaluated = 0, incomplete = 0;
  const campaign::CycleStatus* last = nullptr;
  for (const auto& c : s.cycles) {
    if (c.status == "incomplete") {
      ++incomplete;
    } else {
      ++evaluated;
      last = &c;
    }
  }
  std::printf("campaign store %s (schema %d)\n", s.path.c_str(), s.schema_version);
  std::printf("  machine %s; plan %s: %d cycles planned\n", s.machine.c_str(), s.manifest_file.c_str(), s.planned_cycles);
  std::printf("  %d probe points, %d lines quarantined, %d input samples", s.points, s.quarantined, s.input_samples);
  if (s.input_samples > 0) std::printf(" (last at %s h)", formatNumber(s.inputs_last_time_s / 3600.0, 3).c_str());
  std::printf("\n  cycles: %d evaluated (reference %d), %d incomplete\n", evaluated, s.reference_cycle, incomplete);
  if (last)
    std::printf("  latest, cycle %d at %s h (U, k = 2): %s\n", last->cycle, formatNumber(last->time_s / 3600.0, 3).c_str(),
                latestErrors(*last).c_str());
  for (const auto& c : s.cycles)
    if (c.status == "incomplete") std::printf("  cycle %d incomplete: %s\n", c.cycle, c.reason.c_str());
  for (const auto& q : s.quarantine) std::printf("  quarantined: %s\n", q.c_str());
}

// A folder of stores (one per machine): one row each. A file that is not a store is named and
// skipped; the exit code says whether any was.
int fleetStatus(const std::string& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(folder))
    if (e.is_regular_file() && !e.path().string().ends_with("-wal") && !e.path().string().ends_with("-shm"))
      files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::printf("store,machine,cycles_evaluated,cycles_incomplete,quarantined,last_cycle,last_time_h");
  for (const char* n : geometry::LocationErrors::names()) std::printf(",%s,U_%s", n, n);
  std::printf("\n");
  int bad = 0;
  for (const auto& f : files) {
    try {
      campaign::CampaignStore store(f.string());
      const auto s = store.status();
      int evaluated = 0, incomplete = 0;
      const campaign::CycleStatus* last = nullptr;
      for (const auto& c : s.cycles)
        if (c.status == "incomplete") {
          ++incomplete;
        } else {
          ++evaluated;
          last = &c;
        }
      std::printf("%s,%s,%d,%d,%d,", f.filename().string().c_str(), s.machine.c_str(), evaluated, incomplete, s.quarantined);
      if (last) {
        std::printf("%d,%s", last->cycle, formatNumber(last->time_s / 3600.0, 3).c_str());
        for (std::size_t i = 0; i < last->values.size(); ++i)
          std::printf(",%s,%s", formatNumber(last->values[i], 4).c_str(), formatNumber(last->U[i], 4).c_str());
      } else {
        std::printf(",");
        for (int i = 0; i < geometry::LocationErrors::kCount; ++i) std::printf(",,");
      }
      std::printf("\n");
    } catch (const InputError& e) {
      std::fprintf(stderr, "probeloop: skipped: %s\n", e.what());
      ++bad;
    }
  }
  return bad == 0 ? 0 : 1;
}

int runCampaign(const CampaignArgs& a) {
  if (*a.init) {
    campaign::CampaignStore::create(a.store, a.manifest);
    std::printf("Created the campaign store %s for %s\n", a.store.c_str(), a.manifest.c_str());
    return 0;
  }
  if (*a.ingest) {
    if (a.logs.empty() && a.inputs.empty()) throw InputError("", 0, "campaign ingest: give --log and/or --inputs");
    campaign::CampaignStore store(a.store);
    if (!a.inputs.empty())
      std::printf("%s: %d input samples added\n", a.inputs.c_str(), store.ingestInputs(a.inputs));
    for (const auto& log : a.logs) {
      const auto r = store.ingestLog(log, a.finished);
      std::printf("%s: %d lines, %d points, %d quarantined%s", log.c_str(), r.lines, r.points, r.quarantined,
                  r.waiting_bytes > 0 ? (", a torn last line of " + std::to_string(r.waiting_bytes) + " bytes waits").c_str() : "");
      std::string cycles;
      for (int c : r.evaluated) cycles += " " + std::to_string(c);
      if (!cycles.empty()) std::printf("; evaluated cycle(s)%s", cycles.c_str());
      cycles.clear();
      for (int c : r.incomplete) cycles += " " + std::to_string(c);
      if (!cycles.empty()) std::printf("; incomplete:%s", cycles.c_str());
      std::printf("\n");
    }
    return 0;
  }
  if (*a.status) {
    int code = 0;
    for (const auto& s : a.stores) {
      if (std::filesystem::is_directory(s)) {
        code = std::max(code, fleetStatus(s));
      } else {
        campaign::CampaignStore store(s);
        printStatus(store.status());
      }
    }
    return code;
  }
  if (*a.run) return runLive(a);
  if (*a.add_input) {
    campaign::CampaignStore store(a.store);
    campaign::requestLiveInput(store, a.input_name);
    std::printf("%s: %s requested; the live loop takes it at its next pass and fits with it from its next update\n",
                a.store.c_str(), a.input_name.c_str());
    return 0;
  }
  campaign::CampaignStore store(a.store);
  const std::string errors = store.exportErrorsCsv(), inputs = store.exportInputsCsv();
  if (errors.empty() && inputs.empty())
    throw InputError(a.store, 0, "nothing to export yet: no cycle evaluated and no input ingested");
  if (!errors.empty()) {
    writeFileAtomic(pathIn(a.out, "errors.csv"), errors);
    std::printf("Wrote %s\n", pathIn(a.out, "errors.csv").c_str());
  }
  if (!inputs.empty()) {
    writeFileAtomic(pathIn(a.out, "inputs.csv"), inputs);
    std::printf("Wrote %s\n", pathIn(a.out, "inputs.csv").c_str());
  }
  return 0;
}

}  // namespace

Subcommand addCampaignCommands(CLI::App& app) {
  auto a = std::make_shared<CampaignArgs>();
  auto* group = app.add_subcommand("campaign", "A campaign followed in its store (SQLite) while the machine runs: init, ingest, run, status, export");
  group->require_subcommand(1);
  a->init = group->add_subcommand("init", "Create a campaign store for a sphere-artifact plan");
  a->init->add_option("store", a->store, "the store to create (one file, e.g. machine-7.campaign)")->required();
  a->init->add_option("--manifest", a->manifest, "plan manifest (plan.json)")->required()->check(inputFile());
  a->ingest = group->add_subcommand("ingest", "Read what the controller log and the inputs gained since the last ingest; evaluate every cycle that became final");
  a->ingest->add_option("store", a->store, "campaign store")->required()->check(inputFile());
  a->ingest->add_option("--log", a->logs, "LinuxCNC LOG or Fanuc DPRNT capture (may still be growing)")->check(inputFile());
  a->ingest->add_option("--inputs", a->inputs, "inputs CSV a data logger appends to (time_s, then one column per input)")->check(inputFile());
  a->ingest->add_flag("--finished", a->finished, "the log is complete: its last cycle is final even with points missing");
  a->status = group->add_subcommand("status", "What a store holds; a folder of stores: one CSV row per store");
  a->status->add_option("stores", a->stores, "campaign store(s) or folder(s) of stores")->required()->check(CLI::ExistingPath);
  a->exporter = group->add_subcommand("export", "Write errors.csv and inputs.csv, as `evaluate` and `simulate` do, for the model and report commands");
  a->exporter->add_option("store", a->store, "campaign store")->required()->check(inputFile());
  a->exporter->add_option("--out", a->out, "output folder")->capture_default_str();
  a->run = group->add_subcommand("run", "The live TALC loop (seed 004 Ch. 6): ingest, evaluate, predict on the grid, NG phases, "
                                         "updates; the dashboard and the controller file after every pass");
  a->run->add_option("store", a->store, "campaign store")->required()->check(inputFile());
  a->run->add_option("--log", a->logs, "LinuxCNC LOG or Fanuc DPRNT capture (may still be growing)")->check(inputFile());
  a->run->add_option("--inputs", a->inputs, "inputs CSV a data logger appends to")->check(inputFile());
  a->run->add_flag("--finished", a->finished, "the log and the inputs are complete");
  a->run->add_flag("--follow", a->follow, "keep following the files (stop with SIGINT/SIGTERM or --idle-exit-s)");
  a->run->add_option("--poll-s", a->poll_s, "seconds between passes when following")->capture_default_str()->check(CLI::PositiveNumber);
  a->run->add_option("--idle-exit-s", a->idle_exit_s, "when following, stop after this long without new data (0: never)")->capture_default_str()->check(CLI::NonNegativeNumber);
  addTalcOptions(a->run, a->live.talc, a->talc_inputs);
  a->run->add_option("--grid-s", a->live.grid_s, "prediction grid = CP measurement interval, s (default: the plan's cycle period)")->check(CLI::PositiveNumber);
  a->run->add_flag("--offsets-applied", a->live.offsets_applied, "the controller applies the issued offsets: a cycle measures the residual");
  a->run->add_flag("--requested-only", a->live.requested_only, "feed TALC only the cycles it asked for (a densely measured log replayed)");
  a->run->add_option("--html", a->dashboard, "the live HTML dashboard, rewritten after every pass");
  a->run->add_option("--controller-file", a->controller_file, "JSON for the controller side: wait_s before the next cycle, the compensation in effect");
  a->add_input = group->add_subcommand("add-input", "Add an input column to the live loop's models while it runs (the "
                                                     "dashboard's diagnosis names the one they miss)");
  a->add_input->add_option("store", a->store, "campaign store")->required()->check(inputFile());
  a->add_input->add_option("input", a->input_name, "a column of the inputs stream (a temperature enters as its change since the start)")->required();
  return {group, [a] { return runCampaign(*a); }};
}

}  // namespace probeloop::cli
