// Identification and diagnosis on synthetic campaigns whose truth is written here by an
// independent formula (superposition of step responses, not the library's recursion).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/error.hpp"
#include "model/diagnose.hpp"
#include "model/outputs.hpp"
#include "model/fit.hpp"

using namespace probeloop;
using namespace probeloop::model;

namespace {

// A 48 h campaign: inputs every 60 s (hall temperature with a day cycle, C-axis speed
// steps every 90 min), errors every 7 min.
struct Synthetic {
  Campaign c;
  std::vector<double> lag_caxis;  // at the error times: the first-order lag of |c_rpm| (tau)
};

// x(t) for u held at u_k on [t_k, t_k+1), x(0) = u_0: superposition of the steps u_k - u_{k-1}
// switched on at t_k, each answering (1 - e^{-(t - t_k)/tau}).
double lagBySuperposition(const std::vector<double>& t, const std::vector<double>& u, double at, double tau) {
  double x = u[0];
  for (std::size_t k = 1; k < t.size() && t[k - 1] < at; ++k) {
    // The logged value u_{k-1} holds from t_{k-1}; the step to u_k happens at t_k.
    if (t[k] >= at) break;
    x += (u[k] - u[k - 1]) * (1 - std::exp(-(at - t[k]) / tau));
  }
  return x - u[0];
}

Synthetic makeCampaign(double gain_um_per_rpm, double tau_s, double noise_um, unsigned seed) {
  Synthetic s;
  auto& in = s.c.inputs;
  in.file = "inputs.csv";
  in.names = {"T_env_C", "c_rpm", "tool_changes"};
  in.columns.assign(3, {});
  in.step_s = 60;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> level(0, 4);
  double rpm = 0;
  for (int k = 0; k <= 48 * 60; ++k) {
    const double t = 60.0 * k;
    if (k % 90 == 0) rpm = 300.0 * level(rng);
    in.t_s.push_back(t);
    in.columns[0].push_back(20 + 2 * std::sin(2 * M_PI * t / 86400));
    in.columns[1].push_back(rpm);
    in.columns[2].push_back(0);
  }
  auto& er = s.c.errors;
  er.file = "errors.csv";
  er.channels = {"EY0C_um", "EX0C_um"};
  er.values.assign(2, {});
  er.U.assign(2, {});
  std::normal_distribution<double> noise(0, noise_um);
  for (double t = 100; t < 48 * 3600 - 60; t += 420) {
    er.t_s.push_back(t);
    const double x = lagBySuperposition(in.t_s, in.columns[1], t, tau_s);
    s.lag_caxis.push_back(x);
    er.values[0].push_back(1.0 + gain_um_per_rpm * x + noise(rng));
    er.values[1].push_back(-0.5 + noise(rng));
    er.U[0].push_back(2 * noise_um);
    er.U[1].push_back(2 * noise_um);
  }
  return s;
}

}  // namespace

TEST(FitChannel, RecoversGainAndTimeConstantOfALagWithHonestUncertainty) {
  const double k = 0.012, tau = 2400;  // 14 um at 1200 rpm, 40 min
  const auto s = makeCampaign(k, tau, 0.3, 7);
  Effect lag = makeEffect(EffectKind::Lag, "c_rpm");
  const int n = trainingEnd(s.c.errors.size(), 0.6);
  const auto f = fitChannel(s.c, "EY0C_um", {lag}, n);
  ASSERT_EQ(f.effects.size(), 2u);
  const auto& p = f.effects[1].parameters;
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0].value, k, 4 * p[0].u);
  EXPECT_NEAR(p[1].value, tau, 4 * p[1].u);
  EXPECT_LT(p[1].u, 0.05 * tau);
  EXPECT_NEAR(f.effects[0].parameters[0].value, 1.0, 4 * f.effects[0].parameters[0].u);
  EXPECT_NEAR(f.sigma, 0.3, 0.05);
  ASSERT_TRUE(f.has_validation);
  EXPECT_LT(f.validation.rmse, 1.2 * 0.3);  // the validation span is predicted from the inputs alone
}

