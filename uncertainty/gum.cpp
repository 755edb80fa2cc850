#include "uncertainty/gum.hpp"

#include <algorithm>
#include <functional>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <iomanip>
#include <boost/random/normal_distribution.hpp>
#include <boost/random/student_t_distribution.hpp>
#include <boost/random/uniform_01.hpp>
#include <random>
#include <sstream>

#include "core/error.hpp"

namespace probeloop::uncertainty {

const char* distributionName(Distribution d) {
  switch (d) {
    case Distribution::Normal: return "normal";
    case Distribution::Rectangular: return "rectangular";
    case Distribution::Triangular: return "triangular";
    case Distribution::UShaped: return "U-shaped";
    case Distribution::StudentT: return "Student t";
  }
  return "?";
}

Input Input::normal(std::string name, double value, double u, double dof) {
  Input i;
  i.name = std::move(name);
  i.value = value;
  i.u = u;
  i.dof = dof;
  i.type = std::isfinite(dof) ? 'A' : 'B';
  return i;
}

namespace {
Input bounded(std::string name, double value, double a, Distribution d, double divisor) {
  Input i;
  i.name = std::move(name);
  i.value = value;
  i.half_width = a;
  i.u = a / std::sqrt(divisor);
  i.distribution = d;
  return i;
}
}  // namespace

Input Input::rectangular(std::string name, double value, double a) {
  return bounded(std::move(name), value, a, Distribution::Rectangular, 3.0);
}
Input Input::triangular(std::string name, double value, double a) {
  return bounded(std::move(name), value, a, Distribution::Triangular, 6.0);
}
Input Input::uShaped(std::string name, double value, double a) {
  return bounded(std::move(name), value, a, Distribution::UShaped, 2.0);
}
Input Input::studentT(std::string name, double mean, double s, double dof) {
  Input i;
  i.name = std::move(name);
  i.value = mean;
  i.scale = s;
  i.dof = dof;
  i.type = 'A';
  i.distribution = Distribution::StudentT;
  i.u = dof > 2 ? s * std::sqrt(dof / (dof - 2)) : std::numeric_limits<double>::infinity();
  return i;
}

void Problem::check() const {
  if (inputs.empty()) throw InputError("", 0, output + ": a measurement model needs at least one input");
  for (const auto& in : inputs) {
    if (!std::isfinite(in.value)) throw InputError("", 0, in.name + ": the estimate must be a finite number");
    if (!(in.u >= 0) || !std::isfinite(in.u))
      throw InputError("", 0, in.name + ": the standard uncertainty must be finite and >= 0 (found " + std::to_string(in.u) +
                                  (in.distribution == Distribution::StudentT ? "; a Student t needs dof > 2" : "") + ")");
    if (!(in.dof > 0)) throw InputError("", 0, in.name + ": degrees of freedom must be positive");
  }
  if (correlation.size() == 0) return;
  const auto n = static_cast<Eigen::Index>(inputs.size());
  if (correlation.rows() != n || correlation.cols() != n)
    throw InputError("", 0, "the correlation matrix must be " + std::to_string(n) + " x " + std::to_string(n));
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      const double r = correlation(i, j);
      if (i == j && std::fabs(r - 1) > 1e-12) throw InputError("", 0, "the correlation matrix needs 1 on its diagonal");
      if (std::fabs(r - correlation(j, i)) > 1e-12 || !(std::fabs(r) <= 1))
        throw InputError("", 0, "correlation r(" + inputs[static_cast<std::size_t>(i)].name + ", " +
                                    inputs[static_cast<std::size_t>(j)].name + ") must be symmetric and within [-1, 1]");
    }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(correlation);
  if (es.eigenvalues().minCoeff() < -1e-10)
    throw InputError("", 0, "the correlation matrix is not positive semidefinite (smallest eigenvalue " +
                                std::to_string(es.eigenvalues().minCoeff()) + "): the correlations contradict each other");
}

double coverageFactor(double p, double dof) {
  if (!(p > 0 && p < 1)) throw InputError("", 0, "coverage probability must be in (0, 1)");
  const double q = 0.5 + p / 2;
  if (!std::isfinite(dof)) return boost::math::quantile(boost::math::normal(), q);
  return boost::math::quantile(boost::math::students_t(dof), q);
}

