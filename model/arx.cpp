#include "model/arx.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>

#include "core/error.hpp"

namespace probeloop::model {

int ArxOrders::maxLag() const {
  int l = na;
  for (int n : nb) l = std::max(l, n - 1 + (instantaneous ? 0 : 1));
  return l;
}

int ArxOrders::parameterCount() const {
  int p = na + (intercept ? 1 : 0);
  for (int n : nb) p += n;
  return p;
}

double ArxModel::staticGain(int input) const {
  double sa = 1, sb = 0;
  for (double v : a) sa += v;
  for (double v : b[static_cast<std::size_t>(input)]) sb += v;
  return sb / sa;
}

namespace {

std::string inputName(const std::vector<std::string>& names, int i) {
  return i < static_cast<int>(names.size()) ? names[static_cast<std::size_t>(i)] : "u" + std::to_string(i + 1);
}

void checkSeries(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& o,
                 const std::vector<std::string>& names) {
  if (u.rows() != y.size())
    throw InputError("", 0, "the output has " + std::to_string(y.size()) + " samples and the inputs " +
                                std::to_string(u.rows()) + ": the series must share one time base");
  if (static_cast<Eigen::Index>(o.nb.size()) != u.cols())
    throw InputError("", 0, "orders: " + std::to_string(o.nb.size()) + " input orders for " + std::to_string(u.cols()) + " inputs");
  if (o.na < 0) throw InputError("", 0, "orders: na must be >= 0");
  for (std::size_t i = 0; i < o.nb.size(); ++i)
    if (o.nb[i] < 1) throw InputError("", 0, "orders: input " + inputName(names, static_cast<int>(i)) + " needs >= 1 coefficient");
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    if (!std::isfinite(y(k))) throw InputError("", 0, "output sample " + std::to_string(k + 1) + " is not a finite number");
    for (Eigen::Index i = 0; i < u.cols(); ++i)
      if (!std::isfinite(u(k, i)))
        throw InputError("", 0, "input " + inputName(names, static_cast<int>(i)) + " sample " + std::to_string(k + 1) +
                                    " is not a finite number");
  }
}

// Rows k = first .. N-1 of the regression of Eq. 4.15 (with the instantaneous term and the
// intercept when asked for).
Eigen::MatrixXd regressors(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& o, int first) {
  const Eigen::Index rows = y.size() - first, p = o.parameterCount();
  Eigen::MatrixXd Phi(rows, p);
  const int d = o.instantaneous ? 0 : 1;
  for (Eigen::Index r = 0; r < rows; ++r) {
    const Eigen::Index k = first + r;
    Eigen::Index c = 0;
    for (int i = 1; i <= o.na; ++i) Phi(r, c++) = -y(k - i);
    for (std::size_t in = 0; in < o.nb.size(); ++in)
      for (int j = 0; j < o.nb[in]; ++j) Phi(r, c++) = u(k - j - d, static_cast<Eigen::Index>(in));
    if (o.intercept) Phi(r, c++) = 1.0;
  }
  return Phi;
}

std::vector<std::string> parameterNames(const ArxOrders& o, const std::vector<std::string>& names) {
  std::vector<std::string> n;
  for (int i = 1; i <= o.na; ++i) n.push_back("a" + std::to_string(i));
  const int d = o.instantaneous ? 0 : 1;
  for (std::size_t in = 0; in < o.nb.size(); ++in)
    for (int j = 0; j < o.nb[in]; ++j)
      n.push_back("b[" + inputName(names, static_cast<int>(in)) + "][lag " + std::to_string(j + d) + "]");
  if (o.intercept) n.push_back("c");
  return n;
}

struct Solved {
  Eigen::VectorXd theta;
  Eigen::MatrixXd covariance;
  double ssr = 0;
};

Solved solve(const Eigen::MatrixXd& Phi, const Eigen::VectorXd& target, const Eigen::VectorXd* w,
             const std::vector<std::string>& pnames, bool check_rank) {
  Eigen::MatrixXd A = Phi;
  Eigen::VectorXd b = target;
  if (w) {
    for (Eigen::Index r = 0; r < A.rows(); ++r) {
      const double s = std::sqrt((*w)(r));
      A.row(r) *= s;
      b(r) *= s;
    }
  }
  Eigen::VectorXd scale = A.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j)
    if (scale(j) == 0) {
      if (check_rank)
        throw GeometryError("parameter " + pnames[static_cast<std::size_t>(j)] +
                            " cannot be identified: its regressor is zero over the training span");
      scale(j) = 1;
    }
  const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(As, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  const Eigen::Index p = sv.size();
  if (check_rank && sv(p - 1) < 1e-9 * sv(0)) {
    Eigen::Index worst = 0;
    svd.matrixV().col(p - 1).cwiseAbs().maxCoeff(&worst);
    throw GeometryError("parameter " + pnames[static_cast<std::size_t>(worst)] +
                        " cannot be identified: over the training span its regressor is (nearly) a combination "
                        "of the others (condition " + std::to_string(sv(0) / std::max(sv(p - 1), 1e-300)) +
                        "); the inputs need more varied excitation or a longer span");
  }
  Solved s;
  const Eigen::VectorXd ts = svd.solve(b);
  s.theta = ts.cwiseQuotient(scale);
  const Eigen::VectorXd res = b - A * s.theta;
  s.ssr = res.squaredNorm();
  // (A^T A)^-1 = S^-1 V diag(1/sv^2) V^T S^-1 in the unscaled parameters.
  Eigen::VectorXd inv2 = sv.array().square().inverse();
  s.covariance = scale.cwiseInverse().asDiagonal() * svd.matrixV() * inv2.asDiagonal() * svd.matrixV().transpose() *
                 scale.cwiseInverse().asDiagonal();
  return s;
}

}  // namespace

