#include "uncertainty/gum.hpp"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <iomanip>
#include <boost/random/normal_distribution.hpp>
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
  if (!(u > 0)) return 0;
  const int l = static_cast<int>(std::floor(std::log10(u))) - (nd - 1);
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
  double ws = 0;
  for (const auto& c : r.budget.contributions)
    if (std::isfinite(c.dof) && c.u > 0) ws += std::pow(c.u, 4) / c.dof;
  r.nu_eff = ws > 0 ? std::pow(r.u_c, 4) / ws : std::numeric_limits<double>::infinity();  // G.2b
  if (r.correlated) {
    // With correlated inputs u_c can be smaller than single contributions and G.2b collapses
    // (JCGM 100 H.2: nu_eff of R would be 0.12). The usual case is inputs observed together
    // (n simultaneous observations), for which nu = n - 1 (Willink 2007): nu_eff is not
    // allowed below the smallest dof of the correlated inputs that contribute.
    double floor_dof = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < n; ++i) {
      bool correlated_i = false;
      for (Eigen::Index j = 0; j < n; ++j) correlated_i = correlated_i || (i != j && pr.correlation(i, j) != 0);
      if (correlated_i && cu(i) != 0) floor_dof = std::min(floor_dof, pr.inputs[static_cast<std::size_t>(i)].dof);
    }
    if (std::isfinite(floor_dof)) r.nu_eff = std::max(r.nu_eff, floor_dof);
  }
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
  const bool corr = p.correlation.size() > 0;
  Eigen::MatrixXd L;
  if (corr) {
    for (const auto& in : p.inputs)
      if (in.distribution != Distribution::Normal)
        throw InputError("", 0, in.name + ": correlated inputs must be normal for the Monte Carlo method (JCGM 101 6.4.8)");
    // Positive semidefinite: LDLT, then L sqrt(D).
    Eigen::LDLT<Eigen::MatrixXd> ldlt(p.correlation);
    const Eigen::MatrixXd Lm = ldlt.matrixL();
    const Eigen::MatrixXd PtL = ldlt.transpositionsP().transpose() * Lm;  // A = PtL D PtL^T
    L = PtL * ldlt.vectorD().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  }
  std::vector<double> x(static_cast<std::size_t>(trials) * n);
  Eigen::VectorXd z(static_cast<Eigen::Index>(n));
  for (long t = 0; t < trials; ++t) {
    double* row = &x[static_cast<std::size_t>(t) * n];
    if (corr) {
      for (std::size_t i = 0; i < n; ++i) z(static_cast<Eigen::Index>(i)) = N(rng);
      const Eigen::VectorXd w = L * z;
      for (std::size_t i = 0; i < n; ++i) row[i] = p.inputs[i].value + p.inputs[i].u * w(static_cast<Eigen::Index>(i));
      continue;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Input& in = p.inputs[i];
      switch (in.distribution) {
        case Distribution::Normal: row[i] = in.value + in.u * N(rng); break;
        case Distribution::Rectangular: row[i] = in.value + in.half_width * (2 * U(rng) - 1); break;
        case Distribution::Triangular: row[i] = in.value + in.half_width * (U(rng) + U(rng) - 1); break;
        case Distribution::UShaped: row[i] = in.value + in.half_width * std::sin(2 * M_PI * U(rng)); break;
        case Distribution::StudentT: {
          std::chi_squared_distribution<double> chi(in.dof);
          row[i] = in.value + in.scale * N(rng) / std::sqrt(chi(rng) / in.dof);
          break;
        }
      }
    }
  }
  return x;
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
  r.trials = M;
  double mean = 0;
  for (double v : y) mean += v;
  mean /= static_cast<double>(M);
  double ss = 0;
  for (double v : y) ss += (v - mean) * (v - mean);
  r.y = mean;
  r.u = M > 1 ? std::sqrt(ss / static_cast<double>(M - 1)) : 0.0;
  std::sort(y.begin(), y.end());
  // JCGM 101 7.7: q = pM (rounded), r = (M - q) / 2 for the symmetric interval.
  const long q = std::max(1L, std::min(M - 1, static_cast<long>(std::llround(p * static_cast<double>(M)))));
  const long rs = std::max(0L, (M - q) / 2);
  r.symmetric_low = y[static_cast<std::size_t>(rs)];
  r.symmetric_high = y[static_cast<std::size_t>(std::min(M - 1, rs + q))];
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
