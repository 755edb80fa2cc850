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
//   contributions |c_i| u_i (with correlated inputs this is the usual approximation, and the
//   result says so); k from Student's t at floor(nu_eff) (G.6.4) for the coverage p. A
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
  long max_trials = 100'000'000;
  long fixed_trials = 0;       // > 0: exactly this many, no adaptive stop
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
}  // namespace detail

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
  GufResult r;
  r.y = y.a;
  r.p = p;
  r.correlated = pr.correlation.size() > 0;
  Eigen::VectorXd cu(n);
  std::vector<Contribution> contributions;
  for (int i = 0; i < n; ++i) {
    const auto& in = pr.inputs[static_cast<std::size_t>(i)];
    r.c.push_back(y.v(i));
    cu(i) = y.v(i) * in.gufU();
    Contribution c;
    c.input = in.name;
    c.type = in.type;
    c.distribution = distributionName(in.distribution);
    c.basis = "c = " + std::to_string(y.v(i));
    c.u = std::fabs(cu(i));
    c.dof = in.dof;
    contributions.push_back(c);
  }
  const double u2 = r.correlated ? cu.dot(pr.correlation * cu) : cu.squaredNorm();
  r.budget = combine(pr.output, pr.unit, r.y, contributions);
  r.u_c = std::sqrt(std::max(0.0, u2));
  r.budget.u_c = r.u_c;
  double ws = 0;
  for (const auto& c : r.budget.contributions)
    if (std::isfinite(c.dof) && c.u > 0) ws += std::pow(c.u, 4) / c.dof;
  r.nu_eff = ws > 0 ? std::pow(r.u_c, 4) / ws : std::numeric_limits<double>::infinity();
  r.budget.nu_eff = r.nu_eff;
  r.k = coverageFactor(p, std::isfinite(r.nu_eff) ? std::max(1.0, std::floor(r.nu_eff)) : r.nu_eff);
  r.U = r.k * r.u_c;
  r.budget.k = r.k;
  r.budget.U = r.U;
  return r;
}

template <class Model>
McmResult monteCarlo(const Problem& pr, const Model& f, const McmOptions& o = {}) {
  pr.check();
  const std::size_t n = pr.inputs.size();
  const long batch = o.fixed_trials > 0 ? o.fixed_trials
                                        : (o.batch > 0 ? o.batch : std::max(10'000L, static_cast<long>(std::ceil(100.0 / (1.0 - o.p)))));
  std::vector<double> all;
  std::vector<McmResult> batches;
  McmResult out;
  for (long done = 0; done < o.max_trials;) {
    const std::vector<double> x = detail::sampleInputs(pr, batch, o.seed, done);
    std::vector<double> y(static_cast<std::size_t>(batch));
    for (long t = 0; t < batch; ++t) y[static_cast<std::size_t>(t)] = f(&x[static_cast<std::size_t>(t) * n]);
    all.insert(all.end(), y.begin(), y.end());
    batches.push_back(detail::summarise(y, o.p));
    done += batch;
    if (o.progress) o.progress(done);
    if (o.fixed_trials > 0) break;
    if (batches.size() < 2) continue;
    // JCGM 101 7.9.4: the standard deviations of the batch results, over sqrt(h).
    const double h = static_cast<double>(batches.size());
    auto spread = [&](auto get) {
      double m = 0, s = 0;
      for (const auto& b : batches) m += get(b);
      m /= h;
      for (const auto& b : batches) s += (get(b) - m) * (get(b) - m);
      return std::sqrt(s / (h - 1) / h);
    };
    double u_mean = 0;
    for (const auto& b : batches) u_mean += b.u;
    const double delta = numericalTolerance(u_mean / h, o.significant_digits);
    if (2 * spread([](const McmResult& b) { return b.y; }) <= delta &&
        2 * spread([](const McmResult& b) { return b.u; }) <= delta &&
        2 * spread([](const McmResult& b) { return b.symmetric_low; }) <= delta &&
        2 * spread([](const McmResult& b) { return b.symmetric_high; }) <= delta) {
      out.converged = true;
      break;
    }
  }
  for (double v : all)
    if (!std::isfinite(v)) detail::undefinedAtEstimate(pr.output + " (a Monte Carlo trial)");
  const bool converged = out.converged;
  out = detail::summarise(all, o.p);
  out.converged = converged;
  out.delta = numericalTolerance(out.u, o.significant_digits);
  return out;
}

}  // namespace probeloop::uncertainty