double numericalTolerance(double u, int nd) {
  if (!(u > 0) || !std::isfinite(u)) return 0;
  // u = c x 10^l with c an n_dig-digit integer: round first (0.0997 -> 0.10 -> l = -2).
  int l = static_cast<int>(std::floor(std::log10(u))) - (nd - 1);
  if (std::llround(u / std::pow(10.0, l)) >= static_cast<long long>(std::pow(10.0, nd))) ++l;
  return 0.5 * std::pow(10.0, l);
}

Validation validate(const GufResult& g, const McmResult& m, int nd) {
  Validation v;
  v.delta = numericalTolerance(g.u_c > 0 ? g.u_c : m.u, nd);
  v.d_low = std::fabs(g.y - g.U - m.symmetric_low);
  v.d_high = std::fabs(g.y + g.U - m.symmetric_high);
  v.validated = v.d_low <= v.delta && v.d_high <= v.delta;
  return v;
}

double outputCorrelation(const Problem& p, const GufResult& a, const GufResult& b) {
  const auto n = static_cast<Eigen::Index>(p.inputs.size());
  if (static_cast<Eigen::Index>(a.c.size()) != n || static_cast<Eigen::Index>(b.c.size()) != n)
    throw std::invalid_argument("outputCorrelation: both results must come from this problem's inputs");
  Eigen::VectorXd ca(n), cb(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double u = p.inputs[static_cast<std::size_t>(i)].gufU();
    ca(i) = a.c[static_cast<std::size_t>(i)] * u;
    cb(i) = b.c[static_cast<std::size_t>(i)] * u;
  }
  const double cov = p.correlation.size() ? ca.dot(p.correlation * cb) : ca.dot(cb);
  if (!(a.u_c > 0 && b.u_c > 0)) return 0.0;
  return cov / (a.u_c * b.u_c);
}

GufResult gufFromGradient(const Problem& pr, double y, const std::vector<double>& dydx, double p) {
  pr.check();
  bool finite = std::isfinite(y);
  for (double d : dydx) finite = finite && std::isfinite(d);
  if (!finite) detail::undefinedAtEstimate(pr.output);
  const auto n = static_cast<Eigen::Index>(pr.inputs.size());
  GufResult r;
  r.y = y;
  r.p = p;
  r.correlated = pr.correlation.size() > 0;
  Eigen::VectorXd cu(n);
  std::vector<Contribution> contributions;
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto& in = pr.inputs[static_cast<std::size_t>(i)];
    const double c_i = dydx[static_cast<std::size_t>(i)];
    r.c.push_back(c_i);
    cu(i) = c_i * in.gufU();
    Contribution c;
    c.input = in.name;
    c.type = in.type;
    c.distribution = distributionName(in.distribution);
    std::ostringstream basis;
    basis << "c = " << std::setprecision(6) << c_i;
    c.basis = basis.str();
    c.u = std::fabs(cu(i));
    c.dof = in.dof;
    contributions.push_back(c);
  }
  const double u2 = r.correlated ? cu.dot(pr.correlation * cu) : cu.squaredNorm();
  r.budget = combine(pr.output, pr.unit, r.y, contributions);
  r.u_c = std::sqrt(std::max(0.0, u2));
  r.budget.u_c = r.u_c;
  // Welch-Satterthwaite (G.2b) over independent groups: inputs linked by correlations form
  // one group, whose contribution is c_g^T V_g c_g and whose dof is the smallest of its
  // members (n - 1 for inputs observed together, Willink 2007); without this G.2b collapses
  // when u_c is smaller than single contributions (JCGM 100 H.2: nu_eff(R) = 0.12).
  // Written with (u_g / u_c)^4 so that neither 1e-90 nor 1e80 over- or underflows.
  std::vector<int> group(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) group[static_cast<std::size_t>(i)] = static_cast<int>(i);
  if (r.correlated) {
    std::function<int(int)> root = [&](int i) { return group[static_cast<std::size_t>(i)] == i ? i : root(group[static_cast<std::size_t>(i)]); };
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = i + 1; j < n; ++j)
        if (pr.correlation(i, j) != 0) group[static_cast<std::size_t>(root(static_cast<int>(j)))] = root(static_cast<int>(i));
    for (Eigen::Index i = 0; i < n; ++i) group[static_cast<std::size_t>(i)] = root(static_cast<int>(i));
  }
  double ws = 0;
  if (r.u_c > 0)
    for (Eigen::Index g = 0; g < n; ++g) {
      double var = 0, dof = std::numeric_limits<double>::infinity();
      bool any = false;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (group[static_cast<std::size_t>(i)] != g) continue;
        any = true;
        if (cu(i) != 0) dof = std::min(dof, pr.inputs[static_cast<std::size_t>(i)].dof);
        for (Eigen::Index j = 0; j < n; ++j)
          if (group[static_cast<std::size_t>(j)] == g)
            var += cu(i) * cu(j) * (r.correlated ? pr.correlation(i, j) : (i == j ? 1.0 : 0.0));
      }
      if (!any || !std::isfinite(dof) || var <= 0) continue;
      const double ratio = std::sqrt(var) / r.u_c;
      ws += ratio * ratio * ratio * ratio / dof;
    }
  r.nu_eff = ws > 0 ? 1.0 / ws : std::numeric_limits<double>::infinity();
  r.budget.nu_eff = r.nu_eff;
  r.k = coverageFactor(p, std::isfinite(r.nu_eff) ? std::max(1.0, std::floor(r.nu_eff)) : r.nu_eff);  // G.6.4
  r.U = r.k * r.u_c;
  r.budget.k = r.k;
  r.budget.U = r.U;
  return r;
}