// A lag acting over a lever (a thermal scale error): the error is k x(t) L(t) with L a second
// input (a travel that changes every 6 h); the fit recovers k and tau, and the same lag without
// the lever cannot explain it.
TEST(FitChannel, ALagOverALeverIsTheLagTimesTheLever) {
  auto s = makeCampaign(0, 2400, 0.2, 11);
  auto& in = s.c.inputs;
  in.names.push_back("travel_mm");
  in.columns.push_back({});
  for (double t : in.t_s) in.columns.back().push_back(40 + 20 * (static_cast<int>(t / 21600) % 4));
  const double k = 2e-4;  // um per rpm per mm: 0.24 um/mm at 1200 rpm
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.2);
  for (std::size_t i = 0; i < s.c.errors.t_s.size(); ++i) {
    const double L = 40 + 20 * (static_cast<int>(s.c.errors.t_s[i] / 21600) % 4);
    s.c.errors.values[0][i] = 1.0 + k * s.lag_caxis[i] * L + noise(rng);
  }
  Effect scale = makeEffect(EffectKind::Lag, "c_rpm");
  scale.lever = "travel_mm";
  EXPECT_EQ(scale.id(), "lag(c_rpm)*travel_mm");
  const int n = trainingEnd(s.c.errors.size(), 0.6);
  const auto f = fitChannel(s.c, "EY0C_um", {scale}, n);
  const auto& p = f.effects[1].parameters;
  EXPECT_NEAR(p[0].value, k, 4 * p[0].u);
  EXPECT_NEAR(p[1].value, 2400, 4 * p[1].u);
  EXPECT_EQ(p[0].unit, "um/(rpm mm)");
  EXPECT_LT(f.validation.rmse, 1.3 * 0.2);
  const auto plain = fitChannel(s.c, "EY0C_um", {makeEffect(EffectKind::Lag, "c_rpm")}, n);
  EXPECT_GT(plain.validation.rmse, 3 * f.validation.rmse);
  Effect missing = scale;
  missing.lever = "no_such_mm";
  EXPECT_THROW(fitChannel(s.c, "EY0C_um", {missing}, n), InputError);
}

