// The GUM engine: the law of propagation of uncertainty (JCGM 100, "GUF") with
// sensitivities by automatic differentiation, and the Monte Carlo method (JCGM 101, "MCM")
// with its adaptive number of trials, coverage intervals and the §8 validation of the GUF.
//
// A measurement model is a callable templated on its scalar, `template <class T> T f(const
// T* x)`: the engine calls it with ceres::Jet for the sensitivities and with double for the
// trials.
//
// Contract:
// - Inputs carry a standard uncertainty u > 0 (u = 0 only for a constant), a distribution
//   and degrees of freedom; the correlation matrix (empty = none) must be symmetric with a
//   unit diagonal and positive semidefinite: InputError otherwise.
// - GUF: u_c^2 = c^T V c; nu_eff by Welch-Satterthwaite (JCGM 100 G.2b) over the
//   contributions |c_i| u_i (with correlated inputs an approximation, not allowed below the
//   smallest dof of the correlated inputs that contribute; the result says so); k from Student's t at floor(nu_eff) (G.6.4) for the coverage p. A
//   model whose value or derivative is not finite at the estimate is a GeometryError.
// - MCM: deterministic for a seed; correlated inputs must be normal (JCGM 101 6.4.8);
//   adaptive trials per JCGM 101 7.9 with n_dig significant digits; probabilistically
//   symmetric and shortest intervals; validation of the GUF per JCGM 101 8.
#pragma once
#include <ceres/jet.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "uncertainty/budget.hpp"

namespace probeloop::uncertainty {

enum class Distribution { Normal, Rectangular, Triangular, UShaped, StudentT };
const char* distributionName(Distribution d);

struct Input {
  std::string name, unit;
  double value = 0;
  double u = 0;  // standard uncertainty
  Distribution distribution = Distribution::Normal;
  double dof = std::numeric_limits<double>::infinity();
  char type = 'B';
  double half_width = 0;  // rectangular, triangular, U-shaped
  double scale = 0;       // Student t: x = value + scale * t_dof
  // The standard uncertainty the GUF propagates: s(x) with its dof for a Student t input
  // (JCGM 100 4.2, G.3), u otherwise. (u itself is the standard deviation of the PDF the MCM
  // draws, JCGM 101 6.4.9.)
  double gufU() const { return distribution == Distribution::StudentT ? scale : u; }