ArxModel fitArx(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& o,
                const std::vector<std::string>& names, const Eigen::VectorXd* weights) {
  checkSeries(y, u, o, names);
  const int L = o.maxLag();
  const int p = o.parameterCount();
  const auto N = static_cast<int>(y.size());
  if (N - L <= p) {
    std::ostringstream m;
    m << "too few samples for these orders: " << N << " samples, the first " << L
      << " serve as history, which leaves " << std::max(0, N - L) << " equations for " << p
      << " parameters; at least " << (L + p + 1) << " samples are needed (" << (L + p + 1 - N)
      << " more), and several times that for a useful uncertainty";
    throw InputError("", 0, m.str());
  }
  for (Eigen::Index i = 0; i < u.cols(); ++i) {
    const auto col = u.col(i).tail(N - L + o.nb[static_cast<std::size_t>(i)] - 1);
    if (col.maxCoeff() == col.minCoeff())
      throw InputError("", 0, "input " + inputName(names, static_cast<int>(i)) +
                                  " is constant over the training span: its coefficients cannot be identified "
                                  "(drop it or train on a span where it changes)");
  }
  if (weights && (weights->size() != N || (weights->array() < 0).any() || !weights->allFinite()))
    throw InputError("", 0, "weights: one finite weight >= 0 per sample is needed (Eq. 4.20)");
  ArxModel m;
  m.orders = o;
  m.names = parameterNames(o, names);
  const Eigen::MatrixXd Phi = regressors(y, u, o, L);
  const Eigen::VectorXd target = y.tail(N - L);
  Eigen::VectorXd w;
  if (weights) w = weights->tail(N - L);
  const Solved s = solve(Phi, target, weights ? &w : nullptr, m.names, true);
  m.rows = N - L;
  m.theta = s.theta;
  const double sigma2 = s.ssr / (m.rows - p);
  m.sigma = std::sqrt(sigma2);
  m.covariance = sigma2 * s.covariance;
  Eigen::Index c = 0;
  for (int i = 0; i < o.na; ++i) m.a.push_back(m.theta(c++));
  for (int n : o.nb) {
    std::vector<double> bi;
    for (int j = 0; j < n; ++j) bi.push_back(m.theta(c++));
    m.b.push_back(bi);
  }
  if (o.intercept) m.c = m.theta(c++);
  return m;
}

