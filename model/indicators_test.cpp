// Seed 004 Eqs. 4.27-4.32, each against a hand computation.
#include "model/indicators.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace probeloop::model {
namespace {

// Hyndman-Fan type 5 written independently: piecewise linear through (p_k, x_(k)) with
// p_k = (k - 1/2)/n, flat outside [p_1, p_n].
TEST(Indicators, HazenPercentileIsHyndmanFanType5) {
  std::vector<double> v = {7, 1, 10, 3, 5, 2, 9, 4, 8, 6};
  EXPECT_DOUBLE_EQ(hazenPercentile(v, 0.5), 5.5);
  EXPECT_DOUBLE_EQ(hazenPercentile(v, 0.26), 3.1);   // between p_3 = 0.25 and p_4 = 0.35
  EXPECT_DOUBLE_EQ(hazenPercentile(v, 0.99), 10);    // above p_10 = 0.95
  EXPECT_DOUBLE_EQ(hazenPercentile(v, 0.02), 1);     // below p_1 = 0.05
  EXPECT_DOUBLE_EQ(hazenPercentile({4.0}, 0.99), 4);
  std::vector<double> w;
  for (int i = 1; i <= 200; ++i) w.push_back(i);
  EXPECT_DOUBLE_EQ(hazenPercentile(w, 0.99), 198.5);  // k = 200 x 0.99 + 0.5 = 198.5
}

TEST(Indicators, RmseSmapePeakToValleyAndP99) {
  const std::vector<double> E = {2, -1, 3, 0, 4};
  const std::vector<double> P = {1, -1, 3.5, 1, 0};
  const auto r = indicators(E, P);
  // residuals 1, 0, -0.5, -1, 4
  EXPECT_DOUBLE_EQ(r.rmse, std::sqrt((1 + 0 + 0.25 + 1 + 16) / 5.0));
  // SMAPE: E = 0 (4th) and P = 0 (5th) are excluded; 1st: under-estimation 1 of 2 mirrored to
  // 3: |2-3|/(2+3) = 0.2; 2nd: 0; 3rd: 0.5/6.5.
  EXPECT_EQ(r.smape_samples, 3);
  EXPECT_NEAR(r.smape_percent, 100.0 / 3 * (0.2 + 0 + 0.5 / 6.5), 1e-12);
  // PV: [max res + |min res|] / [max E + |min E|] = (4 + 1) / (4 + 1) = 100 %.
  EXPECT_DOUBLE_EQ(r.pv_ratio_percent, 100);
  // P99 of |res| = {0, 0.5, 1, 1, 4}: above p_5 = 0.9 -> the largest.
  EXPECT_DOUBLE_EQ(r.p99, 4);
  EXPECT_THROW(indicators({1, 2}, {1}), InputError);
  EXPECT_THROW(indicators({1, NAN}, {1, 2}), InputError);
  const auto z = indicators({0, 0}, {0, 0});  // nothing to compare: defined, never NaN
  EXPECT_EQ(z.smape_samples, 0);
  EXPECT_TRUE(z.pv_defined);
  EXPECT_FALSE(indicators({0, 0}, {1, 0}).pv_defined);
}

}  // namespace
}  // namespace probeloop::model
