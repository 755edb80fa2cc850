// Reference tests of the GUM engine: numbers from JCGM 100 (H.1) and from independent
// derivations (Irwin-Hall for sums of rectangular inputs, chi-square for a square).
#include "uncertainty/gum.hpp"

#include <gtest/gtest.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>

#include "core/error.hpp"

namespace probeloop::uncertainty {
namespace {

// JCGM 100 H.1, the end gauge: l = l_s + d - l_s (dalpha theta + alpha_s dtheta) (H.3), with
// the inputs of H.1.3-H.1.6. Published: l = 50.000 838 mm, u_c = 32 nm, nu_eff ~ 16,
// k = 2.92 for p = 0.99, U99 = 93 nm.
TEST(Gum, EndGaugeOfJcgm100H1) {
  Problem pr;
  pr.output = "l";
  pr.unit = "mm";
  pr.inputs = {Input::normal("l_s", 50.000623, 25e-6, 18), Input::normal("d", 215e-6, 9.7e-6, 25.6),
               Input::rectangular("alpha_s", 11.5e-6, 2e-6), Input::normal("theta", -0.1, 0.41),
               Input::normal("dalpha", 0, 0.58e-6, 50), Input::normal("dtheta", 0, 0.029, 2)};
  auto model = [](const auto* x) { return x[0] + x[1] - x[0] * (x[4] * x[3] + x[2] * x[5]); };
  const auto g = propagate<6>(pr, model, 0.99);
  EXPECT_NEAR(g.y, 50.000838, 1e-12);
  EXPECT_EQ(std::lround(g.u_c * 1e6), 32);  // nm
  EXPECT_EQ(std::floor(g.nu_eff), 16);
  EXPECT_NEAR(g.k, 2.92, 0.005);
  EXPECT_EQ(std::lround(g.U * 1e6), 93);
  // Sensitivities by automatic differentiation against the model's partial derivatives.
  EXPECT_NEAR(g.c[4], -50.000623 * -0.1, 1e-12);
  EXPECT_NEAR(g.c[5], -50.000623 * 11.5e-6, 1e-15);
  EXPECT_EQ(g.budget.contributions.front().input, "l_s");  // sorted, largest first
}

// JCGM 101 9.2.2: Y = X1 + X2 + X3 + X4, each N(0, 1): u = 2, 95 % interval +-3.92, and the
// GUF is validated by the MCM.
TEST(Gum, AdditiveModelWithNormalInputsValidatesTheGuf) {
  Problem pr;
  pr.output = "Y";
  for (int i = 0; i < 4; ++i) pr.inputs.push_back(Input::normal("X" + std::to_string(i + 1), 0, 1));
  auto model = [](const auto* x) { return x[0] + x[1] + x[2] + x[3]; };
  const auto g = propagate<4>(pr, model);
  EXPECT_DOUBLE_EQ(g.u_c, 2.0);
  EXPECT_NEAR(g.U, 3.92, 0.001);
  const auto m = monteCarlo(pr, model);
  EXPECT_TRUE(m.converged);
  EXPECT_NEAR(m.u, 2.0, 0.05);
  EXPECT_NEAR(m.symmetric_high, 3.92, 0.05);
  EXPECT_NEAR(m.symmetric_low, -3.92, 0.05);
  EXPECT_TRUE(validate(g, m).validated);
}

// Irwin-Hall: the sum of 4 U(0,1) has F(x) = 1/24 sum_k (-1)^k C(4,k) (x - k)^4, k <= x.
double irwinHall4Quantile(double p) {
  auto F = [](double x) {
    const double c[5] = {1, 4, 6, 4, 1};
    double s = 0;
    for (int k = 0; k <= 4 && k <= x; ++k) s += (k % 2 ? -1 : 1) * c[k] * std::pow(x - k, 4);
    return s / 24;
  };
  double lo = 0, hi = 4;
  for (int i = 0; i < 200; ++i) (F((lo + hi) / 2) < p ? lo : hi) = (lo + hi) / 2;
  return (lo + hi) / 2;
}

// JCGM 101 9.2.3: the same with rectangular inputs of u = 1 (a = sqrt 3): the MCM interval
// is the Irwin-Hall quantile, narrower than the GUF's +-3.92.
TEST(Gum, AdditiveModelWithRectangularInputsFollowsIrwinHall) {
  Problem pr;
  pr.output = "Y";
  for (int i = 0; i < 4; ++i) pr.inputs.push_back(Input::rectangular("X" + std::to_string(i + 1), 0, std::sqrt(3.0)));
  auto model = [](const auto* x) { return x[0] + x[1] + x[2] + x[3]; };
  const auto m = monteCarlo(pr, model);
  const double exact = std::sqrt(3.0) * (2 * irwinHall4Quantile(0.975) - 4);  // 3.88
  EXPECT_NEAR(exact, 3.88, 0.005);
  EXPECT_NEAR(m.symmetric_high, exact, 0.05);
  EXPECT_NEAR(m.u, 2.0, 0.05);
}

// Y = X^2, X ~ N(0, 1): the GUF sees no sensitivity at the estimate (u = 0); the MCM finds
// the chi-square with 1 dof. The shortest 95 % interval is [0, chi2_0.95], the symmetric one
// [chi2_0.025, chi2_0.975]; the GUF is not validated.
TEST(Gum, NonlinearModelIsNotValidatedAndMcmFindsChiSquare) {
  Problem pr;
  pr.output = "Y";
  pr.inputs = {Input::normal("X", 0, 1)};
  auto model = [](const auto* x) { return x[0] * x[0]; };
  const auto g = propagate<1>(pr, model);
  EXPECT_EQ(g.u_c, 0.0);
  McmOptions o;
  o.fixed_trials = 1'000'000;
  const auto m = monteCarlo(pr, model, o);
  boost::math::chi_squared chi(1);
  EXPECT_NEAR(m.shortest_high, boost::math::quantile(chi, 0.95), 0.03);
  EXPECT_NEAR(m.shortest_low, 0.0, 1e-3);
  EXPECT_NEAR(m.symmetric_high, boost::math::quantile(chi, 0.975), 0.05);
  EXPECT_NEAR(m.u, std::sqrt(2.0), 0.01);
  EXPECT_FALSE(validate(g, m).validated);
}

// Correlated inputs: u_c^2 = u1^2 + u2^2 + 2 r u1 u2 (JCGM 100 5.2.2) by both methods.
TEST(Gum, CorrelatedInputs) {
  Problem pr;
  pr.output = "Y";
  pr.inputs = {Input::normal("X1", 1, 1), Input::normal("X2", 2, 1)};
  pr.correlation = (Eigen::Matrix2d() << 1, 0.5, 0.5, 1).finished();
  auto model = [](const auto* x) { return x[0] + x[1]; };
  const auto g = propagate<2>(pr, model);
  EXPECT_NEAR(g.u_c, std::sqrt(3.0), 1e-12);
  EXPECT_TRUE(g.correlated);
  const auto m = monteCarlo(pr, model);
  EXPECT_NEAR(m.u, std::sqrt(3.0), 0.02);
  EXPECT_TRUE(validate(g, m).validated);
}

TEST(Gum, SameSeedSameResult) {
  Problem pr;
  pr.output = "Y";
  pr.inputs = {Input::triangular("X1", 0, 1), Input::uShaped("X2", 0, 1), Input::studentT("X3", 0, 1, 5)};
  auto model = [](const auto* x) { return x[0] + x[1] * x[2]; };
  McmOptions o;
  o.fixed_trials = 20'000;
  const auto a = monteCarlo(pr, model, o), b = monteCarlo(pr, model, o);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.symmetric_high, b.symmetric_high);
  o.seed = 2;
  EXPECT_NE(monteCarlo(pr, model, o).y, a.y);
  // Standard uncertainties of the bounded distributions and of the scaled t.
  EXPECT_NEAR(pr.inputs[0].u, 1 / std::sqrt(6.0), 1e-15);
  EXPECT_NEAR(pr.inputs[1].u, 1 / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(pr.inputs[2].u, std::sqrt(5.0 / 3.0), 1e-15);
}

TEST(Gum, BadInputIsExplained) {
  Problem pr;
  pr.output = "Y";
  pr.inputs = {Input::normal("X1", 1, 1), Input::normal("X2", 1, 1), Input::normal("X3", 1, 1)};
  auto sum = [](const auto* x) { return x[0] + x[1] + x[2]; };
  pr.correlation = (Eigen::Matrix3d() << 1, 0.9, -0.9, 0.9, 1, 0.9, -0.9, 0.9, 1).finished();
  try {
    propagate<3>(pr, sum);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not positive semidefinite"), std::string::npos) << e.what();
  }
  pr.correlation.resize(0, 0);
  pr.inputs[1].u = -1;
  EXPECT_THROW(propagate<3>(pr, sum), InputError);
  Problem root;
  root.output = "sqrt";
  root.inputs = {Input::normal("X", 0, 1)};
  EXPECT_THROW(propagate<1>(root, [](const auto* x) { using std::sqrt; return sqrt(x[0]); }), GeometryError);
}

}  // namespace
}  // namespace probeloop::uncertainty