namespace detail {

void undefinedAtEstimate(const std::string& output) {
  throw GeometryError(output + ": the model or its derivative is not defined (not finite) at the estimate; "
                               "the law of propagation does not apply here");
}

std::vector<double> sampleInputs(const Problem& p, long trials, std::uint64_t seed, long offset) {
  const std::size_t n = p.inputs.size();
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(offset) + 1);
  // Boost's normal is a ziggurat (several times faster than the polar method of libstdc++);
  // with 1e6 trials of 32 inputs the draws dominate the Monte Carlo time.
  boost::random::normal_distribution<double> N(0.0, 1.0);
  boost::random::uniform_01<double> U;
  // Inputs linked by a correlation are drawn jointly (multivariate normal, JCGM 101 6.4.8);
  // the others by their own distributions.
  std::vector<std::size_t> joint;
  if (p.correlation.size() > 0)
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < n; ++j)
        if (i != j && p.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) != 0) {
          joint.push_back(i);
          break;
        }
  std::vector<bool> in_joint(n, false);
  for (std::size_t i : joint) in_joint[i] = true;
  Eigen::MatrixXd L;
  if (!joint.empty()) {
    for (std::size_t i : joint)
      if (p.inputs[i].distribution != Distribution::Normal)
        throw InputError("", 0, p.inputs[i].name + ": correlated inputs must be normal for the Monte Carlo method (JCGM 101 6.4.8); "
                                "give it distribution: normal (for observations: distribution: normal)");
    const auto k = static_cast<Eigen::Index>(joint.size());
    Eigen::MatrixXd R(k, k);
    for (Eigen::Index a = 0; a < k; ++a)
      for (Eigen::Index b = 0; b < k; ++b)
        R(a, b) = p.correlation(static_cast<Eigen::Index>(joint[static_cast<std::size_t>(a)]), static_cast<Eigen::Index>(joint[static_cast<std::size_t>(b)]));
    // Positive semidefinite: LDLT, then L sqrt(D).
    Eigen::LDLT<Eigen::MatrixXd> ldlt(R);
    const Eigen::MatrixXd Lm = ldlt.matrixL();
    const Eigen::MatrixXd PtL = ldlt.transpositionsP().transpose() * Lm;  // R = PtL D PtL^T
    L = PtL * ldlt.vectorD().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  }
  std::vector<double> x(static_cast<std::size_t>(trials) * n);
  Eigen::VectorXd z(static_cast<Eigen::Index>(joint.size()));
  for (long t = 0; t < trials; ++t) {
    double* row = &x[static_cast<std::size_t>(t) * n];
    if (!joint.empty()) {
      for (Eigen::Index a = 0; a < z.size(); ++a) z(a) = N(rng);
      const Eigen::VectorXd w = L * z;
      for (std::size_t a = 0; a < joint.size(); ++a)
        row[joint[a]] = p.inputs[joint[a]].value + p.inputs[joint[a]].u * w(static_cast<Eigen::Index>(a));
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (in_joint[i]) continue;
      const Input& in = p.inputs[i];
      switch (in.distribution) {
        case Distribution::Normal: row[i] = in.value + in.u * N(rng); break;
        case Distribution::Rectangular: row[i] = in.value + in.half_width * (2 * U(rng) - 1); break;
        case Distribution::Triangular: row[i] = in.value + in.half_width * (U(rng) + U(rng) - 1); break;
        case Distribution::UShaped: row[i] = in.value + in.half_width * std::sin(2 * M_PI * U(rng)); break;
        case Distribution::StudentT: {
          // Boost's, not std's: the same draws with every standard library.
          boost::random::student_t_distribution<double> T(in.dof);
          row[i] = in.value + in.scale * T(rng);
          break;
        }
      }
    }
  }
  return x;
}

