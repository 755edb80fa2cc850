// TALC replay (seed 004 Ch. 6) on synthetic campaigns whose schedule and residuals follow
// by hand from the construction: an exact ARX/FIR response of one temperature, dense
// measurements every 5 min from t = 0, disturbances at known times.
#include "model/talc.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.hpp"
#include "model/indicators.hpp"

namespace probeloop::model {
namespace {

constexpr double kD = 300;  // dense measurement step [s]
constexpr double kH = 3600;

double temperature(double t) {
  const double h = t / kH;
  return 20 + 2.0 * std::sin(2 * M_PI * h / 7.0) + 1.5 * std::sin(2 * M_PI * h / 2.3 + 1.0) +
         0.8 * std::sin(2 * M_PI * h / 31.0);
}

// Inputs every 60 s (T_a_C from `T`, c_rpm a square wave) over [0, hours]; dense errors every
// 300 s, channel q's value at sample k = errors[q](k, u) with u[i] = T(i D) - T(0) (the grid
// times are multiples of 60 s, so the replay's interpolation is exact).
using ErrorFn = std::function<double(int k, const std::vector<double>& u)>;
Campaign makeCampaign(double hours, const std::vector<std::string>& channels, const std::vector<ErrorFn>& errors,
                      const std::function<double(double)>& T = temperature) {
  Campaign c;
  c.inputs.file = "inputs.csv";
  c.inputs.names = {"T_a_C", "c_rpm"};
  c.inputs.columns.assign(2, {});
  c.inputs.step_s = 60;
  for (int i = 0; i * 60.0 <= hours * kH + 1e-9; ++i) {
    c.inputs.t_s.push_back(i * 60.0);
    c.inputs.columns[0].push_back(T(i * 60.0));
    c.inputs.columns[1].push_back((i / 90) % 2 ? -600.0 : 0.0);
  }
  c.errors.file = "errors.csv";
  c.errors.channels = channels;
  c.errors.values.assign(channels.size(), {});
  c.errors.U.assign(channels.size(), {});
  std::vector<double> u;
  for (int k = 0; k * kD <= hours * kH + 1e-9; ++k) u.push_back(T(k * kD) - T(0));
  for (int k = 0; k < static_cast<int>(u.size()); ++k) {
    c.errors.t_s.push_back(k * kD);
    for (std::size_t q = 0; q < channels.size(); ++q) {
      c.errors.values[q].push_back(errors[q](k, u));
      c.errors.U[q].push_back(0);
    }
  }
  return c;
}

// E[k] = 0.8 E[k-1] + 1.5 u[k] - 1.0 u[k-1], E[0] = 0 (na = 1, nb = 2 with the instantaneous term).
std::vector<double> exactArx(const std::vector<double>& u) {
  std::vector<double> E(u.size(), 0.0);
  for (std::size_t k = 1; k < u.size(); ++k) E[k] = 0.8 * E[k - 1] + 1.5 * u[k] - 1.0 * u[k - 1];
  return E;
}

// Deterministic noise, uniform in [-a, a].
double noise(int k, double a) {
  unsigned x = 2654435761u * static_cast<unsigned>(k + 1);
  x ^= x >> 13;
  x *= 0x5bd1e995u;
  x ^= x >> 15;
  return a * (2.0 * (x % 100000) / 99999.0 - 1.0);
}

std::vector<double> takenTimesH(const TalcReplay& r, double from_h) {
  std::vector<double> v;
  for (std::size_t j = 0; j < r.time_s.size(); ++j)
    if (r.taken[j] && r.time_s[j] >= from_h * kH - 1) v.push_back(r.time_s[j] / kH);
  return v;
}

TalcOptions baseOptions() {
  TalcOptions o;
  o.cp_h = 6;
  o.post_interval_h = 2;
  o.ng_interval_min = 10;
  o.ng_measurements = 12;
  o.update_interval_h = 0;
  o.na = 1;
  o.nb = 2;
  o.inputs = {"T_a_C"};
  return o;
}

TEST(Talc, ExactArxResponseIsCompensatedToTheNoiseLevel) {
  std::vector<double> E;
  auto c = makeCampaign(48, {"EY0C_um"}, {[&](int k, const std::vector<double>& u) {
                          if (E.empty()) E = exactArx(u);
                          return E[static_cast<std::size_t>(k)] + noise(k, 0.05);
                        }});
  const TalcReplay r = replayTalc(c, baseOptions());
  ASSERT_EQ(r.channels.size(), 1u);
  const auto& ch = r.channels[0];
  EXPECT_EQ(r.ng_phases, 0);
  EXPECT_EQ(ch.exceedances_unseen, 0);
  // Uncompensated P99 after the CP (t > 6 h), computed here from the construction.
  std::vector<double> uc;
  for (std::size_t k = 0; k < E.size(); ++k)
    if (k * kD > 6 * kH + 1) uc.push_back(std::fabs(E[k] + noise(static_cast<int>(k), 0.05)));
  EXPECT_DOUBLE_EQ(ch.p99_uncompensated, hazenPercentile(uc, 0.99));
  EXPECT_GT(ch.p99_uncompensated, 3.0);
  // The residual is the measurement noise carried through one feedback step: well under 0.25 um.
  EXPECT_LT(ch.p99_compensated, 0.25);
  EXPECT_GT(ch.reduction_percent, 90.0);
  // Compensation is off in the CP: compensated = uncompensated there.
  for (std::size_t j = 0; j < r.time_s.size(); ++j)
    if (r.in_cp[j]) {
      EXPECT_EQ(ch.compensated[j], ch.uncompensated[j]);
    }
}

TEST(Talc, PeriodicUpdatesScheduleAndQProd) {
  auto c = makeCampaign(50, {"EY0C_um"},
                        {[](int k, const std::vector<double>& u) { return exactArx(u)[static_cast<std::size_t>(k)]; }});
  TalcOptions o = baseOptions();
  o.update_interval_h = 12;
  const TalcReplay r = replayTalc(c, o);
  // CP: every measurement with t <= 6 h: 0, 5, ..., 360 min = 73; then 8, 10, ..., 50 h = 22.
  EXPECT_EQ(r.measurements_available, 601);
  EXPECT_EQ(r.measurements_taken, 73 + 22);
  std::vector<double> expected;
  for (int h = 8; h <= 50; h += 2) expected.push_back(h);
  const auto post = takenTimesH(r, 6.01);
  ASSERT_EQ(post.size(), expected.size());
  for (std::size_t i = 0; i < post.size(); ++i) EXPECT_NEAR(post[i], expected[i], 1e-9);
  // First fit at 6 h, then every 12 h: 18, 30, 42 (54 is past the end).
  EXPECT_EQ(r.updates_periodic, 3);
  EXPECT_EQ(r.updates_after_ng, 0);
  std::vector<double> upd;
  for (const auto& e : r.events)
    if (e.action == "periodic update") upd.push_back(e.t_s / kH);
  ASSERT_EQ(upd.size(), 3u);
  EXPECT_NEAR(upd[0], 18, 1e-9);
  EXPECT_NEAR(upd[1], 30, 1e-9);
  EXPECT_NEAR(upd[2], 42, 1e-9);
  // Eq. 6.1: t_total = 50 h + one dense interval; after the CP: 22 measurements over 44 h.
  EXPECT_NEAR(r.q_prod_percent, 100 * (1 - 95.0 * 95 / (50 * kH + kD)), 1e-9);
  EXPECT_NEAR(r.q_prod_post_cp_percent, 100 * (1 - 22 * 95.0 / (44 * kH)), 1e-9);
  // Noise-free exact model: nothing left after compensation.
  EXPECT_LT(r.channels[0].p99_compensated, 1e-6);
}

// FIR (na = 0) so that a disturbance persists in the residual (no output feedback):
// +8 um on EY0C_um, +6 um on EZ0T_um and +10 urad on EA0C_urad during [19 h, 21 h).
TEST(Talc, StepTripsOneNgPhaseWithExceedancesIgnoredThenAnUpdate) {
  auto fir = [](double gain, double step) {
    return [gain, step](int k, const std::vector<double>& u) {
      const double t = k * kD;
      const double e =
          gain * (2.0 * u[static_cast<std::size_t>(k)] - 0.5 * (k ? u[static_cast<std::size_t>(k - 1)] : 0.0));
      return e + (t >= 19 * kH && t < 21 * kH ? step : 0.0);
    };
  };
  auto c = makeCampaign(30, {"EY0C_um", "EA0C_urad", "EZ0T_um"}, {fir(1.0, 8.0), fir(2.0, 10.0), fir(0.5, 6.0)});
  TalcOptions o = baseOptions();
  o.na = 0;
  o.update_interval_h = 15;  // due at 21 h, inside the NG (20-22 h): folded into the NG's update
  const TalcReplay r = replayTalc(c, o);
  const auto& y = r.channels[0];
  const auto& a = r.channels[1];
  const auto& z = r.channels[2];
  EXPECT_EQ(r.ng_phases, 1);  // two channels beyond their limit at 20 h: one NG phase
  EXPECT_EQ(y.ng_triggers, 1);
  EXPECT_EQ(z.ng_triggers, 1);
  EXPECT_EQ(a.ng_triggers, 0);  // 10 urad < 15 urad: the angular limit applies
  // The measurement at 20 h sees the full step; NG measurements 20:10 .. 22:00 (12 at 10 min);
  // those at 20:10 .. 20:50 still see it and are ignored (5).
  ASSERT_FALSE(r.events.empty());
  std::vector<const TalcEvent*> ng_start, ignored, after_ng;
  for (const auto& e : r.events) {
    if (e.action == "NG start" && e.channel == "EY0C_um") ng_start.push_back(&e);
    if (e.action == "ignored (NG active)" && e.channel == "EY0C_um") ignored.push_back(&e);
    if (e.action == "update after NG") after_ng.push_back(&e);
  }
  ASSERT_EQ(ng_start.size(), 1u);
  EXPECT_NEAR(ng_start[0]->t_s, 20 * kH, 1e-9);
  EXPECT_EQ(ng_start[0]->channel, "EY0C_um");
  EXPECT_NEAR(ng_start[0]->residual, 8.0, 1e-6);  // the CP fit is exact on noise-free FIR data
  ASSERT_EQ(ignored.size(), 5u);
  for (int i = 0; i < 5; ++i) {
    EXPECT_NEAR(ignored[static_cast<std::size_t>(i)]->t_s, 20 * kH + (i + 1) * 600, 1e-9);
    EXPECT_EQ(ignored[static_cast<std::size_t>(i)]->channel, "EY0C_um");
  }
  EXPECT_EQ(y.exceedances_ignored, 5);
  EXPECT_EQ(z.exceedances_ignored, 5);
  EXPECT_EQ(a.exceedances_ignored, 0);
  const auto ngt = takenTimesH(r, 20.1);
  ASSERT_GE(ngt.size(), 12u);
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(ngt[static_cast<std::size_t>(i)], 20 + (i + 1) / 6.0, 1e-9);
  ASSERT_EQ(after_ng.size(), 1u);
  EXPECT_NEAR(after_ng[0]->t_s, 22 * kH, 1e-9);
  EXPECT_EQ(r.updates_after_ng, 1);
  EXPECT_EQ(r.updates_periodic, 0);  // the timer restarts at 22 h; 37 h is past the end
  // The post-CP clock restarts at 22 h: 24, 26, 28, 30.
  ASSERT_EQ(ngt.size(), 16u);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(ngt[static_cast<std::size_t>(12 + i)], 24 + 2 * i, 1e-9);
  // 73 (CP) + 8..20 h (7) + 12 (NG) + 4.
  EXPECT_EQ(r.measurements_taken, 96);
  // Unseen: 19:00 .. 19:55 (12, before the 20 h measurement) and the untaken 20:05 .. 20:55 (6).
  EXPECT_EQ(y.exceedances_unseen, 18);
  EXPECT_EQ(z.exceedances_unseen, 18);
  EXPECT_EQ(a.exceedances_unseen, 0);
}

TEST(Talc, RefusesATooShortCalibrationPhaseSayingHowLong) {
  auto c = makeCampaign(24, {"EY0C_um"},
                        {[](int k, const std::vector<double>& u) { return exactArx(u)[static_cast<std::size_t>(k)]; }});
  TalcOptions o = baseOptions();
  o.nb = 5;
  o.cp_h = 0.5;
  // na = 1, nb = 5 with u[k]: 4 samples of history + 6 parameters + 1 = 11 samples = 10
  // intervals of 300 s = 0.83 h; the thesis's sum of orders x interval: 6 x 300 s = 0.50 h.
  try {
    replayTalc(c, o);
    FAIL() << "a 0.5 h CP was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("too short"), std::string::npos) << m;
    EXPECT_NE(m.find("at least 0.83 h"), std::string::npos) << m;
    EXPECT_NE(m.find("0.50 h"), std::string::npos) << m;
  }
  // ASAP: with a white input the data are full-rank as soon as the sample count allows.
  // (A smooth input needs longer: its lagged copies are nearly collinear over 50 min.)
  auto white = makeCampaign(
      24, {"EY0C_um"}, {[](int k, const std::vector<double>& u) { return exactArx(u)[static_cast<std::size_t>(k)]; }},
      [](double t) { return 20 + noise(static_cast<int>(t / 60), 1.0); });
  o.cp_h = 0;
  const TalcReplay r = replayTalc(white, o);
  EXPECT_NEAR(r.cp_h, 3000.0 / kH, 1e-12);
  EXPECT_NEAR(r.cp_required_h, 3000.0 / kH, 1e-12);
  EXPECT_EQ(std::count(r.in_cp.begin(), r.in_cp.end(), 1), 11);
  EXPECT_GE(replayTalc(c, o).cp_h, r.cp_h);
}

TEST(Talc, RefusesACalibrationPhaseWithoutExcitationSayingFromWhenItWorks) {
  // The temperature is constant until 10 h, then ramps: b0 is identifiable from the first
  // sample after 10 h, i.e. a CP of 10 h + 300 s = 10.08 h.
  auto T = [](double t) { return t <= 10 * kH ? 20.0 : 20.0 + (t - 10 * kH) / kH; };
  auto c = makeCampaign(20, {"EY0C_um"},
                        {[](int k, const std::vector<double>& u) { return 3.0 * u[static_cast<std::size_t>(k)]; }}, T);
  TalcOptions o = baseOptions();
  o.na = 0;
  o.nb = 1;
  try {
    replayTalc(c, o);
    FAIL() << "an unexcited CP was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("does not identify"), std::string::npos) << m;
    EXPECT_NE(m.find("constant"), std::string::npos) << m;
    EXPECT_NE(m.find("from a CP of 10.08 h"), std::string::npos) << m;
  }
}

TEST(Talc, TextRoundsToOneDecimalAndReducesFromUnroundedValues) {
  TalcReplay r;
  r.cp_h = 6;
  r.cp_required_h = 0.8;
  r.dense_step_s = 300;
  r.inputs = {"T_a_C - start"};
  TalcChannelResult a;
  a.channel = "EY0C_um";
  a.unit = "um";
  a.p99_uncompensated = 4.449;
  a.p99_compensated = 2.751;
  a.reduction_percent = 100 * (1 - 2.751 / 4.449);  // 38.17 %; from the rounded 4.4 and 2.8: 36.4 %
  TalcChannelResult b;
  b.channel = "EA0C_urad";
  b.unit = "urad";
  b.p99_uncompensated = 18.75;
  b.p99_compensated = 7.04;
  b.reduction_percent = 100 * (1 - 7.04 / 18.75);  // 62.45 %
  r.channels = {a, b};
  r.events.push_back({20 * kH, "EY0C_um", 8.123, "NG start"});
  const std::string s = talcText(r);
  EXPECT_NE(s.find("4.4 um"), std::string::npos) << s;
  EXPECT_NE(s.find("2.8 um"), std::string::npos) << s;
  EXPECT_NE(s.find("38.2 %"), std::string::npos) << s;
  EXPECT_NE(s.find("18.8 urad"), std::string::npos) << s;  // 18.75 -> 18.8 (as Table 6.5's 18.8 um/m)
  EXPECT_NE(s.find("7.0 urad"), std::string::npos) << s;
  EXPECT_NE(s.find("62.5 %"), std::string::npos) << s;
  EXPECT_NE(s.find("20.000"), std::string::npos) << s;
  EXPECT_NE(s.find("NG start"), std::string::npos) << s;
}

TEST(Talc, RefusesUnknownInputsChannelsAndUnits) {
  auto c = makeCampaign(12, {"EY0C_um", "EQ_mm"},
                        {[](int k, const std::vector<double>& u) { return u[static_cast<std::size_t>(k)]; },
                         [](int, const std::vector<double>&) { return 0.0; }});
  TalcOptions o = baseOptions();
  o.channels = {"EY0C"};
  o.inputs = {"T_b_C"};
  try {
    replayTalc(c, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("T_a_C, c_rpm"), std::string::npos) << e.what();
  }
  o.inputs = {"T_a_C", "|c_rpm|"};
  o.nb = 1;
  o.na = 0;
  EXPECT_NO_THROW(replayTalc(c, o));
  o.channels = {"EQ_mm"};
  try {
    replayTalc(c, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unit 'mm'"), std::string::npos) << e.what();
  }
  o.channels = {};
  o.predicted_weight = 2;
  EXPECT_THROW(replayTalc(c, o), InputError);
}

}  // namespace
}  // namespace probeloop::model
