// Tool-change settling and production tool changes between measurements (duty): the
// planner's program runs with the probe's own M6 once, tool changes fall at random times in
// the dwells, and the evaluated EZ0T must follow the settling law derived here from the
// change times truth.json lists (not from the simulator's state).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unistd.h>

#include "core/error.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "planner/sphere_cycle.hpp"
#include "sim/virtual_machine.hpp"
#include "sim/test_support.hpp"

namespace probeloop::sim {
namespace {
using test::src;
using test::tempDir;
using test::truthFrom;
using test::writeTemp;

namespace fs = std::filesystem;

struct Run {
  parts::PlanManifest manifest;
  SimulationOutputs out;
  evaluate::CampaignEvaluation eval;
  nlohmann::json truth;
};

// The probe stays in the spindle (tool_change_each_cycle: false): the program changes tools
// twice (probe in, empty spindle out), the duty the rest.
Run runCampaign(const MachineTruth& truth, int cycles, std::uint64_t seed = 3) {
  auto artifact = parts::loadSphereArtifact(src("parts/sphere_artifact.yaml"));
  artifact.cycle_count = cycles;
  artifact.tool_change_each_cycle = false;
  const auto machine = parts::loadMachine(src("parts/machines/nmv5000.yaml"));
  const auto plan = planner::planSphereCycle(artifact, machine);
  Run r;
  r.manifest = plan.manifest;
  r.out = simulateProgram("cycle.nc", planner::programText(plan, parts::Dialect::FanucMacroB), machine, artifact,
                          truth, seed);
  const auto records = evaluate::readProbeRecords(writeTemp("points.csv", r.out.points_csv),
                                                  evaluate::PointsFormat::PointsCsv, r.manifest);
  r.eval = evaluate::evaluateSphereCampaign(r.manifest, records);
  r.truth = nlohmann::json::parse(r.out.truth_json);
  return r;
}

constexpr int kEmptyTool = 0;  // nmv5000's empty spindle (checked below)

// The settling law written out: every change that seats a holder at t_i <= t contributes
// A exp(-(t - t_i) / tau) (superposition of first-order decays).
double settlingAt(const nlohmann::json& changes, double t, double A_um, double tau_s) {
  double s = 0;
  for (const auto& c : changes)
    if (c["tool"].get<int>() != kEmptyTool && c["time_s"].get<double>() <= t)
      s += A_um * std::exp(-(t - c["time_s"].get<double>()) / tau_s);
  return s;
}

TEST(ToolChangeSettling, EZ0TFollowsTheDecayingJumpsAtTheProbingTimes) {
  ASSERT_EQ(parts::loadMachine(src("parts/machines/nmv5000.yaml")).tool_change.empty_tool, kEmptyTool);
  const double A = 5.0, tau = 600.0;  // um, s
  const auto r = runCampaign(truthFrom(R"(
tool_change: {settling: {tool_Z: 5 um, time_constant: 10 min}}
duty: {tool_changes: {per_hour: 6}}
)"),
                             16);
  const auto& changes = r.truth["tool_changes"];
  int duty = 0;
  for (const auto& c : changes) duty += c["source"] == "duty";
  ASSERT_GE(duty, 3) << "too few duty changes to test anything";

  // The top point sees Z (equator points are square to it): each sphere centre's Z moves
  // by -settling at its top point's time (tip up: the artifact reads lower); seed 004
  // Eq. 5.6's EZ0T is the mean over positions 1-4.
  int top = -1;
  for (const auto& p : r.manifest.points)
    if (p.approach.z() < -0.5) top = p.point;
  ASSERT_GT(top, 0);
  std::map<std::pair<int, int>, double> at_top;  // (cycle, position) -> settling at the top point
  for (const auto& e : r.truth["events"]) {
    const double want = settlingAt(changes, e["time_s"].get<double>(), A, tau);
    EXPECT_NEAR(e["settling_um"].get<double>(), want, 1e-9);
    if (e["point"].get<int>() == top) at_top[{e["cycle"].get<int>(), e["position"].get<int>()}] = want;
  }
  std::map<int, double> z1;  // position -> known-radius centre Z in cycle 1, um
  for (const auto& s : r.eval.cycles.front().spheres) z1[s.position] = s.known_radius.centre_mm.z() * 1e3;
  double largest = 0;
  for (const auto& cyc : r.eval.cycles) {
    double mean = 0;
    for (const auto& s : cyc.spheres) {
      const double d = at_top.at({cyc.cycle, s.position}) - at_top.at({1, s.position});
      EXPECT_NEAR(s.known_radius.centre_mm.z() * 1e3 - z1[s.position], -d, 1e-6) << cyc.cycle << "/" << s.position;
      if (s.position <= 4) mean += d / 4;
      largest = std::max(largest, std::fabs(d));
    }
    ASSERT_TRUE(cyc.formulas);
    EXPECT_NEAR(cyc.formulas->EZ0T_um, -mean, 1e-6) << "cycle " << cyc.cycle;
    EXPECT_NEAR(cyc.formulas->EX0C_um, 0, 1e-4);
    EXPECT_NEAR(cyc.formulas->ER0T_um, 0, 1e-4);
  }
  EXPECT_GT(largest, 1.0);  // the transient is really there
}

TEST(ToolChangeSettling, DutyChangesFallInTheDwellsAndAreCountedInTheInputs) {
  const auto r = runCampaign(truthFrom("duty: {tool_changes: {per_hour: 8}}\ntool_change: {repeatability: 0.5 um}\n"), 12);
  // inputs.csv rows: the count of changes in (t_{k-1}, t_k].
  std::istringstream in(r.out.inputs_csv);
  std::string line;
  std::vector<std::pair<double, int>> rows;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("time_s", 0) == 0) continue;
    rows.emplace_back(std::stod(line.substr(0, line.find(','))), std::stoi(line.substr(line.rfind(',') + 1)));
  }
  const auto& changes = r.truth["tool_changes"];
  int duty = 0;
  for (const auto& c : changes) duty += c["source"] == "duty";
  int counted = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    int want = 0;
    for (const auto& c : changes) {
      const double t = c["time_s"].get<double>();
      // Rows print the time to 1 ms.
      if (t <= rows[k].first + 5e-4 && (k == 0 || t > rows[k - 1].first + 5e-4)) ++want;
    }
    EXPECT_EQ(rows[k].second, want) << "row at " << rows[k].first << " s";
    counted += rows[k].second;
  }
  EXPECT_EQ(counted, static_cast<int>(changes.size()));
  EXPECT_EQ(static_cast<int>(changes.size()), duty + 2);  // + the program's probe in and out
  // Each duty change falls in a gap: after the last probe event of one cycle and before
  // the first of the next; and re-seats the probe (a new ATC step for the next cycle).
  std::map<int, std::pair<double, double>> span;  // cycle -> first, last event time
  for (const auto& e : r.truth["events"]) {
    const int c = e["cycle"].get<int>();
    const double t = e["time_s"].get<double>();
    if (!span.count(c)) span[c] = {t, t};
    span[c].second = std::max(span[c].second, t);
  }
  for (const auto& c : changes) {
    if (c["source"] != "duty") continue;
    const double t = c["time_s"].get<double>();
    bool in_gap = false;
    for (auto it = span.begin(); std::next(it) != span.end(); ++it)
      in_gap |= t > it->second.second && t < std::next(it)->second.first;
    EXPECT_TRUE(in_gap) << "duty change at " << t << " s is not between two cycles";
  }
  // Poisson on the dwell clock: 11 gaps of 5 min at 8/h -> mean 7.3; seed 3 must show some.
  EXPECT_GE(duty, 2);
  std::map<int, std::vector<double>> atc;  // cycle -> the probe's ATC step in that cycle
  for (const auto& e : r.truth["events"]) atc[e["cycle"].get<int>()] = e["atc_um"].get<std::vector<double>>();
  int moved = 0;
  for (int cyc = 2; cyc <= 12; ++cyc) moved += atc[cyc] != atc[cyc - 1];
  EXPECT_GT(moved, 0);
  EXPECT_LE(moved, duty);
}