  static Input normal(std::string name, double value, double u, double dof = std::numeric_limits<double>::infinity());
  static Input rectangular(std::string name, double value, double half_width);  // u = a / sqrt 3
  static Input triangular(std::string name, double value, double half_width);   // u = a / sqrt 6
  static Input uShaped(std::string name, double value, double half_width);      // u = a / sqrt 2
  // Type A from n observations: mean, s / sqrt(n), nu = n - 1; the MCM draws the scaled and
  // shifted t of JCGM 101 6.4.9 (u = s/sqrt(n) sqrt(nu / (nu - 2)), needs n >= 4).
  static Input studentT(std::string name, double mean, double s_of_mean, double dof);
};

struct Problem {
  std::string output, unit;
  std::vector<Input> inputs;
  Eigen::MatrixXd correlation;  // empty = uncorrelated
  void check() const;           // InputError
};

struct GufResult {
  double y = 0, u_c = 0, nu_eff = std::numeric_limits<double>::infinity(), k = 0, U = 0, p = 0.95;
  std::vector<double> c;  // sensitivity coefficients dy/dx_i
  bool correlated = false;
  Budget budget;          // contributions |c_i| u_i, sorted
};

struct McmOptions {
  double p = 0.95;
  int significant_digits = 2;  // n_dig of JCGM 101 7.9
  long batch = 0;              // 0: max(ceil(100 / (1 - p)), 10^4)
  long max_trials = 10'000'000;  // adaptive runs that do not converge stop here (converged = false)
  long fixed_trials = 0;       // > 0: exactly this many (drawn in batches), no adaptive stop
  std::uint64_t seed = 1;
  std::function<void(long done)> progress;  // called after each batch
};

struct McmResult {
  double y = 0, u = 0;
  double symmetric_low = 0, symmetric_high = 0;  // probabilistically symmetric
  double shortest_low = 0, shortest_high = 0;
  long trials = 0;
  double delta = 0;        // numerical tolerance of u to n_dig digits (JCGM 101 7.9.2)
  bool converged = false;  // the adaptive stop was reached
};

struct Validation {
  double d_low = 0, d_high = 0, delta = 0;
  bool validated = false;  // d_low, d_high <= delta (JCGM 101 8.2)
};

// Student's t quantile for a two-sided coverage p (dof may be infinite: the normal).
double coverageFactor(double p, double dof);

// Numerical tolerance of a standard uncertainty to n_dig significant digits: u = c x 10^l
// with c an n_dig-digit integer, delta = 10^l / 2 (JCGM 101 7.9.2).
double numericalTolerance(double u, int significant_digits);

Validation validate(const GufResult& g, const McmResult& m, int significant_digits = 2);

// Correlation of two outputs of the same inputs (JCGM 100 H.2.4, F.1.2.3):
// r(y_a, y_b) = c_a^T V c_b / (u(y_a) u(y_b)), V the input covariance.
double outputCorrelation(const Problem& p, const GufResult& a, const GufResult& b);

namespace detail {
[[noreturn]] void undefinedAtEstimate(const std::string& output);
std::vector<double> sampleInputs(const Problem& p, long trials, std::uint64_t seed, long offset);
McmResult summarise(std::vector<double>& y, double p);
// JCGM 101 7.9.4: twice the standard deviation of the batch means of y, u and both interval
// ends is within the numerical tolerance of u (needs >= 2 batches).
bool stable(const std::vector<McmResult>& batches, int significant_digits);
long batchSize(const McmOptions& o);
long minimumTrials(double p);          // below this the 7.7 intervals are not defined
void checkTrials(const McmOptions& o);  // p and fixed_trials: InputError
[[noreturn]] void nonFinite(const std::string& output);
}  // namespace detail

// The GUF from a model's value and gradient at the estimate (models whose number of inputs
// is known only at run time, e.g. Expression::gradient). Checks the problem.
GufResult gufFromGradient(const Problem& pr, double y, const std::vector<double>& dydx, double p = 0.95);

template <int N, class Model>
GufResult propagate(const Problem& pr, const Model& f, double p = 0.95) {
  pr.check();
  const int n = static_cast<int>(pr.inputs.size());
  if (n != N) throw std::invalid_argument("propagate<N>: N must equal the number of inputs");
  using J = ceres::Jet<double, N>;
  std::vector<J> x(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) x[static_cast<std::size_t>(i)] = J(pr.inputs[static_cast<std::size_t>(i)].value, i);
  const J y = f(x.data());
  if (!std::isfinite(y.a) || !y.v.allFinite()) detail::undefinedAtEstimate(pr.output);
  std::vector<double> grad(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) grad[static_cast<std::size_t>(i)] = y.v(i);
  return gufFromGradient(pr, y.a, grad, p);
}

template <class Model>
McmResult monteCarlo(const Problem& pr, const Model& f, const McmOptions& o = {}) {
  pr.check();
  detail::checkTrials(o);
  const std::size_t n = pr.inputs.size();
  const long batch = detail::batchSize(o);
  const long limit = o.fixed_trials > 0 ? o.fixed_trials : o.max_trials;
  std::vector<double> all;
  std::vector<McmResult> batches;
  McmResult out;
  for (long done = 0; done < limit;) {
    const long b = std::min(batch, limit - done);
    const std::vector<double> x = detail::sampleInputs(pr, b, o.seed, done);
    std::vector<double> y(static_cast<std::size_t>(b));
    for (long t = 0; t < b; ++t) {
      y[static_cast<std::size_t>(t)] = f(&x[static_cast<std::size_t>(t) * n]);
      if (!std::isfinite(y[static_cast<std::size_t>(t)])) detail::nonFinite(pr.output);
    }
    all.insert(all.end(), y.begin(), y.end());
    done += b;
    if (o.progress) o.progress(done);
    if (o.fixed_trials > 0) continue;
    batches.push_back(detail::summarise(y, o.p));
    if (detail::stable(batches, o.significant_digits)) {
      out.converged = true;
      break;
    }
  }
  const bool converged = out.converged;
  out = detail::summarise(all, o.p);
  out.converged = converged;
  out.delta = numericalTolerance(out.u, o.significant_digits);
  return out;
}

}  // namespace probeloop::uncertainty