Eigen::VectorXd simulate(const ArxModel& m, const Eigen::MatrixXd& u, const Eigen::VectorXd& initial,
                         const Eigen::VectorXd* measured) {
  const auto& o = m.orders;
  const int L = o.maxLag();
  const Eigen::Index N = u.rows();
  if (static_cast<Eigen::Index>(o.nb.size()) != u.cols())
    throw InputError("", 0, "simulate: the model has " + std::to_string(o.nb.size()) + " inputs, the data " + std::to_string(u.cols()));
  if (initial.size() < L)
    throw InputError("", 0, "simulate: " + std::to_string(L) + " initial outputs are needed (the model's longest lag)");
  if (measured && measured->size() != N) throw InputError("", 0, "simulate: measured outputs must have one entry per sample");
  if (!u.allFinite()) throw InputError("", 0, "simulate: the inputs contain a value that is not finite");
  Eigen::VectorXd pred(N), fb(N);
  const int d = o.instantaneous ? 0 : 1;
  for (Eigen::Index k = 0; k < N; ++k) {
    if (k < L) {
      pred(k) = fb(k) = initial(k);
      continue;
    }
    double v = o.intercept ? m.c : 0.0;
    for (int i = 1; i <= o.na; ++i) v -= m.a[static_cast<std::size_t>(i - 1)] * fb(k - i);
    for (std::size_t in = 0; in < o.nb.size(); ++in)
      for (int j = 0; j < o.nb[in]; ++j) v += m.b[in][static_cast<std::size_t>(j)] * u(k - j - d, static_cast<Eigen::Index>(in));
    pred(k) = v;
    fb(k) = measured && std::isfinite((*measured)(k)) ? (*measured)(k) : v;
  }
  return pred;
}

OrderSelection selectOrders(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, int max_na, int max_nb,
                            bool instantaneous, bool intercept) {
  const auto r = static_cast<int>(u.cols());
  ArxOrders probe;
  probe.na = max_na;
  probe.nb.assign(static_cast<std::size_t>(r), max_nb);
  probe.instantaneous = instantaneous;
  probe.intercept = intercept;
  checkSeries(y, u, probe, {});
  // Every candidate is scored on the same rows: those after the longest lag of any candidate.
  const int first = probe.maxLag();
  const auto N = static_cast<int>(y.size()) - first;
  if (N <= probe.parameterCount())
    throw InputError("", 0, "order selection up to na = " + std::to_string(max_na) + ", nb = " + std::to_string(max_nb) +
                                " needs more than " + std::to_string(first + probe.parameterCount()) + " samples; there are " +
                                std::to_string(y.size()));
  const Eigen::VectorXd target = y.tail(N);
  OrderSelection best;
  best.criterion = std::numeric_limits<double>::infinity();
  auto score = [&](const ArxOrders& o) {
    ++best.evaluated;
    const Eigen::MatrixXd Phi = regressors(y, u, o, first);
    const Solved s = solve(Phi, target, nullptr, parameterNames(o, {}), false);
    const double V = s.ssr / N;
    const double c = V * (1.0 + o.parameterCount() * std::log(static_cast<double>(N)) / N);  // Rissanen MDL
    if (c < best.criterion) best.criterion = c, best.best = o;
    return c;
  };
  double combos = max_na + 1;
  for (int i = 0; i < r; ++i) combos *= max_nb;
  ArxOrders o = probe;
  if (combos <= 20000) {
    std::function<void(int)> rec = [&](int i) {
      if (i == r) {
        score(o);
        return;
      }
      for (int n = 1; n <= max_nb; ++n) {
        o.nb[static_cast<std::size_t>(i)] = n;
        rec(i + 1);
      }
    };
    for (int na = 0; na <= max_na; ++na) {
      o.na = na;
      rec(0);
    }
    return best;
  }
  // Coordinate descent from the smallest model: one order at a time, until nothing improves.
  o.na = 0;
  o.nb.assign(static_cast<std::size_t>(r), 1);
  double current = score(o);
  for (bool improved = true; improved;) {
    improved = false;
    for (int which = -1; which < r; ++which) {
      const int hi = which < 0 ? max_na : max_nb, lo = which < 0 ? 0 : 1;
      for (int v = lo; v <= hi; ++v) {
        ArxOrders t = o;
        (which < 0 ? t.na : t.nb[static_cast<std::size_t>(which)]) = v;
        const double c = score(t);
        if (c < current - 1e-15 * std::fabs(current)) current = c, o = t, improved = true;
      }
    }
  }
  best.best = o;
  best.criterion = current;
  return best;
}

}  // namespace probeloop::model