long minimumTrials(double p) { return std::max(100L, static_cast<long>(std::ceil(10.0 / (1.0 - p)))); }

void checkTrials(const McmOptions& o) {
  if (!(o.p > 0.5 && o.p <= 0.9999))
    throw InputError("", 0, "coverage probability " + std::to_string(o.p) + ": the Monte Carlo method here takes p in (0.5, 0.9999]");
  if (o.fixed_trials > 0 && o.fixed_trials < minimumTrials(o.p))
    throw InputError("", 0, std::to_string(o.fixed_trials) + " trials are too few for p = " + std::to_string(o.p) +
                                ": at least " + std::to_string(minimumTrials(o.p)) + " (JCGM 101 7.2.2 recommends 10^4/(1 - p))");
}

void nonFinite(const std::string& output) {
  throw GeometryError(output + ": a Monte Carlo trial gave a value that is not finite: the model is not defined over the "
                               "whole range of its inputs' distributions (e.g. a division by, sqrt or log of a quantity "
                               "that can reach 0)");
}

long batchSize(const McmOptions& o) {
  if (o.fixed_trials > 0) return std::min(o.fixed_trials, 100'000L);  // bounded memory per draw
  return o.batch > 0 ? o.batch : std::max(10'000L, static_cast<long>(std::ceil(100.0 / (1.0 - o.p))));
}

bool stable(const std::vector<McmResult>& batches, int nd) {
  if (batches.size() < 2) return false;
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
  const double delta = numericalTolerance(u_mean / h, nd);
  return 2 * spread([](const McmResult& b) { return b.y; }) <= delta &&
         2 * spread([](const McmResult& b) { return b.u; }) <= delta &&
         2 * spread([](const McmResult& b) { return b.symmetric_low; }) <= delta &&
         2 * spread([](const McmResult& b) { return b.symmetric_high; }) <= delta;
}

McmResult summarise(std::vector<double>& y, double p) {
  McmResult r;
  const auto M = static_cast<long>(y.size());
  if (M < 2) throw InputError("", 0, "a Monte Carlo summary needs at least 2 trials");
  r.trials = M;
  double mean = 0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(M);
  double ss = 0;
  for (double v : y) ss += (v - mean) * (v - mean);
  r.y = mean;
  r.u = M > 1 ? std::sqrt(ss / static_cast<double>(M - 1)) : 0.0;
  std::sort(y.begin(), y.end());
  // JCGM 101 7.7: q = pM rounded; the symmetric interval is [y_(r), y_(r+q)] (1-based) with
  // r = (M - q)/2 for M - q even and (M - q + 1)/2 otherwise, i.e. r = floor((M - q + 1)/2).
  // Callers guarantee M >= minimumTrials(p), so 1 <= r and r + q <= M.
  const long q = std::max(1L, std::min(M - 1, static_cast<long>(std::llround(p * static_cast<double>(M)))));
  const long r1 = std::max(1L, (M - q + 1) / 2);
  r.symmetric_low = y[static_cast<std::size_t>(r1 - 1)];
  r.symmetric_high = y[static_cast<std::size_t>(std::min(M - 1, r1 - 1 + q))];
  long best = 0;
  for (long k = 0; k + q < M; ++k)
    if (y[static_cast<std::size_t>(k + q)] - y[static_cast<std::size_t>(k)] <
        y[static_cast<std::size_t>(best + q)] - y[static_cast<std::size_t>(best)])
      best = k;
  r.shortest_low = y[static_cast<std::size_t>(best)];
  r.shortest_high = y[static_cast<std::size_t>(best + q)];
  return r;
}

}  // namespace detail

}  // namespace probeloop::uncertainty
