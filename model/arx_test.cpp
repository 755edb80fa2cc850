// ARX/FIR identification (seed 004 Eqs. 4.3-4.21): recovery of known models, uncertainty,
// weighting, simulation mode, order selection and refusals.
#include "model/arx.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"

namespace probeloop::model {
namespace {

// Random-step inputs (heat sources switched at random, as in seed 004 Ch. 4), reproducible.
Eigen::MatrixXd inputs(int N, int r, unsigned seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> level(0, 5);
  std::uniform_int_distribution<int> hold(3, 12);
  Eigen::MatrixXd u(N, r);
  for (int i = 0; i < r; ++i) {
    double v = level(g);
    for (int k = 0, left = hold(g); k < N; ++k, --left) {
      if (left == 0) v = level(g), left = hold(g);
      u(k, i) = v;
    }
  }
  return u;
}

// y[k] = -sum a_i y[k-i] + sum b_ij u_i[k-j] + c (instantaneous terms included) + e[k].
Eigen::VectorXd generate(const Eigen::MatrixXd& u, const std::vector<double>& a, const std::vector<std::vector<double>>& b,
                         double c, double noise = 0, unsigned seed = 1) {
  std::mt19937 g(seed);
  std::normal_distribution<double> e(0, noise > 0 ? noise : 1.0);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.rows());
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    double v = c;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (k - 1 - static_cast<Eigen::Index>(i) >= 0) v -= a[i] * y(k - 1 - static_cast<Eigen::Index>(i));
    for (std::size_t in = 0; in < b.size(); ++in)
      for (std::size_t j = 0; j < b[in].size(); ++j)
        if (k - static_cast<Eigen::Index>(j) >= 0) v += b[in][j] * u(k - static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(in));
    y(k) = v + (noise > 0 ? e(g) : 0.0);
  }
  return y;
}

// Seed 004 Eq. 4.26 with the sign of the notes' consistency check (E[k] = 0.9 E[k-1] + ...,
// i.e. a_1 = -0.9): static gains 0.3/0.1 = 3.0 and -0.1/0.1 = -1.0.
TEST(Arx, RecoversTheThesisArxModelExactlyWithoutNoise) {
  const auto u = inputs(400, 2, 7);
  const std::vector<std::vector<double>> b = {{1.0, -0.7}, {0.1, 0.0, -0.1, -0.1}};
  const auto y = generate(u, {-0.9}, b, 0.2);
  ArxOrders o;
  o.na = 1;
  o.nb = {2, 4};
  o.intercept = true;
  const auto m = fitArx(y, u, o, {"S1", "S2"});
  EXPECT_NEAR(m.a[0], -0.9, 1e-10);
  for (std::size_t i = 0; i < b.size(); ++i)
    for (std::size_t j = 0; j < b[i].size(); ++j) EXPECT_NEAR(m.b[i][j], b[i][j], 1e-9) << i << " " << j;
  EXPECT_NEAR(m.c, 0.2, 1e-9);
  EXPECT_NEAR(m.staticGain(0), 3.0, 1e-8);
  EXPECT_NEAR(m.staticGain(1), -1.0, 1e-8);
  EXPECT_EQ(m.names[1], "b[S1][lag 0]");
  // Simulation mode reproduces the data from the first max-lag outputs alone.
  const Eigen::VectorXd sim = simulate(m, u, y.head(o.maxLag()));
  EXPECT_LT((sim - y).cwiseAbs().maxCoeff(), 1e-7);
}

// Seed 004 Eq. 4.24, the FIR model of E_Y: static gains -20.5 + 23.9 = 3.4 and
// 2.8 - 4.3 + 5.9 - 4.9 = -0.5, the static model's (Eq. 4.22).
TEST(Arx, RecoversTheThesisFirModel) {
  const auto u = inputs(300, 2, 3);
  const auto y = generate(u, {}, {{-20.5, 23.9}, {2.8, -4.3, 5.9, -4.9}}, 0.2);
  ArxOrders o;
  o.na = 0;
  o.nb = {2, 4};
  o.intercept = true;
  const auto m = fitArx(y, u, o);
  EXPECT_NEAR(m.staticGain(0), 3.4, 1e-9);
  EXPECT_NEAR(m.staticGain(1), -0.5, 1e-9);
}

