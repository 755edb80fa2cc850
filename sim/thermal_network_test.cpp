#include "sim/thermal_network.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace probeloop::sim {
namespace {

// One node: C dT/dt = G (T_env - T) + Q has T(t) = T_env + Q/G (1 - exp(-t G / C)).
TEST(ThermalNetwork, OneNodeFollowsTheFirstOrderStepResponse) {
  const double C = 2e5, G = 10, Q = 30, Tenv = 20;
  ThermalNetwork net({{"n", C, G}}, {}, Tenv);
  Eigen::VectorXd q(1);
  q << Q;
  double t = 0;
  for (double dt : {60.0, 600.0, 3600.0, 7200.0}) {
    net.advance(dt, Tenv, q);
    t += dt;
    EXPECT_NEAR(net.temperatures_C()(0), Tenv + Q / G * (1 - std::exp(-t * G / C)), 1e-12) << t;
  }
  ASSERT_EQ(net.timeConstants_s().size(), 1u);
  EXPECT_NEAR(net.timeConstants_s()[0], C / G, 1e-9);
}

// With inputs held, one long step equals many short ones (exact modal integration).
TEST(ThermalNetwork, ResultDoesNotDependOnTheStepWithHeldInputs) {
  std::vector<ThermalNodeSpec> nodes{{"a", 1e5, 5}, {"b", 4e5, 0}, {"c", 5e4, 1}};
  std::vector<ThermalLinkSpec> links{{0, 1, 3}, {1, 2, 8}};
  ThermalNetwork one(nodes, links, 20), many(nodes, links, 20);
  Eigen::VectorXd q(3);
  q << 50, 0, -10;
  one.advance(36000, 22, q);
  for (int k = 0; k < 3600; ++k) many.advance(10, 22, q);
  EXPECT_LT((one.temperatures_C() - many.temperatures_C()).cwiseAbs().maxCoeff(), 1e-9);
}

// After a long time the network sits at the steady state L T = g T_env + q, solved here
// independently from the conductance matrix written out by hand.
TEST(ThermalNetwork, ReachesTheSteadyStateOfTheConductanceMatrix) {
  std::vector<ThermalNodeSpec> nodes{{"a", 1e5, 5}, {"b", 4e5, 0}, {"c", 5e4, 1}};
  std::vector<ThermalLinkSpec> links{{0, 1, 3}, {1, 2, 8}};
  ThermalNetwork net(nodes, links, 20);
  Eigen::VectorXd q(3);
  q << 50, 0, -10;
  net.advance(1e8, 18, q);
  Eigen::Matrix3d L;
  L << 5 + 3, -3, 0, -3, 3 + 8, -8, 0, -8, 8 + 1;
  const Eigen::Vector3d rhs(5 * 18 + 50, 0, 1 * 18 - 10);
  const Eigen::Vector3d T = L.lu().solve(rhs);
  EXPECT_LT((net.temperatures_C() - T).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ThermalNetwork, ANodeWithoutAPathToTheEnvironmentIsRefused) {
  try {
    ThermalNetwork({{"a", 1e5, 5}, {"island", 1e5, 0}}, {}, 20);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'island' has no path to the environment"), std::string::npos);
  }
}

}  // namespace
}  // namespace probeloop::sim