TEST(FitChannel, RefusesWhatCannotBeIdentified) {
  const auto s = makeCampaign(0.012, 2400, 0.3, 7);
  const int n = trainingEnd(s.c.errors.size(), 0.6);
  // A constant input, named.
  try {
    fitChannel(s.c, "EY0C_um", {makeEffect(EffectKind::Transient, "tool_changes")}, n);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'tool_changes' is constant"), std::string::npos) << e.what();
  }
  // Too few samples: says how many more.
  try {
    fitChannel(s.c, "EY0C_um", {makeEffect(EffectKind::Lag, "c_rpm"), makeEffect(EffectKind::Static, "T_env_C")}, 3);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("3 samples for 4 parameters"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2 more samples"), std::string::npos) << e.what();
  }
  // Unknown input and channel, listing what exists.
  EXPECT_THROW(fitChannel(s.c, "EY0C_um", {makeEffect(EffectKind::Static, "T_spindle_C")}, n), InputError);
  EXPECT_THROW(fitChannel(s.c, "EQ0C_um", {}, n), InputError);
  // Static and a drift over a span where the temperature is a straight line: collinear.
  auto flat = s;
  for (std::size_t k = 0; k < flat.c.inputs.t_s.size(); ++k) flat.c.inputs.columns[0][k] = 20 + flat.c.inputs.t_s[k] / 86400;
  try {
    fitChannel(flat.c, "EY0C_um", {makeEffect(EffectKind::Static, "T_env_C"), makeEffect(EffectKind::Drift)}, n);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be identified"), std::string::npos) << e.what();
  }
}

TEST(Diagnose, RanksTheHiddenRotaryHeatFirstAndSaysHowToAddIt) {
  const auto s = makeCampaign(0.012, 2400, 0.3, 11);
  ErrorModel m;
  m.channels = {{"EY0C_um", {}}, {"EX0C_um", {}}};
  DiagnoseOptions opt;
  opt.model_path = "m.yaml";
  const auto d = diagnose(s.c, m, opt);
  ASSERT_EQ(d.verdict, "missing");
  ASSERT_FALSE(d.ranked.empty());
  const auto& top = d.ranked.front();
  EXPECT_EQ(top.effect.id(), "lag(c_rpm)");
  ASSERT_EQ(top.channels.size(), 1u);  // EX0C has nothing to explain
  EXPECT_EQ(top.channels[0].channel, "EY0C_um");
  EXPECT_LT(top.channels[0].rmse_after, 1.5 * 0.3);
  EXPECT_NEAR(*top.effect.tau_s, 2400, 300);
  EXPECT_NE(top.sentence.find("rotary (C) axis"), std::string::npos) << top.sentence;
  EXPECT_EQ(top.command.rfind("probeloop model add lag --model m.yaml --channels EY0C_um --input c_rpm --tau-s ", 0), 0u)
      << top.command;
  // The residual of the offset-only model is not white; EX0C's is.
  EXPECT_FALSE(d.channels[0].white);
  EXPECT_TRUE(d.channels[1].white);
}

TEST(Diagnose, SaysNothingIsMissingWhenTheModelIsComplete) {
  const auto s = makeCampaign(0.012, 2400, 0.3, 13);
  ErrorModel m;
  Effect lag = makeEffect(EffectKind::Lag, "c_rpm");
  m.channels = {{"EY0C_um", {lag}}, {"EX0C_um", {}}};
  const auto d = diagnose(s.c, m, {});
  EXPECT_EQ(d.verdict, "nothing_missing") << d.message << (d.ranked.empty() ? "" : d.ranked[0].sentence);
  EXPECT_TRUE(d.ranked.empty());
}

TEST(LjungBox, MatchesAHandComputationAndTheChiSquareTail) {
  // x = 1, -1, 1, -1: rho_1 = -3/4, rho_2 = 2/4; Q = 4*6*(rho1^2/3 + rho2^2/2).
  double Q = 0, p = 0;
  ljungBox({1, -1, 1, -1}, 2, Q, p);
  EXPECT_NEAR(Q, 24 * (0.5625 / 3 + 0.25 / 2), 1e-12);
  EXPECT_NEAR(p, std::exp(-Q / 2), 1e-12);  // chi^2 with 2 dof: P(>Q) = e^{-Q/2}
}

TEST(Effects, TransientJumpsHalfAStepBeforeItsSampleAndDecays) {
  // One event counted in sample 2 (t = 120 s) happened at 90 s: at t it is e^{-(t-90)/tau}.
  const std::vector<double> t{0, 60, 120, 180, 240}, u{0, 0, 1, 0, 0};
  Effect e = makeEffect(EffectKind::Transient, "tool_changes");
  const auto r = regressor(e, t, u, 600);
  EXPECT_EQ(r[1], 0);
  for (int k = 2; k < 5; ++k) EXPECT_NEAR(r[k], std::exp(-(t[k] - 90) / 600), 1e-15);
}

TEST(FitChannel, AFixedTimeConstantIsUsedAsGivenAndIsNoParameter) {
  const auto s = makeCampaign(0.012, 2400, 0.3, 7);
  const int n = trainingEnd(s.c.errors.size(), 0.6);
  Effect lag = makeEffect(EffectKind::Lag, "c_rpm");
  lag.tau_s = 30;  // below the grid's lower bound: kept anyway
  lag.tau_fixed = true;
  const auto f = fitChannel(s.c, "EY0C_um", {lag}, n);
  EXPECT_EQ(f.parameters, 2);  // offset and gain
  ASSERT_EQ(f.effects[1].parameters.size(), 2u);
  EXPECT_EQ(f.effects[1].parameters[1].name, "tau (fixed)");
  EXPECT_EQ(f.effects[1].parameters[1].value, 30);
  EXPECT_EQ(f.effects[1].parameters[1].u, 0);
  // With the true tau fixed, the gain and its u are those of the linear fit: tight.
  lag.tau_s = 2400;
  const auto g = fitChannel(s.c, "EY0C_um", {lag}, n);
  EXPECT_NEAR(g.effects[1].parameters[0].value, 0.012, 4 * g.effects[1].parameters[0].u);
  EXPECT_LT(g.effects[1].parameters[0].u, 2e-4);
}

// "Within 1.5 u" is weak where u dwarfs the residual (model/verdict_strength.hpp): the
// diagnosis and the fit say so, with the ratio, in the message and in the text.
TEST(Diagnose, SaysHowWeakWithinIsWhenUDwarfsTheResidual) {
  auto s = makeCampaign(0.012, 2400, 0.3, 13);
  ErrorModel m;
  m.file = "m.yaml";
  m.channels = {{"EY0C_um", {makeEffect(EffectKind::Lag, "c_rpm")}}, {"EX0C_um", {}}};
  // As generated, u = U/2 = 0.3 um, the noise itself: a fair verdict, no note.
  auto d = diagnose(s.c, m, {});
  ASSERT_EQ(d.verdict, "nothing_missing") << d.message;
  EXPECT_EQ(d.message.find("weak"), std::string::npos) << d.message;
  EXPECT_EQ(diagnosisText(s.c, m, d).find("cannot be judged finer than u"), std::string::npos);
  // The same residual against a claimed U three times larger: u = 0.9 um, about 3x the residual.
  for (auto& U : s.c.errors.U)
    for (double& v : U) v *= 3;
  d = diagnose(s.c, m, {});
  ASSERT_EQ(d.verdict, "nothing_missing") << d.message;
  EXPECT_NE(d.message.find("The verdict is weak on EY0C_um"), std::string::npos) << d.message;
  const std::string text = diagnosisText(s.c, m, d);
  EXPECT_NE(text.find("note: the measurement's uncertainty (u = 0.9 um) is "), std::string::npos) << text;
  EXPECT_NE(text.find("\u00d7 the residual (RMS 0."), std::string::npos) << text;
  EXPECT_NE(fitText(s.c, m, fitModel(s.c, m)).find("note: the measurement's uncertainty (u = 0.9 um)"), std::string::npos);
}

TEST(Diagnose, PrintsAVanishingPValueAsABoundNeverZero) {
  const auto s = makeCampaign(0.012, 2400, 0.3, 11);
  ErrorModel m;
  m.file = "m.yaml";
  m.channels = {{"EY0C_um", {}}, {"EX0C_um", {}}};
  const auto d = diagnose(s.c, m, {});
  ASSERT_LT(d.channels[0].ljung_box_p, 1e-4);  // the hidden rotary heat: a structured residual
  const std::string text = diagnosisText(s.c, m, d);
  EXPECT_NE(text.find("NOT white, p < 1e-4"), std::string::npos) << text;
  EXPECT_EQ(text.find("p = 0 "), std::string::npos) << text;
}