// Each effect draws from its own stream (docs/simulator.md): production tool changes (which
// take no program time) leave the sensor noise and the probe noise exactly as they were.
TEST(ToolChangeSettling, SwitchingDutyChangesOnLeavesTheOtherDrawsAlone) {
  const std::string base = R"(
probe: {noise: 0.25 um}
tool_change: {repeatability: 0.3 um}
thermal:
  environment: {mean_C: 20}
  nodes: [{name: n, capacity_J_per_K: 1.0e5, to_environment_W_per_K: 10}]
  sensors: [{column: T_n_C, node: n, noise_K: 0.03, offset_K: random}]
)";
  const auto off = runCampaign(truthFrom(base), 8), on = runCampaign(truthFrom(base + "duty: {tool_changes: {per_hour: 8}}\n"), 8);
  // The sensor column of every row (the last row's time is the program's end, which the
  // re-seated probe's ATC steps move by milliseconds).
  auto sensors = [](const std::string& csv) {
    std::istringstream in(csv);
    std::string line, out;
    while (std::getline(in, line)) {
      const std::size_t a = line.find(',');
      out += line.substr(a + 1, line.find(',', a + 1) - a - 1) + "\n";
    }
    return out;
  };
  EXPECT_EQ(sensors(off.out.inputs_csv), sensors(on.out.inputs_csv));
  EXPECT_NE(off.out.inputs_csv, on.out.inputs_csv);  // the tool_changes column differs
  ASSERT_EQ(off.truth["events"].size(), on.truth["events"].size());
  for (std::size_t i = 0; i < off.truth["events"].size(); ++i)
    EXPECT_EQ(off.truth["events"][i]["noise_um"], on.truth["events"][i]["noise_um"]) << i;
}

TEST(ToolChangeSettling, TheTruthKeysAreStrict) {
  auto message = [](const std::string& yaml) {
    try {
      truthFrom(yaml);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unknown = message("tool_change:\n  settling: {tool_Z: 4 um, time_constant: 10 min, tau: 1}\n");
  EXPECT_NE(unknown.find(":3:"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("tau"), std::string::npos) << unknown;
  EXPECT_NE(message("tool_change: {settling: {tool_Z: 4 um}}\n").find("time_constant"), std::string::npos);
  EXPECT_NE(message("tool_change: {settling: {tool_Z: 4 um, time_constant: 0 s}}\n").find("must be positive"),
            std::string::npos);
  EXPECT_NE(message("duty: {tool_changes: {per_hour: 0}}\n").find("must be positive"), std::string::npos);
  EXPECT_NE(message("duty: {tool_changes: {per_hour: 2, rate: 2}}\n").find("rate"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::sim
