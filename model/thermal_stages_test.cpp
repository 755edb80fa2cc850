// The stepped workpiece's thermal stages (model/thermal_stages.hpp) on parts whose one-part
// e_proc follows known laws: c_S + a_S T at each speed S (c the process error at thermal zero);
// the stage curves, the interpolation in S (hand-derived weights, against the thesis's printed
// swapped ones, notes/seed000.md §4.5) and the process part's separation.
#include "model/thermal_stages.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace probeloop::model {
namespace {

using nlohmann::json;

json budget(double v, double u) { return {{"value", v}, {"u_c", u}, {"U", 2 * u}}; }

const double kT[4] = {5, 55, 107, 186};

// A part: feeds F[i], speed S on every step; e_proc = c + a T (+ proc_per_feed F), e_splz = g T.
json part(const char* id, double S, const double F[4], double c, double a, double g, double proc_per_feed = 0) {
  json j{{"kind", "stepped_workpiece"}, {"experiment", id}};
  for (int i = 0; i < 4; ++i)
    j["separation"].push_back({{"step", i + 1}, {"feed_mm_per_min", F[i]}, {"spindle_rpm", S}, {"temp_state_min", kT[i]},
                               {"e_proc_x_um", budget(c + a * kT[i] + proc_per_feed * F[i], 0.5)},
                               {"e_proc_y_um", budget(c + 2 * a * kT[i] + proc_per_feed * F[i], 0.5)},
                               {"e_splz_um", budget(g * kT[i], 0.4)}});
  return j;
}

const double kF100[4] = {100, 100, 100, 100};

// What a prediction reads besides the separation: k per axis (u 0.01), the travels and sizes
// (steps 30, 45, 60, 75 mm; tool d 10, stylus d 2).
json predictable(json j, double kx, double ky, double kz) {
  j["k_pos_x_um_per_mm"] = budget(kx, 0.01);
  j["k_pos_y_um_per_mm"] = budget(ky, 0.01);
  j["k_pos_z_um_per_mm"] = budget(kz, 0.01);
  for (int i = 0; i < 4; ++i) {
    j["separation"][i]["travel_probe_mm"] = 32 + 15 * i;
    j["separation"][i]["travel_tool_mm"] = 40 + 15 * i;
    j["cmm"]["steps"].push_back({{"step", i + 1}, {"size_mm", 30 + 15 * i}});
  }
  return j;
}

ThermalStages threeStages() {
  return thermalStagesFromEvaluations({{part("W6", 1000, kF100, 3.0, 0.006, 0.02), "w6.json"},
                                       {part("W1", 3500, kF100, 0.8, 0.021, 0.07), "w1.json"},
                                       {part("W7", 5500, kF100, 0.5, 0.033, 0.11), "w7.json"}});
}

TEST(ThermalStages, EachStageIsItsCurveWithoutTheIntercept) {
  const auto st = threeStages();
  ASSERT_EQ(st.stages.size(), 3u);
  EXPECT_DOUBLE_EQ(st.stages[0].spindle_rpm, 1000);
  EXPECT_DOUBLE_EQ(st.stages[2].spindle_rpm, 5500);
  // The intercept is the stage's process error at thermal zero (L844).
  EXPECT_NEAR(st.stages[1].intercept_x_um(), 0.8, 1e-9);
  EXPECT_NEAR(st.stages[0].intercept_y_um(), 3.0, 1e-9);
  // At a stage's own speed: e_pt(T) = a T (the intercept removed), e_splz = g T.
  EXPECT_NEAR(st.at(ThermalComponent::PtX, 150, 3500).value_um, 0.021 * 150, 1e-9);
  EXPECT_NEAR(st.at(ThermalComponent::PtY, 150, 5500).value_um, 2 * 0.033 * 150, 1e-9);
  EXPECT_NEAR(st.at(ThermalComponent::Splz, 100, 1000).value_um, 0.02 * 100, 1e-9);
  EXPECT_EQ(st.at(ThermalComponent::PtX, 150, 3500).basis, "stage 3500 rpm");
}

TEST(ThermalStages, BetweenStagesTheWeightGrowsTowardsTheNearerSpeed) {
  const auto st = threeStages();
  // S = 4000: a quarter of the way from 3500 to 5500, so 3/4 of stage 3500 and 1/4 of 5500.
  // The thesis's Eq. 3.7 as printed weighs (S - 3500)/2000 = 1/4 on e_pt1 (3500) and 3/4 on e_pt3.
  const double T = 120, ours = 0.75 * 0.021 * T + 0.25 * 0.033 * T, printed = 0.25 * 0.021 * T + 0.75 * 0.033 * T;
  const auto v = st.at(ThermalComponent::PtX, T, 4000);
  EXPECT_NEAR(v.value_um, ours, 1e-9);
  EXPECT_GT(std::fabs(v.value_um - printed), 0.5);
  // S = 1500: 4/5 of stage 1000, 1/5 of 3500 (the thesis's Eq. 5.22 weights it so).
  EXPECT_NEAR(st.at(ThermalComponent::Splz, T, 1500).value_um, 0.8 * 0.02 * T + 0.2 * 0.07 * T, 1e-9);
  // u combined with the weights: sqrt((0.75 u_a)^2 + (0.25 u_b)^2), u = 0.5 each (type B, exact laws).
  EXPECT_NEAR(v.u_um, std::hypot(0.75 * 0.5, 0.25 * 0.5), 1e-9);
  // Outside: proportional (Eq. 3.9/3.10): 500 rpm is half of stage 1000, 6600 is 1.2 x stage 5500.
  EXPECT_NEAR(st.at(ThermalComponent::PtX, T, 500).value_um, 0.5 * 0.006 * T, 1e-9);
  EXPECT_NEAR(st.at(ThermalComponent::PtX, T, 6600).value_um, 1.2 * 0.033 * T, 1e-9);
}

TEST(ThermalStages, TheProcessPartLosesItsThermalError) {
  const auto st = threeStages();
  // W8 at 3500 rpm: e_proc = 0.8 + 0.021 T + 0.008 F; with the stage's e_pt (0.021 T) taken out,
  // 0.8 + 0.008 F remains: the process error, the stage's thermal-zero intercept included.
  const double F[4] = {100, 200, 400, 800};
  const auto steps = separateProcess(st, part("W8", 3500, F, 0.8, 0.021, 0.07, 0.008), "w8.json");
  ASSERT_EQ(steps.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(steps[i].e_proc_x_um, 0.8 + 0.008 * F[i], 1e-9);
    EXPECT_NEAR(steps[i].e_proc_y_um, 0.8 + 0.008 * F[i], 1e-9);
    EXPECT_NEAR(steps[i].u_e_proc_x_um, std::hypot(0.5, 0.5), 1e-9);
  }
  // The prediction from the campaign: width = k L + e_proc(F) + e_pt(T, S).
  const json w8 = predictable(part("W8", 3500, F, 0.8, 0.021, 0.07, 0.008), 0.15, 0.25, 0.02);
  const auto p = steppedPredictorFromCampaign(st, w8, "w8.json");
  const auto r = predictSteppedErrors(p, {{1, 60, 25, 300, 4500, 150}});
  ASSERT_EQ(r.size(), 1u);
  // e_proc against the feed per revolution (1000 F / S); only the thermal term is checked here:
  // at 4500 rpm halfway between 3500 and 5500.
  EXPECT_TRUE(p.proc_per_rev);
  EXPECT_EQ(p.proc_x.variable, "chip_load_um_per_rev");
  const double pt = 0.5 * 0.021 * 150 + 0.5 * 0.033 * 150;
  EXPECT_NEAR(r[0].width_x_um - 0.15 * 70 - p.proc_x.at(1000.0 * 300 / 4500), pt, 1e-6);
  EXPECT_NEAR(r[0].depth_um, 0.02 * 25 - (0.5 * 0.07 + 0.5 * 0.11) * 150, 1e-6);
}

// The process error follows the chip load f = 1000 F / S (um per revolution), e_proc = 0.03 f: the
// stages' intercepts (F 100 at 1000, 3500, 5500 rpm: 3, 0.857, 0.545 um) and W8's steps (F 100-800
// at 3500 rpm, with e_pt 0.021 T taken out) lie on one line through 0; a step at 1000 rpm and
// F 200 (f = 200, beyond W8's 229 only in feed) is predicted 6 um, which W8's feeds alone (at
// 3500 rpm, f = F / 3.5) would put at 0.03 x 57.1 = 1.71 um.
TEST(ThermalStages, TheCampaignsProcessErrorFollowsTheChipLoad) {
  auto c = [](double F, double S) { return 0.03 * 1000 * F / S; };
  const auto st = thermalStagesFromEvaluations({{part("W6", 1000, kF100, c(100, 1000), 0.006, 0.02), "w6.json"},
                                                {part("W1", 3500, kF100, c(100, 3500), 0.021, 0.07), "w1.json"},
                                                {part("W7", 5500, kF100, c(100, 5500), 0.033, 0.11), "w7.json"}});
  const double F[4] = {100, 200, 400, 800};
  const json w8 = predictable(part("W8", 3500, F, 0, 0.021, 0.07, 0.03 / 3.5), 0, 0, 0);
  const auto p = steppedPredictorFromCampaign(st, w8, "w8.json");
  EXPECT_NEAR(p.proc_x.at(200), 6.0, 1e-6);
  // A process part that changes its speed between steps (as W3 does) is a campaign's too.
  json w3 = w8;
  w3["separation"][2]["spindle_rpm"] = 1000;
  EXPECT_NO_THROW(steppedPredictorFromCampaign(st, w3, "w3.json"));
  EXPECT_THROW(steppedPredictorFromEvaluation(w3, "w3.json"), InputError);
  const auto r = predictSteppedErrors(p, {{1, 60, 25, 200, 1000, 0}});
  EXPECT_NEAR(r[0].width_x_um, 6.0, 1e-6);  // k = 0, T = 0: e_pt 0
}

TEST(ThermalStages, RefusesWhatIsNotAStage) {
  const double F[4] = {100, 200, 400, 800};
  try {
    thermalStagesFromEvaluations({{part("W8", 3500, F, 0.8, 0.02, 0.07), "w8.json"}});
    FAIL() << "a part cut at changing feeds was taken as a thermal stage";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("w8.json: separation[1].feed_mm_per_min: 200"), std::string::npos) << e.what();
  }
  auto mixed = part("W1", 3500, kF100, 0.8, 0.02, 0.07);
  mixed["separation"][3]["spindle_rpm"] = 1000;
  EXPECT_THROW(thermalStagesFromEvaluations({{mixed, "w1.json"}}), InputError);
  // Two parts at one speed are pooled, but only at one feed.
  const double F200[4] = {200, 200, 200, 200};
  EXPECT_THROW(thermalStagesFromEvaluations({{part("W1", 3500, kF100, 0.8, 0.02, 0.07), "w1.json"},
                                             {part("W4", 3500, F200, 0.8, 0.02, 0.07), "w4.json"}}),
               InputError);
  const auto pooled = thermalStagesFromEvaluations({{part("W1", 3500, kF100, 0.8, 0.02, 0.07), "w1.json"},
                                                    {part("W4", 3500, kF100, 0.8, 0.02, 0.07), "w4.json"}});
  ASSERT_EQ(pooled.stages.size(), 1u);
  EXPECT_EQ(pooled.stages[0].one_part_x.x.size(), 8u);
  EXPECT_THROW(thermalStagesFromEvaluations({{json{{"kind", "thermal_test_piece"}}, "t.json"}}), InputError);
  // Three steps leave a line with a free intercept 1 dof: refused with the reason.
  auto three = part("W1", 3500, kF100, 0.8, 0.02, 0.07);
  three["separation"].erase(3);
  try {
    thermalStagesFromEvaluations({{three, "w1.json"}});
    FAIL() << "a 3-step stage was fitted";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(threeStages().at(ThermalComponent::PtX, 400, 3500), GeometryError);  // T beyond 2 x 186
}

TEST(ThermalStages, SeparationJsonRefitsTheSameCampaign) {
  const auto st = threeStages();
  const json j = json::parse(separationJson(st, {}, nullptr, ""));
  const auto c = campaignFromSeparationJson(j, "separation.json");
  EXPECT_TRUE(c.process_evaluation.is_null());
  for (double S : {800.0, 2000.0, 3500.0, 4700.0, 6000.0})
    EXPECT_DOUBLE_EQ(c.stages.at(ThermalComponent::PtY, 90, S).value_um, st.at(ThermalComponent::PtY, 90, S).value_um) << S;
  EXPECT_THROW(campaignFromSeparationJson(json{{"kind", "stepped_workpiece"}}, "e.json"), InputError);
}

}  // namespace
}  // namespace probeloop::model
