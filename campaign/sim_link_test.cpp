// The live loop closed on the virtual machine: the offsets a link issues move the axes as a
// controller's external offsets do, so the evaluated errors of a cycle run with them are the
// uncompensated ones minus the prediction (seed 004 Eqs. 6.3-6.5 as derived in
// geometry/compensation_offsets.hpp: the sign convention "the offset cancels the error").
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "evaluate/ingest.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "geometry/compensation_offsets.hpp"
#include "parts/machine.hpp"
#include "parts/machine_offsets.hpp"
#include "parts/sphere_artifact.hpp"
#include "planner/sphere_cycle.hpp"
#include "sim/live_link.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::campaign {
namespace {

namespace fs = std::filesystem;

// Applies a fixed prediction from the second cycle on (after the first cycle's last point).
struct ConstantPrediction : sim::LiveLink {
  geometry::LocationErrors prediction;
  geometry::OffsetFrame frame;
  int points_per_cycle = 0, points = 0;
  void logLine(double, const std::string&, const std::string& line) override {
    if (line.rfind("PT", 0) == 0) ++points;
  }
  void inputSample(double, const std::string&, const std::string&) override {}
  Eigen::Vector3d offsetsUm(double, const Eigen::Vector3d& tip_mm, double) override {
    if (points < points_per_cycle) return Eigen::Vector3d::Zero();
    const auto o = geometry::compensationOffsets(prediction, tip_mm, frame);
    return {o.x_um, o.y_um, o.z_um};
  }
  std::optional<double> externalVariable(double, int) override { return std::nullopt; }
  double analogInput(double, int) override { return 0; }
};

TEST(LiveLinkOnTheVirtualMachine, OffsetsShiftTheEvaluatedErrorsByMinusThePrediction) {
  const std::string src = PROBELOOP_SOURCE_DIR;
  auto artifact = parts::loadSphereArtifact(src + "/parts/sphere_artifact.yaml");
  artifact.cycle_count = 3;
  artifact.duration_s = 0;
  const auto machine = parts::loadMachine(src + "/parts/machines/nmv5000.yaml");
  const auto plan = planner::planSphereCycle(artifact, machine);
  const fs::path dir = fs::temp_directory_path() / ("probeloop_sim_link_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // A machine without errors and a probe without noise or quantisation: what remains is the
  // offsets' action (and its second order).
  std::ofstream(dir / "truth.yaml") << "kind: machine_truth\nprobe: {noise: 0 um, quantise: false}\n";
  const auto truth = sim::loadMachineTruth((dir / "truth.yaml").string());

  ConstantPrediction link;
  link.prediction.EX0C_um = 6, link.prediction.EY0C_um = -9, link.prediction.EZ0T_um = 4, link.prediction.ER0T_um = 2.5;
  link.prediction.EA0C_urad = 25, link.prediction.EB0C_urad = -18, link.prediction.EC0C_urad = 12;
  link.frame.axis_centre_xy_mm = plan.manifest.c_axis_centre_mm;
  link.frame.pivot_z_mm = plan.manifest.table_surface_z_mm + plan.manifest.sphere_centre_height_mm;
  link.frame.reference_radius_mm = plan.manifest.radius_from_axis_mm;
  link.points_per_cycle = static_cast<int>(plan.manifest.spheres.size()) * plan.manifest.pointsPerSphere();

  auto evaluate = [&](sim::LiveLink* live) {
    sim::SimulationPart part;
    part.artifact = &artifact;
    part.live = live;
    const auto out = sim::simulateProgram("sphere_cycle.nc", planner::programText(plan, parts::Dialect::FanucMacroB),
                                          machine, part, truth, 1);
    std::optional<double> start;
    const auto records = evaluate::probeLogRecords(out.log_text, out.log_name, 1, &start);
    return evaluate::evaluateSphereCampaign(plan.manifest, records);
  };
  const auto open = evaluate(nullptr), closed = evaluate(&link);
  fs::remove_all(dir);
  ASSERT_EQ(open.cycles.size(), 3u);
  ASSERT_EQ(closed.cycles.size(), 3u);
  const auto p = link.prediction.values();
  for (std::size_t c = 1; c < 3; ++c) {
    const auto a = open.cycles[c].least_squares.values(), b = closed.cycles[c].least_squares.values();
    for (int i = 0; i < geometry::LocationErrors::kCount; ++i)
      // The DPRNT log's 4 decimals (0.1 um) and the second order of 25 urad over 200 mm.
      EXPECT_NEAR(b[i] - a[i], -p[i], i < 4 ? 0.15 : 0.8) << geometry::LocationErrors::names()[i] << " cycle " << c + 1;
  }
}

// Records the B at which the machine asks for the offsets, and answers the trunnion's offsets
// there (parts/machine_offsets.hpp): what StoreLiveLink does with the loop's prediction.
struct RecordingLink : sim::LiveLink {
  parts::MachineOffsetFrame frame;
  geometry::LocationErrors prediction;
  std::vector<std::pair<double, Eigen::Vector3d>> asked;  // B, offsets (um)
  void logLine(double, const std::string&, const std::string&) override {}
  void inputSample(double, const std::string&, const std::string&) override {}
  Eigen::Vector3d offsetsUm(double, const Eigen::Vector3d& tip_mm, double b_deg) override {
    const auto o = frame.offsetsAt(prediction, tip_mm, b_deg);
    asked.emplace_back(b_deg, Eigen::Vector3d(o.x_um, o.y_um, o.z_um));
    return asked.back().second;
  }
  std::optional<double> externalVariable(double, int) override { return std::nullopt; }
  double analogInput(double, int) override { return 0; }
};

TEST(LiveLinkOnTheVirtualMachine, AsksForTheOffsetsAtTheBItStandsAt) {
  const std::string src = PROBELOOP_SOURCE_DIR;
  auto artifact = parts::loadSphereArtifact(src + "/parts/sphere_artifact.yaml");
  const auto machine = parts::loadMachine(src + "/parts/machines/nmv5000.yaml");
  const fs::path dir = fs::temp_directory_path() / ("probeloop_sim_link_b_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "truth.yaml") << "kind: machine_truth\n";
  const auto truth = sim::loadMachineTruth((dir / "truth.yaml").string());
  fs::remove_all(dir);
  RecordingLink link;
  link.frame = parts::machineOffsetFrame(machine, 75, 160);
  link.prediction.EX0C_um = 10, link.prediction.EZ0T_um = 4;
  sim::SimulationPart part;
  part.artifact = &artifact;
  part.live = &link;
  // Tip high above the table; B to -90 deg and back: the blocks after the B move run tilted.
  sim::simulateProgram("tilt.nc", "%\nO1000\nG90 G00 Z600.\nB-90.\nX10.\nB0.\nX20.\nM30\n%\n", machine, part, truth, 1);
  ASSERT_GE(link.asked.size(), 4u);
  bool tilted = false;
  for (const auto& [b, o] : link.asked) {
    if (b == 0) {
      EXPECT_NEAR(o.x(), 10, 1e-9);  // EX0C along X, EZ0T along Z with the table horizontal
      EXPECT_NEAR(o.z(), 4, 1e-9);
    } else {
      // B' by -90 deg turns the table right-handedly about +Y by 90 deg: the C axis's +X shift
      // points along -Z, its +Z shift along +X (seed 004 Eqs. 6.3, 6.5 with B^ = 90 deg).
      tilted = true;
      EXPECT_EQ(b, -90.0);
      EXPECT_NEAR(o.x(), 4, 1e-9);
      EXPECT_NEAR(o.z(), -10, 1e-9);
    }
  }
  EXPECT_TRUE(tilted);
}

}  // namespace
}  // namespace probeloop::campaign
