#include "sim/thermal_network.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace probeloop::sim {

ThermalNetwork::ThermalNetwork(const std::vector<ThermalNodeSpec>& nodes,
                               const std::vector<ThermalLinkSpec>& links, double initial_C) {
  const int n = static_cast<int>(nodes.size());
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
  sqrt_c_.resize(n);
  g_env_.resize(n);
  for (int i = 0; i < n; ++i) {
    if (!(nodes[i].capacity_J_per_K > 0))
      throw InputError("", 0, "thermal node '" + nodes[i].name + "': capacity must be positive");
    if (nodes[i].to_environment_W_per_K < 0)
      throw InputError("", 0, "thermal node '" + nodes[i].name + "': conductance to the environment must not be negative");
    sqrt_c_(i) = std::sqrt(nodes[i].capacity_J_per_K);
    g_env_(i) = nodes[i].to_environment_W_per_K;
    L(i, i) += g_env_(i);
  }
  for (const auto& l : links) {
    if (!(l.conductance_W_per_K > 0)) throw InputError("", 0, "thermal link: conductance must be positive");
    L(l.a, l.a) += l.conductance_W_per_K;
    L(l.b, l.b) += l.conductance_W_per_K;
    L(l.a, l.b) -= l.conductance_W_per_K;
    L(l.b, l.a) -= l.conductance_W_per_K;
  }
  // Each node must reach the environment (connected component with some g_env > 0).
  std::vector<int> reach(n, 0);
  for (int i = 0; i < n; ++i) reach[i] = g_env_(i) > 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (const auto& l : links)
      if (reach[l.a] != reach[l.b]) reach[l.a] = reach[l.b] = 1, changed = true;
  }
  for (int i = 0; i < n; ++i)
    if (!reach[i])
      throw InputError("", 0, "thermal node '" + nodes[i].name +
                                  "' has no path to the environment: its temperature would grow without bound");
  const Eigen::VectorXd is = sqrt_c_.cwiseInverse();
  const Eigen::MatrixXd S = is.asDiagonal() * L * is.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  V_ = es.eigenvectors();
  lambda_ = es.eigenvalues();
  T_ = Eigen::VectorXd::Constant(n, initial_C);
}

std::vector<double> ThermalNetwork::timeConstants_s() const {
  std::vector<double> t;
  for (int i = 0; i < lambda_.size(); ++i) t.push_back(1.0 / lambda_(i));
  std::sort(t.rbegin(), t.rend());
  return t;
}

void ThermalNetwork::advance(double dt, double T_env, const Eigen::VectorXd& heat_W) {
  if (dt <= 0 || T_.size() == 0) return;
  // y = C^1/2 T, z = V^T y: dz/dt = -lambda z + V^T C^-1/2 (g_env T_env + q).
  const Eigen::VectorXd w = (g_env_ * T_env + heat_W).cwiseQuotient(sqrt_c_);
  Eigen::VectorXd z = V_.transpose() * T_.cwiseProduct(sqrt_c_);
  const Eigen::VectorXd b = V_.transpose() * w;
  for (int i = 0; i < z.size(); ++i) {
    const double one_minus_e = -std::expm1(-lambda_(i) * dt);  // exact for small lambda dt
    z(i) = (1.0 - one_minus_e) * z(i) + one_minus_e / lambda_(i) * b(i);
  }
  T_ = (V_ * z).cwiseQuotient(sqrt_c_);
}

}  // namespace probeloop::sim
