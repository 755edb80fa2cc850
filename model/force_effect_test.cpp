// The force effect (seed 003's force-induced error as a model term): a compliance in um/N
// times a cutting-force input. The campaign's truth is written here from seed 003's closed
// form for the gantry under F_y (Table 4, Sec. 5.2 arms), not through the library.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "model/diagnose.hpp"
#include "model/fit.hpp"

using namespace probeloop::model;

namespace {

// Y compliance of the gantry at the tool, um/N (our arms, docs/seed003-stiffness.md):
// crossbeam 1/(4 k_cby) + R_cby a_x/(k_cby D_cb^2), bed 1/(4 k_mby) + R_mby |a_x|/(k_mby L_mb^2).
const double kCompliance_um_per_N =
    1e3 * (1 / (4 * 4926.0) + 75.0 * 75 / (4926.0 * 1e4) + 1 / (4 * 84962.0) + 75.0 * 75 / (84962.0 * 1e4));

// 12 h of cutting: the forces change every 20 min (seeded levels), the hall swings slowly;
// errors every 5 min at input sample times.
Campaign forceCampaign(double noise_um, unsigned seed) {
  Campaign c;
  auto& in = c.inputs;
  in.file = "inputs.csv";
  in.names = {"T_env_C", "F_x_N", "F_y_N"};
  in.columns.assign(3, {});
  in.step_s = 60;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(0, 400);
  double fx = 0, fy = 0;
  for (int k = 0; k <= 12 * 60; ++k) {
    const double t = 60.0 * k;
    if (k % 20 == 0) fx = level(rng), fy = level(rng);
    in.t_s.push_back(t);
    in.columns[0].push_back(20 + 0.5 * std::sin(2 * M_PI * t / 86400));
    in.columns[1].push_back(fx);
    in.columns[2].push_back(fy);
  }
  auto& er = c.errors;
  er.file = "errors.csv";
  er.channels = {"EY_um"};
  er.values.assign(1, {});
  er.U.assign(1, {});
  std::normal_distribution<double> noise(0, noise_um);
  for (int k = 2; k <= 12 * 60; k += 5) {
    er.t_s.push_back(60.0 * k);
    er.values[0].push_back(0.4 + kCompliance_um_per_N * in.columns[2][k] + noise(rng));
    er.U[0].push_back(2 * noise_um);
  }
  return c;
}

}  // namespace

TEST(ForceEffect, IdUnitAndRegressor) {
  const Effect e = makeEffect(EffectKind::Force, "F_y_N");
  EXPECT_EQ(e.id(), "force(F_y_N)");
  EXPECT_EQ(kindFromName("force"), EffectKind::Force);
  EXPECT_TRUE(isForceInput("F_y_N"));
  EXPECT_FALSE(isForceInput("T_env_C"));
  EXPECT_EQ(inputUnit("F_y_N"), "N");
  // No force, no deflection: the regressor is the force itself.
  const auto r = regressor(e, {0, 60, 120}, {150, 0, 300}, 0);
  EXPECT_EQ(r, (std::vector<double>{150, 0, 300}));
}

TEST(ForceEffect, DiagnosisProposesItAndTheFitRecoversTheCompliance) {
  const double noise = 0.5;  // um
  const Campaign c = forceCampaign(noise, 5);
  ErrorModel m;
  m.file = "m.yaml";
  m.channels = {{"EY_um", {}}};
  // Without the effect the model fails: the residual is the deflection, tens of um.
  const Diagnosis d = diagnose(c, m, {});
  ASSERT_EQ(d.channels.size(), 1u);
  EXPECT_FALSE(d.channels[0].within);
  EXPECT_GT(d.channels[0].rms_judged(), 10 * noise);
  ASSERT_EQ(d.verdict, "missing") << d.message;
  ASSERT_FALSE(d.ranked.empty());
  EXPECT_EQ(d.ranked.front().effect.id(), "force(F_y_N)") << d.message;
  EXPECT_NE(d.ranked.front().command.find("probeloop model add force"), std::string::npos);
  EXPECT_NE(d.ranked.front().command.find("--input F_y_N"), std::string::npos);
  EXPECT_NE(d.message.find("compliance"), std::string::npos) << d.message;
  // With it: the compliance within its U (k = 2), in um/N, and the residual at the noise.
  const int n = trainingEnd(c.errors.size(), 0.6);
  const ChannelFit f = fitChannel(c, "EY_um", {makeEffect(EffectKind::Force, "F_y_N")}, n);
  ASSERT_EQ(f.effects.size(), 2u);
  const auto& k = f.effects[1].parameters.at(0);
  EXPECT_EQ(k.unit, "um/N");
  EXPECT_NEAR(k.value, kCompliance_um_per_N, 2 * k.u);
  EXPECT_LT(k.u, 0.01 * kCompliance_um_per_N);
  EXPECT_NEAR(f.validation.rmse, noise, 0.2 * noise);
  // And now nothing is missing.
  ErrorModel with = m;
  with.channels[0].effects.push_back(makeEffect(EffectKind::Force, "F_y_N"));
  EXPECT_EQ(diagnose(c, with, {}).verdict, "nothing_missing");
}
