// The stepped workpiece's control errors (model/control_errors.hpp) on parts whose one-part
// e_proc follows known laws: the stages' thermal error a_S T, a process error p0 + p1 F, and a
// control error the part's joining adds (hand-set constants), so every separated value is known.
#include "model/control_errors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace probeloop::model {
namespace {

using nlohmann::json;

json budget(double v, double u) { return {{"value", v}, {"u_c", u}, {"U", 2 * u}}; }

const double kT[4] = {5, 55, 107, 186};
const double kA = 0.021;  // the 3500 rpm stage's e_pt slope (um/min), Y twice it

// A part at 3500 rpm: e_proc = kA T + p0 + p1 F + extra (Y: 2 kA T + ... + extra_y).
json part(const char* id, const std::string& transition, double transition_feed, const double F[4], double p0, double p1,
          double extra_x, double extra_y, double S = 3500) {
  json j{{"kind", "stepped_workpiece"}, {"experiment", id}, {"transition", transition}};
  if (transition != "continuous") j["transition_feed_mm_per_min"] = transition_feed;
  for (int i = 0; i < 4; ++i)
    j["separation"].push_back({{"step", i + 1}, {"feed_mm_per_min", F[i]}, {"spindle_rpm", S}, {"temp_state_min", kT[i]},
                               {"e_proc_x_um", budget(kA * kT[i] + p0 + p1 * F[i] + extra_x, 0.5)},
                               {"e_proc_y_um", budget(2 * kA * kT[i] + p0 + p1 * F[i] + extra_y, 0.5)},
                               {"e_splz_um", budget(0.07 * kT[i], 0.4)}});
  return j;
}

const double kF100[4] = {100, 100, 100, 100};
const double kFW8[4] = {100, 200, 400, 800};
const double kFW2[4] = {200, 400, 800, 1600};

// The 3500 rpm stage (W1) alone: its intercept 0.8 um (its process error at F 100).
ThermalStages oneStage() {
  return thermalStagesFromEvaluations({{part("W1", "non_cutting", 100, kF100, 0.8, 0, 0, 0), "w1.json"}});
}

const json kW8 = part("W8", "non_cutting", 100, kFW8, -1.0, 0.01, 0, 0);

TEST(ControlErrors, TheTransitionsPartKeepsWhatItsJoiningAddsAtEveryFeed) {
  const json w2 = part("W2", "fast", 1200, kFW2, -1.0, 0.01, 7.7, 3.3);
  const auto c = separateControl(oneStage(), kW8, "w8.json", &w2, "w2.json", nullptr, "");
  // The reference's line on the feed is W8's process error exactly (e_pt taken out).
  EXPECT_NEAR(c.reference_x.at(300), -1.0 + 0.01 * 300, 1e-9);
  EXPECT_DOUBLE_EQ(c.reference_feed_min, 100);
  EXPECT_DOUBLE_EQ(c.reference_feed_max, 800);
  ASSERT_EQ(c.transitions.size(), 4u);
  for (const auto& s : c.transitions) {
    EXPECT_NEAR(s.x_um, 7.7, 1e-9) << s.step;
    EXPECT_NEAR(s.y_um, 3.3, 1e-9) << s.step;
    // Eq. 3.13/3.14: the slope over the feed change 1200 - 100.
    EXPECT_NEAR(s.x_um_per_mm_per_min, 7.7 / 1100, 1e-12);
    EXPECT_EQ(s.extrapolated, s.feed_mm_per_min > 800) << s.step;
    // U: the part's (k 2), e_pt's and the reference's at their k, in quadrature: larger than the
    // part's own alone.
    EXPECT_GT(s.U_x_um, 2 * s.u_one_part_x_um);
    EXPECT_NEAR(s.u_x_um, std::sqrt(0.25 + s.pt_x.u_um * s.pt_x.u_um + s.ref_x.u_um * s.ref_x.u_um), 1e-12);
  }
  EXPECT_EQ(c.transitions[0].quantity, "e_ctrl");
  // Inside the reference's feeds u_ref is the line's out-of-sample u; at 1600 mm/min it grows with
  // the line's leverage: feeds 100/200/400/800 (mean 375, Sxx 287500) give h = 1/4 + (F - 375)^2 / Sxx,
  // 0.8783 at 800 (the largest measured) and 5.4696 at 1600: sqrt(5.4696 / 0.8783) = 2.4955.
  EXPECT_DOUBLE_EQ(c.transitions[2].ref_x.u_um, c.reference_x.u_pred_um);
  EXPECT_NEAR(c.transitions[3].ref_x.u_um / c.reference_x.u_pred_um, std::sqrt((0.25 + 1225.0 * 1225.0 / 287500) / (0.25 + 425.0 * 425.0 / 287500)), 1e-9);
}

TEST(ControlErrors, TheForcePartIsMeasuredFromTheReferenceAndRegressedOnTheFeed) {
  // W5: a continuous path whose control error grows with the cutting feed, -0.01 um per mm/min.
  json w5 = part("W5", "continuous", 0, kFW8, -1.0, 0.01 - 0.01, 0, 0);
  const auto c = separateControl(oneStage(), kW8, "w8.json", nullptr, "", &w5, "w5.json");
  ASSERT_EQ(c.force.size(), 4u);
  for (const auto& s : c.force) {
    EXPECT_NEAR(s.x_um, -0.01 * s.feed_mm_per_min, 1e-9) << s.step;
    EXPECT_FALSE(s.extrapolated);
    EXPECT_EQ(s.quantity, "e_cpr");
  }
  ASSERT_TRUE(c.has_force_fit);
  EXPECT_NEAR(c.force_x.at(600), -6.0, 1e-9);
  EXPECT_TRUE(c.transitions.empty());
  // W2 given too: e_cpr does not depend on it (Eq. 3.15's route through W2 cancels its terms).
  const json w2 = part("W2", "fast", 1200, kFW8, -1.0, 0.01, 5.0, 5.0);
  const auto both = separateControl(oneStage(), kW8, "w8.json", &w2, "w2.json", &w5, "w5.json");
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(both.force[static_cast<std::size_t>(i)].x_um, -0.01 * kFW8[i], 1e-9);
}

void expectRefusal(const json& ref, const json* w2, const json* w5, const std::string& want) {
  try {
    separateControl(oneStage(), ref, "ref.json", w2, "w2.json", w5, "w5.json");
    FAIL() << "accepted; expected " << want;
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(ControlErrors, PartsJoinedTheWrongWayOrAtAnotherSpeedAreRefused) {
  const json w2 = part("W2", "fast", 1200, kFW2, -1.0, 0.01, 0, 0);
  const json w5 = part("W5", "continuous", 0, kFW8, -1.0, 0.01, 0, 0);
  json old = kW8;
  old.erase("transition");
  expectRefusal(old, &w2, nullptr, "ref.json: transition: missing");
  expectRefusal(w5, &w2, nullptr, "ref.json: transition: continuous");
  expectRefusal(kW8, &w5, nullptr, "w2.json: transition: continuous");
  expectRefusal(kW8, nullptr, &w2, "w5.json: transition: fast");
  const json slow = part("W2", "fast", 100, kFW2, -1.0, 0.01, 0, 0);
  expectRefusal(kW8, &slow, nullptr, "w2.json: transition_feed_mm_per_min: 100 mm/min");
  const json other_speed = part("W2", "fast", 1200, kFW2, -1.0, 0.01, 0, 0, 5500);
  expectRefusal(kW8, &other_speed, nullptr, "holds at its speed, 3500 rpm");
  const double far[4] = {200, 400, 800, 1700};
  const json too_fast = part("W2", "fast", 1200, far, -1.0, 0.01, 0, 0);
  expectRefusal(kW8, &too_fast, nullptr, "w2.json: feed_mm_per_min: 1700 mm/min lies beyond twice the reference's largest feed (800 mm/min)");
  json unknown = w2;
  unknown["transition"] = "zigzag";
  expectRefusal(kW8, &unknown, nullptr, "w2.json: transition: 'zigzag'");
  json empty = kW8;
  empty["separation"] = json::array();
  expectRefusal(empty, &w2, nullptr, "ref.json: separation: no steps");
}

}  // namespace
}  // namespace probeloop::model
