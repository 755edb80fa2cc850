// Truth recovery: the planner's program runs on the virtual machine with one effect at a
// time, the evaluator reads what the controller reported, and the result is compared with
// the effect's analytic signature (derived here, not taken from the simulator).
#include "sim/virtual_machine.hpp"
#include "sim/test_support.hpp"

#include <gtest/gtest.h>

#include <sstream>

#include <atomic>
#include <functional>
#include <map>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "core/error.hpp"
#include "evaluate/ingest.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "planner/sphere_cycle.hpp"

namespace probeloop::sim {
namespace {
using test::src;
using test::tempDir;
using test::truthFrom;
using test::writeTemp;

namespace fs = std::filesystem;
using Eigen::Vector3d;

struct Campaign {
  parts::PlanManifest manifest;
  SimulationOutputs out;
  evaluate::CampaignEvaluation eval;
  nlohmann::json truth;
};

Campaign run(const MachineTruth& truth, int cycles = 3, parts::Dialect dialect = parts::Dialect::FanucMacroB,
             std::uint64_t seed = 1, const std::string& machine_file = "parts/machines/nmv5000.yaml") {
  auto artifact = parts::loadSphereArtifact(src("parts/sphere_artifact.yaml"));
  artifact.cycle_count = cycles;
  const auto machine = parts::loadMachine(src(machine_file));
  const auto plan = planner::planSphereCycle(artifact, machine);
  Campaign c;
  c.manifest = plan.manifest;
  const std::string name = dialect == parts::Dialect::LinuxCnc ? "cycle.ngc" : "cycle.nc";
  c.out = simulateProgram(name, planner::programText(plan, dialect), machine, artifact, truth, seed);
  const std::string csv = writeTemp("points.csv", c.out.points_csv);
  const auto records = evaluate::readProbeRecords(csv, evaluate::PointsFormat::PointsCsv, c.manifest);
  c.eval = evaluate::evaluateSphereCampaign(c.manifest, records);
  c.truth = nlohmann::json::parse(c.out.truth_json);
  return c;
}

const evaluate::SphereMeasurement& sphere(const evaluate::CycleEvaluation& c, int position) {
  for (const auto& s : c.spheres)
    if (s.position == position) return s;
  throw std::runtime_error("no sphere");
}

TEST(VirtualMachine, WithEveryEffectOffProbedCentresAreNominal) {
  const auto c = run(truthFrom(""), 2);
  ASSERT_EQ(c.eval.cycles.size(), 2u);
  EXPECT_EQ(c.out.probe_events, 2 * 25);
  for (const auto& cyc : c.eval.cycles)
    for (const auto& s : cyc.spheres) {
      const Vector3d nominal = c.manifest.sphere(s.position)->nominal_centre_mm;
      EXPECT_LT((s.known_radius.centre_mm - nominal).norm(), 1e-9) << "position " << s.position;
      ASSERT_TRUE(s.free_radius);
      EXPECT_LT((s.free_radius->centre_mm - nominal).norm(), 1e-9);
      EXPECT_NEAR(s.free_radius->radius_mm, c.manifest.sphere_radius_mm + c.manifest.tip_radius_mm, 1e-9);
    }
}

TEST(VirtualMachine, SameSeedGivesByteIdenticalOutputs) {
  const auto truth = truthFrom(R"(
probe: {noise: 0.5 um, quantise: true}
tool_change: {repeatability: 0.7 um}
thermal:
  environment: {mean_C: 20, daily_amplitude_K: 2}
  nodes: [{name: c_axis, capacity_J_per_K: 2.0e5, to_environment_W_per_K: 10, displacement_per_K: {EY0C_um_per_K: 3}}]
  sources: [{node: c_axis, input: c_axis_speed, W_per_rpm: 0.05}]
  sensors: [{column: T_caxis_C, node: c_axis, noise_K: 0.05, offset_K: random}]
duty: {c_axis: {levels_rpm: [0, 300, 600], hold: 10 min}}
)");
  const auto a = run(truth, 2, parts::Dialect::FanucMacroB, 7), b = run(truth, 2, parts::Dialect::FanucMacroB, 7);
  EXPECT_EQ(a.out.log_text, b.out.log_text);
  EXPECT_EQ(a.out.points_csv, b.out.points_csv);
  EXPECT_EQ(a.out.inputs_csv, b.out.inputs_csv);
  EXPECT_EQ(a.out.truth_json, b.out.truth_json);
  const auto d = run(truth, 2, parts::Dialect::FanucMacroB, 8);
  EXPECT_NE(a.out.log_text, d.out.log_text);
  EXPECT_NE(a.out.inputs_csv, d.out.inputs_csv);
}

TEST(VirtualMachine, BothDialectsProbeTheSamePoints) {
  const auto truth = truthFrom("location_keyframes: [{time: 0 s}, {time: 2 h, EX0C_um: 5, EB0C_urad: 30}]\n");
  const auto f = run(truth, 2, parts::Dialect::FanucMacroB);
  const auto l = run(truth, 2, parts::Dialect::LinuxCnc);
  auto body = [](const std::string& s) { return s.substr(s.find('\n') + 1); };  // without the comment
  EXPECT_EQ(body(f.out.points_csv), body(l.out.points_csv));
  EXPECT_NE(l.out.log_text.find("PT 2.000000 5 5 "), std::string::npos);
}

// Each location error alone, as a step after cycle 1: the evaluation finds that error and
// nothing else (first-order model; second-order terms stay below 2e-3).
TEST(VirtualMachine, EachLocationErrorStepIsRecoveredAlone) {
  const auto& names = geometry::LocationErrors::names();
  const double value[7] = {3, -4, 5, 2.5, 20, -15, 25};
  for (int j = 0; j < 7; ++j) {
    const std::string yaml = std::string("location_keyframes: [{time: 0 s}, {time: 200 s}, {time: 201 s, ") +
                             names[j] + ": " + std::to_string(value[j]) + "}]\n";
    const auto c = run(truthFrom(yaml), 3);
    ASSERT_EQ(c.eval.cycles.size(), 3u);
    for (int cyc = 1; cyc < 3; ++cyc) {
      const auto got = c.eval.cycles[cyc].least_squares.values();
      for (int k = 0; k < 7; ++k)
        EXPECT_NEAR(got[k], k == j ? value[j] : 0.0, 2e-3) << names[j] << " -> " << names[k];
    }
  }
}

// A constant heat source on one node: dT(t) = Q/G (1 - exp(-t/tau)), tau = C/G. The node
// tilts the C axis, grows the artifact and lengthens the spindle; each channel must follow
// k * dT at the times the points were probed.
TEST(VirtualMachine, ThermalDriftFollowsTheFirstOrderResponse) {
  const double C = 7.2e4, G = 10, Q = 50, alpha = 11.5e-6;  // tau = 2 h, 5 K final rise
  const auto truth = truthFrom(R"(
thermal:
  environment: {mean_C: 20}
  nodes:
    - {name: n, capacity_J_per_K: 7.2e4, to_environment_W_per_K: 10,
       displacement_per_K: {EY0C_um_per_K: 3.4, EA0C_urad_per_K: -2, tool_Z_um_per_K: 1.5}}
  sources: [{node: n, input: constant, W: 50}]
artifact: {node: n, alpha_um_per_m_K: 11.5}
)");
  const auto c = run(truth, 6);
  auto dT = [&](double t) { return Q / G * (1 - std::exp(-t * G / C)); };
  // Expected per cycle: the mean over the points of positions 1-4 (those least squares uses).
  std::map<int, std::pair<int, double>> mean_dT;
  for (const auto& e : c.truth["events"]) {
    if (e["position"].get<int>() > 4) continue;
    auto& m = mean_dT[e["cycle"].get<int>()];
    ++m.first;
    m.second += dT(e["time_s"].get<double>());
  }
  const double r = c.manifest.radius_from_axis_mm, h = c.manifest.spheres[0].nominal_centre_mm.z(),
               R = c.manifest.sphere_radius_mm;
  const double ref = mean_dT[1].second / mean_dT[1].first;
  for (const auto& cyc : c.eval.cycles) {
    const double d = mean_dT[cyc.cycle].second / mean_dT[cyc.cycle].first - ref;
    const auto v = cyc.least_squares;
    EXPECT_NEAR(v.EY0C_um, 3.4 * d, 0.01) << cyc.cycle;
    EXPECT_NEAR(v.EA0C_urad, -2 * d, 0.05) << cyc.cycle;
    EXPECT_NEAR(v.ER0T_um, alpha * d * r * 1e3, 0.01) << cyc.cycle;
    // Spindle growth moves the tip +Z: the artifact appears lower. The stem lifts the
    // centre by alpha dT h; the ball's radius grows by alpha dT R, which the known-radius
    // fit reads as a lift: with the equator points insensitive to Z, minimising
    // 4 (dR)^2 + (dR - e)^2 over the centre shift e gives e = dR.
    EXPECT_NEAR(v.EZ0T_um, -1.5 * d + alpha * d * (h + R) * 1e3, 0.01) << cyc.cycle;
    EXPECT_NEAR(v.EX0C_um, 0, 0.01);
    EXPECT_NEAR(v.EC0C_urad, 0, 0.05);
  }
  EXPECT_GT(c.eval.cycles.back().least_squares.EY0C_um, 3.0);  // the drift is really there
}

TEST(VirtualMachine, ToolChangeStepsShiftAllSpheresTogether) {
  const auto c = run(truthFrom("tool_change: {repeatability: 1 um}\n"), 4);
  std::map<int, Vector3d> atc;
  for (const auto& e : c.truth["events"])
    atc[e["cycle"].get<int>()] =
        Vector3d(e["atc_um"][0].get<double>(), e["atc_um"][1].get<double>(), e["atc_um"][2].get<double>());
  double spread = 0;
  for (const auto& cyc : c.eval.cycles) {
    const Vector3d d = atc[cyc.cycle] - atc[1];
    spread = std::max(spread, d.norm());
    EXPECT_NEAR(cyc.least_squares.EX0C_um, -d.x(), 1e-6);
    EXPECT_NEAR(cyc.least_squares.EY0C_um, -d.y(), 1e-6);
    EXPECT_NEAR(cyc.least_squares.EZ0T_um, -d.z(), 1e-6);
    EXPECT_NEAR(cyc.least_squares.ER0T_um, 0, 1e-6);
    EXPECT_NEAR(cyc.least_squares.EA0C_urad, 0, 1e-5);
  }
  EXPECT_GT(spread, 0.3);  // the steps are there
}

// Pre-travel p, trigger delay d at probing feed v: every point stops p + v d past contact
// toward the centre, so the free-radius sphere shrinks by that much. A 3-lobed pre-travel
// p + A cos(3 phi) shifts the centre by A along X (approach +X: p + A, approach -X: p - A).
TEST(VirtualMachine, ProbePretravelAndTriggerDelayShrinkTheSphere) {
  const auto c = run(truthFrom("probe: {pretravel: 5 um, pretravel_vertical: 5 um, trigger_delay_ms: 3}\n"), 1);
  const double v = 200.0 / 60.0;  // mm/s, the planned probing feed
  const double shrink = 5e-3 + v * 3e-3;
  for (const auto& s : c.eval.cycles[0].spheres) {
    ASSERT_TRUE(s.free_radius);
    EXPECT_NEAR(s.free_radius->radius_mm, c.manifest.sphere_radius_mm + c.manifest.tip_radius_mm - shrink, 1e-9);
    EXPECT_LT((s.free_radius->centre_mm - c.manifest.sphere(s.position)->nominal_centre_mm).norm(), 1e-9);
  }
  const auto lobed = run(truthFrom("probe: {pretravel: 5 um, lobe_amplitude: 1.5 um, pretravel_vertical: 5 um}\n"), 1);
  for (const auto& s : lobed.eval.cycles[0].spheres) {
    const Vector3d d = s.free_radius->centre_mm - lobed.manifest.sphere(s.position)->nominal_centre_mm;
    EXPECT_NEAR(d.x(), 1.5e-3, 1e-6);
    EXPECT_NEAR(d.y(), 0.0, 1e-6);
  }
}

// Positioning error EXX = k x: the tip is at x (1 + k) when x is commanded, so a sphere at
// x_s is reported at x_s / (1 + k). Squareness EC0Y: the Y axis leans to -X by EC0Y * y, so
// a sphere at y_s is reported at x + EC0Y * y_s.
TEST(VirtualMachine, LinearAxisScaleAndSquarenessDistortTheCentres) {
  const auto c = run(truthFrom("axes: {X: {EXX_um: [0, 0.01]}}\nsquareness: {EC0Y_urad: 50}\n"), 1);
  const double k = 0.01e-3;
  for (const auto& s : c.eval.cycles[0].spheres) {
    const Vector3d n = c.manifest.sphere(s.position)->nominal_centre_mm;
    const Vector3d got = sphere(c.eval.cycles[0], s.position).known_radius.centre_mm;
    EXPECT_NEAR(got.x(), n.x() / (1 + k) + 50e-6 * n.y(), 2e-6) << s.position;
    EXPECT_NEAR(got.y(), n.y(), 2e-6) << s.position;
  }
}

void expectSafetyError(const std::function<void()>& f, const std::string& want) {
  try {
    f();
    FAIL() << "no error; expected '" << want << "'";
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(VirtualMachine, AMisplacedArtifactStopsTheProgramAsTheControllerWould) {
  // 10 mm off in X: a protected descent lands on the sphere -> the program's own check.
  const auto off = truthFrom("artifact: {placement_error: {x: 10000 um}}\n");
  expectSafetyError([&] { run(off, 1, parts::Dialect::FanucMacroB); }, "#3000=2 (UNEXPECTED CONTACT)");
  expectSafetyError([&] { run(off, 1, parts::Dialect::LinuxCnc, 1, "parts/machines/linuxcnc_rotary_mill.yaml"); },
                    "program aborted: probeloop: unexpected contact");
  // 6 mm low: the top point's probing move ends without contact.
  const auto low = truthFrom("artifact: {placement_error: {z: -6000 um}}\n");
  expectSafetyError([&] { run(low, 1, parts::Dialect::LinuxCnc, 1, "parts/machines/linuxcnc_rotary_mill.yaml"); },
                    "G38.2 probe move finished without contact");
}

SimulationOutputs runText(const std::string& program, const std::string& name = "t.ngc") {
  auto artifact = parts::loadSphereArtifact(src("parts/sphere_artifact.yaml"));
  const auto machine = parts::loadMachine(src("parts/machines/nmv5000.yaml"));
  return simulateProgram(name, program, machine, artifact, truthFrom(""), 1);
}

TEST(VirtualMachine, UnsafeMovesAreRefusedWithTheProgramLine) {
  // Sphere 1 at C = 0 sits at (-160, 0, 75), radius 15, stem radius 5 down to the table.
  const std::string head = "G21 G90\nT99 M6\nG43 H99\n";
  expectSafetyError([&] { runText(head + "G0 X400\n"); }, "t.ngc:4: move outside travel: X 400");
  expectSafetyError([&] { runText(head + "G0 X-140 Y0 Z120\nG0 Z30\nG38.2 X-170 F200\n"); },
                    "t.ngc:6: probe move would hit the artifact's stem");
  expectSafetyError([&] { runText(head + "G0 X-140 Y0 Z75\nG0 X-180\n"); },
                    "t.ngc:5: rapid (G0) would pass through the sphere artifact");
  expectSafetyError([&] { runText(head + "G0 X0 Y0 Z120\nG1 Z1 F500\n"); }, "t.ngc:5: feed move (G1/G2/G3) would hit the table");
  expectSafetyError([&] { runText(head + "G0 X-160 Y20 Z80\nG0 C90\n"); }, "t.ngc:5: rapid (G0) turns the table");
  expectSafetyError([&] { runText(head + "S1000 M3\n"); }, "t.ngc:4: spindle start (M3/M4) with the touch probe");
}

// The A axis (issue 33): refused on the NMV 5000 (B/C), checked against the travel of the
// table-table A/C machine, and indexed there at its positioning speed.
TEST(VirtualMachine, TheAAxisIsCheckedAndTimed) {
  const std::string head = "G21 G90\nT99 M6\nG43 H99\n";
  expectSafetyError([&] { runText(head + "G0 A10\n"); }, "t.ngc:4: move of A on a machine without an A axis");
  auto artifact = parts::loadSphereArtifact(src("parts/sphere_artifact.yaml"));
  const auto ac = parts::loadMachine(src("parts/machines/table_table_ac.yaml"));  // A +-120 deg at 20 rpm
  expectSafetyError([&] { simulateProgram("t.ngc", head + "G0 A130\n", ac, artifact, truthFrom(""), 1); },
                    "t.ngc:4: move outside travel: A 130 deg");
  expectSafetyError([&] { simulateProgram("t.ngc", head + "G1 A30 F36000\n", ac, artifact, truthFrom(""), 1); },
                    "exceeds the A axis's maximum turning speed 20 rpm");
  SimulationPart part;
  part.artifact = &artifact;
  part.trace = true;
  const auto out = simulateProgram("t.ngc", head + "G0 A-90\nM2\n", ac, part, truthFrom(""), 1);
  // The trace carries A before B; 90 deg at 20 rpm = 7200 deg/min take 0.75 s.
  EXPECT_EQ(out.trace_csv.rfind("time_s,duration_s,line,kind,x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,", 0), 0u) << out.trace_csv;
  const auto row = out.trace_csv.find(",4,rapid,");
  ASSERT_NE(row, std::string::npos) << out.trace_csv;
  const auto start = out.trace_csv.rfind('\n', row) + 1;
  const std::string line = out.trace_csv.substr(start, out.trace_csv.find('\n', row) - start);
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
  ASSERT_GE(f.size(), 10u) << line;
  EXPECT_NEAR(std::stod(f[1]), 0.75, 1e-9) << line;
  EXPECT_EQ(std::stod(f[7]), -90) << line;
  EXPECT_EQ(std::stod(f[8]), 0) << line;
}

}  // namespace
}  // namespace probeloop::sim
