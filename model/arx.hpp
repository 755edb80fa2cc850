// ARX and FIR models of one error channel from r input series (seed 004 Eqs. 4.3-4.21),
// identified by (weighted) linear least squares, simulated with their own past outputs fed
// back, and their orders chosen by a criterion that penalises order.
//
// Model (A(q) E[k] = B_1(q) u_1[k] + ... + B_r(q) u_r[k] + c + e[k]):
//   E[k] = -a_1 E[k-1] - ... - a_na E[k-na] + sum_i sum_j b_ij u_i[k - j - d] + c
// with j = 0 .. nb_i - 1 and d = 0 when the instantaneous term b_i0 u_i[k] is included
// (Eq. 4.3), d = 1 when not (Eqs. 4.6, 4.15): nb_i counts input coefficients either way.
// na = 0 is a FIR model. The intercept c is optional (the thesis's static and FIR models
// have one, Eqs. 4.22, 4.24).
//
// Contract:
// - Series are sampled on one time base: y has N samples, u is N x r; finite (InputError
//   naming the sample and the series otherwise).
// - fitArx refuses what cannot be identified, with the reason: an input that is constant
//   over the span (its coefficients and the intercept are not separable), too few samples
//   for the orders (N - max lag must exceed the number of parameters: it says how many more
//   samples are needed), a rank-deficient regression (it names the parameter that is not
//   identifiable). Parameter uncertainties are sigma^2 (Phi^T W Phi)^-1, sigma^2 = weighted
//   SSR / (rows - parameters).
// - simulate: E[k] for k >= max lag from the inputs and the model's own past outputs (the
//   first max-lag outputs are taken from `initial`); where `measured` holds a finite value,
//   it replaces the prediction in the feedback (seed 004 Ch. 6).
// - selectOrders: every combination of na in [0, max_na] and nb_i in [1, max_nb] (or
//   coordinate descent when there are more than 20 000), scored by Rissanen's MDL
//   V_N (1 + d ln N / N) (d parameters, N rows, V_N the mean squared residual). The printed
//   Eq. 4.23 uses "N = sum of the orders" and log(N)/N, which falls as the orders grow, so
//   it does not penalise order (docs/decisions.md).
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::model {

struct ArxOrders {
  int na = 1;               // output order; 0 = FIR
  std::vector<int> nb;      // coefficients per input, >= 1 each
  bool instantaneous = true;  // include b_i0 u_i[k]
  bool intercept = false;
  int maxLag() const;
  int parameterCount() const;
};

struct ArxModel {
  ArxOrders orders;
  std::vector<double> a;                 // a_1 .. a_na (A(q) = 1 + a_1 q^-1 + ...)
  std::vector<std::vector<double>> b;    // b[i][j]: input i, j-th coefficient
  double c = 0;                          // intercept
  Eigen::VectorXd theta;                 // [a, b_1.., b_r.., c]
  Eigen::MatrixXd covariance;            // of theta
  std::vector<std::string> names;        // of theta, e.g. "a1", "b[T_spindle][lag 0]", "c"
  double sigma = 0;                      // residual standard deviation (one-step)
  int rows = 0;                          // regression rows used (N - max lag)

  double staticGain(int input) const;    // sum_j b_ij / (1 + sum a): the steady-state response
};

ArxModel fitArx(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& orders,
                const std::vector<std::string>& input_names = {}, const Eigen::VectorXd* weights = nullptr);

// Simulation mode (Ch. 4 validation): initial supplies E[0 .. maxLag-1]; measured (optional,
// same length as u, NaN = no measurement) replaces predictions in the feedback.
Eigen::VectorXd simulate(const ArxModel& m, const Eigen::MatrixXd& u, const Eigen::VectorXd& initial,
                         const Eigen::VectorXd* measured = nullptr);

struct OrderSelection {
  ArxOrders best;
  double criterion = 0;
  int evaluated = 0;
};
OrderSelection selectOrders(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, int max_na, int max_nb,
                            bool instantaneous = true, bool intercept = false);

}  // namespace probeloop::model
