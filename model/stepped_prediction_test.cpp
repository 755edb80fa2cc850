// The stepped workpiece's forward prediction (model/stepped_prediction.hpp) on a separation
// whose components follow known laws: e_proc = c F, e_splz = A (1 - exp(-T / tau)), e_pos = k L;
// the prediction at other conditions is that law's value (hand-derived below).
#include "model/stepped_prediction.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace probeloop::model {
namespace {

using nlohmann::json;

json budget(double v, double u) { return {{"value", v}, {"u_c", u}, {"U", 2 * u}}; }

// W8-like: feeds 100/200/400/800 at 3500 rpm, T 5/45/82/118 min, sizes 30/45/80/99, tool d 10.
json evaluation(double c_x, double c_y, double A, double tau, double kx, double ky, double kz) {
  const double F[4] = {100, 200, 400, 800}, T[4] = {5, 45, 82, 118}, size[4] = {30, 45, 80, 99};
  json j{{"kind", "stepped_workpiece"}, {"experiment", "W8"}};
  j["k_pos_x_um_per_mm"] = budget(kx, 0.01);
  j["k_pos_y_um_per_mm"] = budget(ky, 0.01);
  j["k_pos_z_um_per_mm"] = budget(kz, 0.02);
  for (int i = 0; i < 4; ++i) {
    j["separation"].push_back({{"step", i + 1}, {"feed_mm_per_min", F[i]}, {"spindle_rpm", 3500}, {"temp_state_min", T[i]},
                               {"travel_probe_mm", size[i] + 2}, {"travel_tool_mm", size[i] + 10},
                               {"e_proc_x_um", budget(c_x * F[i], 0.5)}, {"e_proc_y_um", budget(c_y * F[i], 0.5)},
                               {"e_splz_um", budget(A * (1 - std::exp(-T[i] / tau)), 0.4)}});
    j["cmm"]["steps"].push_back({{"step", i + 1}, {"size_mm", size[i]}});
  }
  return j;
}

TEST(SteppedPrediction, KnownLawsArePredictedAtOtherConditions) {
  const double cx = 0.008, cy = 0.0085, A = 14, tau = 60, kx = 0.15, ky = 0.25, kz = 0.02;
  const auto p = steppedPredictorFromEvaluation(evaluation(cx, cy, A, tau, kx, ky, kz), "w8.json");
  EXPECT_DOUBLE_EQ(p.tool_d_mm, 10);
  EXPECT_DOUBLE_EQ(p.speed_ref_rpm, 3500);
  // Linear in the feed through 0: the straight line is found exactly (leave-one-out 0).
  const Candidate line{Family::Polynomial, 1, true};
  EXPECT_EQ(p.proc_x.selection.candidates[static_cast<std::size_t>(p.proc_x.selection.best)].candidate.label(), line.label());
  // A saturating exponential in T through (0, 0): a - b exp(-c T) with a = b = A, c = 1 / tau.
  EXPECT_EQ(p.splz.fit.function.family, Family::SaturatingExponential);
  // A new part: size 60, depth 25, feed 300, 1750 rpm (half the stage: scaled by 0.5), T 150.
  const auto r = predictSteppedErrors(p, {{1, 60, 25, 300, 1750, 150}});
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].width_x_um, kx * (60 + 10) + cx * 300, 1e-6);
  EXPECT_NEAR(r[0].width_y_um, ky * (60 + 10) + cy * 300, 1e-6);
  EXPECT_NEAR(r[0].depth_um, kz * 25 - 0.5 * A * (1 - std::exp(-150 / tau)), 1e-4);
  // U: u(k) x (size + stylus d) with k = 2, and the points' own u (0.5, type B: exact laws leave
  // nothing out of sample, so the Welch-Satterthwaite dof are the type B's, many): k = 1.96.
  EXPECT_NEAR(r[0].U_width_x_um, std::hypot(2 * 0.01 * 62, 1.959964 * 0.5), 1e-5);
}

TEST(SteppedPrediction, RefusesWhatOnePartCannotSay) {
  const auto j = evaluation(0.008, 0.008, 14, 60, 0.15, 0.25, 0.02);
  const auto p = steppedPredictorFromEvaluation(j, "w8.json");
  EXPECT_THROW(predictSteppedErrors(p, {{1, 30, 9, 1700, 3500, 50}}), GeometryError);  // feed beyond 2 x 800
  auto mixed = j;
  mixed["separation"][2]["spindle_rpm"] = 5500;
  try {
    steppedPredictorFromEvaluation(mixed, "w3.json");
    FAIL() << "accepted a part cut at two speeds";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("w3.json: separation[2].spindle_rpm: 5500"), std::string::npos) << e.what();
  }
  auto two = j;
  two["separation"].erase(two["separation"].begin(), two["separation"].begin() + 2);
  EXPECT_THROW(steppedPredictorFromEvaluation(two, "w.json"), InputError);
  EXPECT_THROW(steppedPredictorFromEvaluation(json{{"kind", "thermal_test_piece"}}, "t.json"), InputError);
}

}  // namespace
}  // namespace probeloop::model