TEST(Arx, NoisyDataGiveHonestParameterUncertainties) {
  const auto u = inputs(3000, 1, 11);
  const double sigma = 0.05;
  std::mt19937 g(5);
  std::normal_distribution<double> e(0, sigma);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.rows());
  for (Eigen::Index k = 1; k < u.rows(); ++k) y(k) = 0.8 * y(k - 1) + 0.5 * u(k, 0) + 0.3 * u(k - 1, 0) + e(g);
  ArxOrders o;
  o.na = 1;
  o.nb = {2};
  const auto m = fitArx(y, u, o);
  const double truth[3] = {-0.8, 0.5, 0.3};
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::fabs(m.theta(i) - truth[i]), 4 * std::sqrt(m.covariance(i, i))) << i;
  EXPECT_NEAR(m.sigma, sigma, 0.1 * sigma);
}

// Eq. 4.20: samples with weight 0 do not pull the fit; plain least squares is pulled.
TEST(Arx, WeightedLeastSquaresIgnoresZeroWeightSamples) {
  const auto u = inputs(200, 1, 2);
  Eigen::VectorXd y = generate(u, {}, {{1.5, -0.5}}, 0.0);
  Eigen::VectorXd w = Eigen::VectorXd::Ones(200);
  for (int k = 100; k < 110; ++k) y(k) += 5, w(k) = 0;
  ArxOrders o;
  o.na = 0;
  o.nb = {2};
  const auto weighted = fitArx(y, u, o, {}, &w);
  EXPECT_NEAR(weighted.b[0][0], 1.5, 1e-9);
  EXPECT_NEAR(weighted.b[0][1], -0.5, 1e-9);
  EXPECT_GT(std::fabs(fitArx(y, u, o).b[0][0] - 1.5), 1e-3);
}

// Ch. 6: measured outputs replace predictions in the feedback where they exist.
TEST(Arx, MeasuredOutputsReplacePredictionsInTheFeedback) {
  const auto u = inputs(50, 1, 4);
  const auto y = generate(u, {-0.5}, {{1.0}}, 0.0);
  ArxModel m;
  m.orders.na = 1;
  m.orders.nb = {1};
  m.a = {-0.4};  // a wrong model: its simulation drifts from the data
  m.b = {{1.0}};
  const Eigen::VectorXd free = simulate(m, u, y.head(1));
  const Eigen::VectorXd fed = simulate(m, u, y.head(1), &y);
  // With every output measured, each prediction is one step from the data:
  // E[k] - Ê[k] = (0.5 - 0.4) E[k-1].
  for (int k = 1; k < 50; ++k) EXPECT_NEAR(y(k) - fed(k), 0.1 * y(k - 1), 1e-12);
  EXPECT_GT((y - free).cwiseAbs().maxCoeff(), (y - fed).cwiseAbs().maxCoeff());
}

TEST(Arx, OrderSelectionPenalisesOrder) {
  const auto u = inputs(1500, 2, 9);
  // White equation error, the noise model ARX assumes (measurement noise on E would make the
  // equation error coloured, and higher orders would rightly fit it better).
  const Eigen::VectorXd y = generate(u, {-0.7}, {{0.8, 0.4}, {0.3, 0.2, 0.1, -0.2}}, 0.0, 0.01, 8);
  const auto s = selectOrders(y, u, 2, 6);
  EXPECT_EQ(s.best.na, 1);
  EXPECT_EQ(s.best.nb, (std::vector<int>{2, 4}));
  EXPECT_EQ(s.evaluated, 3 * 6 * 6);
}

TEST(Arx, RefusesWhatCannotBeIdentified) {
  const auto u = inputs(40, 2, 1);
  const auto y = generate(u, {-0.5}, {{1.0, 0.5}, {0.2}}, 0.0);
  ArxOrders o;
  o.na = 1;
  o.nb = {10, 10};
  try {
    fitArx(y.head(15), u.topRows(15), o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more)"), std::string::npos) << e.what();
  }
  o.nb = {2, 1};
  Eigen::MatrixXd flat = u;
  flat.col(1).setConstant(3.0);
  try {
    fitArx(y, flat, o, {"T_spindle", "T_hall"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("T_hall is constant"), std::string::npos) << e.what();
  }
  Eigen::MatrixXd twins = u;
  twins.col(1) = 2 * u.col(0);  // two inputs that move together
  o.nb = {1, 1};
  EXPECT_THROW(fitArx(y, twins, o), GeometryError);
  Eigen::VectorXd bad = y;
  bad(7) = NAN;
  try {
    fitArx(bad, u, o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 8"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probeloop::model
