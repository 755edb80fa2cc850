// Lumped thermal network: nodes with heat capacity, conductances between nodes and to the
// environment, heat inputs. C dT/dt = -L T + g_env T_env(t) + q(t), with T the node
// temperatures, L the conductance Laplacian (plus the links to the environment), g_env the
// conductances to the environment, q the heat flows (W).
//
// Contract: advance(dt, T_env, q) integrates exactly for inputs held constant over dt (modal
// solution of the linear ODE; no step-size error), so the result does not depend on how a
// span is cut into steps when the inputs are constant. Every node must reach the
// environment through some path (else the network has no steady state): InputError.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::sim {

struct ThermalNodeSpec {
  std::string name;
  double capacity_J_per_K = 0;
  double to_environment_W_per_K = 0;
};
struct ThermalLinkSpec {
  int a = 0, b = 0;
  double conductance_W_per_K = 0;
};

class ThermalNetwork {
 public:
  ThermalNetwork() = default;
  ThermalNetwork(const std::vector<ThermalNodeSpec>& nodes, const std::vector<ThermalLinkSpec>& links,
                 double initial_C);

  int size() const { return static_cast<int>(T_.size()); }
  const Eigen::VectorXd& temperatures_C() const { return T_; }
  // Node time constants (s), slowest first: 1/eigenvalues of C^-1 L.
  std::vector<double> timeConstants_s() const;
  void advance(double dt_s, double T_env_C, const Eigen::VectorXd& heat_W);

 private:
  Eigen::VectorXd T_, sqrt_c_, g_env_;
  Eigen::MatrixXd V_;       // eigenvectors of S = C^-1/2 L C^-1/2
  Eigen::VectorXd lambda_;  // its eigenvalues (1/s)
};

}  // namespace probeloop::sim
