// The turning campaign's truth against closed forms: one heat source's step response, its
// twist through the notes' first-order levers (notes/seeds001-003.md §2.5), and the
// loader's refusals.
#include "sim/lathe_campaign.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace probeloop::sim {
namespace {

std::vector<std::vector<double>> dataRows(const std::string& csv) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(csv);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("time_s", 0) == 0) continue;
    std::vector<double> r;
    std::istringstream f(line);
    std::string cell;
    while (std::getline(f, cell, ',')) r.push_back(std::stod(cell));
    rows.push_back(r);
  }
  return rows;
}

LatheTruth spindleOnly() {
  LatheTruth t;
  t.duration_s = 3 * 3600.0;
  t.cold_start_s = 4 * 3600.0;  // the whole campaign at the top level: a step response
  t.diameter_noise_um = t.face_noise_um = 1e-9;
  LatheHeatSource s;
  s.input = "spindle_rpm";
  s.body = 4;
  s.levels = {0, 2000};
  s.K_per_unit = 0.005;
  s.tau_s = 3600;
  s.per_K.translation_mm = Eigen::Vector3d(1e-3, 0, 2e-3);  // 1 um/K radial X, 2 um/K axial
  s.per_K.rotation_rad = Eigen::Vector3d(0, 0.5e-6, 0);     // 0.5 urad/K about Y
  t.sources = {s};
  return t;
}

TEST(LatheCampaign, SpindleHeatFollowsTheStepResponseThroughTheNotesLevers) {
  const LatheTruth t = spindleOnly();
  const auto c = simulateLatheCampaign(t, 1);
  const auto e = dataRows(c.errors_csv);
  ASSERT_EQ(e.size(), 19u);  // 3 h of 10 min cycles and the first part
  const double Wx = t.workpiece_point_mm.x(), Wz = t.workpiece_point_mm.z();
  for (const auto& r : e) {
    // loaded from the second sample on (sample 0: cold and idle)
    const double time = r[0], theta = 10.0 * (time > 0 ? 1 - std::exp(-(time - 60) / 3600) : 0);
    // notes §2.5 with body 4 only: Px = -dx4 - ey4 Wz, Pz = -dz4 + ey4 Wx (um)
    const double Px = -1.0 * theta - 0.5e-3 * theta * Wz, Pz = -2.0 * theta + 0.5e-3 * theta * Wx;
    EXPECT_NEAR(r[2], 2 * Px, 1e-3) << time;  // diameter: 2 Px, to second order
    EXPECT_NEAR(r[3], Pz, 1e-3) << time;
  }
  // warm at 2000 rpm: 10 K; |P| = sqrt(Px^2 + Pz^2) with the levers above; after 4 h of
  // it (the cold start), e^-4 of it is still to come
  const double Px = -10 - 0.005 * Wz, Pz = -20 + 0.005 * Wx;
  EXPECT_NEAR(c.cold_start_resultant_um, std::hypot(Px, Pz), 1e-3);
  EXPECT_NEAR(c.after_warm_up_resultant_um, std::hypot(Px, Pz) * std::exp(-4.0), 1e-3);
}

TEST(LatheCampaign, EachSourceDrawsItsLevelsFromItsOwnStream) {
  LatheTruth t = spindleOnly();
  t.cold_start_s = 3600;
  t.duration_s = 12 * 3600.0;
  t.sources[0].levels = {0, 1000, 2000, 3000};
  const auto one = dataRows(simulateLatheCampaign(t, 5).inputs_csv);
  LatheHeatSource z = t.sources[0];
  z.input = "feed_z_mm_per_min";
  z.body = 1;
  t.sources.push_back(z);
  const auto two = dataRows(simulateLatheCampaign(t, 5).inputs_csv);
  ASSERT_EQ(one.size(), two.size());
  int changes = 0;
  for (std::size_t k = 0; k < one.size(); ++k) {
    EXPECT_EQ(one[k][1], two[k][1]) << k;  // adding a source leaves the spindle's loads alone
    if (k > 0 && one[k][1] != one[k - 1][1]) ++changes;
  }
  EXPECT_GE(changes, 3);  // 11 holds of 90 min: the levels do change
}

std::string writeTruth(const std::string& name, const std::string& text) {
  const std::string path = std::string(::testing::TempDir()) + name;
  std::ofstream(path) << text;
  return path;
}

const char* kSource =
    "sources:\n  - {input: spindle_rpm, body: spindle, levels: [0, 1000], hold: 90 min, K_per_unit: 0.005, tau: 60 min,"
    " per_K: {dz: 2 um}}\n";

TEST(LatheCampaign, LoaderRefusesWhatCannotBeSimulated) {
  auto refuses = [](const std::string& text, const std::string& what) {
    const std::string path = writeTruth("lathe_truth_test.yaml", "kind: lathe_truth\n" + text);
    try {
      loadLatheTruth(path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  EXPECT_NO_THROW(loadLatheTruth(writeTruth("lathe_ok.yaml", std::string("kind: lathe_truth\n") + kSource)));
  refuses(std::string("geometry: {tool_tip: [-150, 3, -100]}\n") + kSource, "eq. 24");
  refuses(std::string("campaign: {duration: 24 h, cycle: 90 s, inputs_rate: 60 s}\n") + kSource, "inputs_rate");
  refuses(std::string("geometry: {turret: [1, 2]}\n") + kSource, "3 numbers");
  refuses("sources:\n  - {input: spindle_rpm, body: spindle, levels: [0, 1000], hold: 90 min, K_per_unit: 0.005, "
          "tau: 60 min, per_K: {dz: 2 um}, screw_um_per_m_K: 11.5}\n",
          "linear axis");
  refuses(std::string("measurment: {diameter_noise: 1 um}\n") + kSource, "measurment");
  refuses(std::string("measurement: {face_noise: 0 um}\n") + kSource, "face_noise");
  refuses(std::string("campaign: {cycle: 0 min}\n") + kSource, "cycle");
  refuses("sources:\n  - {input: spindle_rpm, body: chuck, levels: [0], hold: 1 h, K_per_unit: 1, tau: 1 h, per_K: {}}\n",
          "body");
}

}  // namespace
}  // namespace probeloop::sim
