#include "model/regression_family.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::model {

namespace {

const Family kAll[] = {Family::Polynomial, Family::SaturatingExponential, Family::Gompertz, Family::LogLogistic,
                       Family::Hill,       Family::Hyperbolic,            Family::Weibull,  Family::Power};

std::string num(double v) { return formatNumber(v); }

// How many of a family's parameters enter linearly; they come first in parameterNames().
int linearCount(Family f, int parameters) {
  switch (f) {
    case Family::Polynomial: return parameters;
    case Family::SaturatingExponential:
    case Family::LogLogistic:
    case Family::Weibull: return 2;
    default: return 1;
  }
}

// Forms with x^p (written exp(p ln x) by the thesis) need x >= 0.
bool needsNonNegativeX(Family f) {
  return f == Family::LogLogistic || f == Family::Hill || f == Family::Weibull || f == Family::Power;
}

// (x/x0)^p and x^p by continuity at x = 0; false where undefined (x0 <= 0, x < 0, or x = 0 with p <= 0).
bool powerOf(double x, double p, double& out) {
  if (x < 0) return false;
  if (x == 0) {
    if (p <= 0) return false;
    out = 0;
    return true;
  }
  out = std::exp(p * std::log(x));
  return std::isfinite(out);
}

// The linear basis g_j(x; nonlinear) of a family: f = sum_j lin_j g_j. Also the value when the
// full parameter vector is given. false where the form is undefined.
bool basis(Family f, double x, const double* nl, double* g) {
  switch (f) {
    case Family::SaturatingExponential: {  // a - b exp(-c x)
      g[0] = 1;
      g[1] = -std::exp(-nl[0] * x);
      return std::isfinite(g[1]);
    }
    case Family::Gompertz: {  // a exp(-exp(b - c x))
      g[0] = std::exp(-std::exp(nl[0] - nl[1] * x));
      return std::isfinite(g[0]);
    }
    case Family::LogLogistic:
    case Family::Hill: {  // a - b/(1 + (x/x0)^p); Hill: b = a
      const double p = nl[0], x0 = nl[1];
      double u = 0;
      if (!(x0 > 0) || !powerOf(x / x0, p, u)) return false;
      if (f == Family::Hill) {
        g[0] = u / (1 + u);  // a - a/(1+u) = a u/(1+u)
      } else {
        g[0] = 1;
        g[1] = -1 / (1 + u);
      }
      return true;
    }
    case Family::Hyperbolic: {  // a x/(b + x)
      const double d = nl[0] + x;
      if (d == 0) return false;
      g[0] = x / d;
      return std::isfinite(g[0]);
    }
    case Family::Weibull: {  // a + b exp(-k x^p)
      double w = 0;
      if (!powerOf(x, nl[1], w)) return false;
      g[0] = 1;
      g[1] = std::exp(-nl[0] * w);
      return std::isfinite(g[1]);
    }
    case Family::Power: {  // a x^p
      return powerOf(x, nl[0], g[0]);
    }
    case Family::Polynomial: break;
  }
  return false;
}

bool value(Family f, const std::vector<double>& p, double x, double& out) {
  if (f == Family::Polynomial) {
    out = 0;
    for (std::size_t k = p.size(); k-- > 0;) out = out * x + p[k];  // Horner
    return std::isfinite(out);
  }
  const int L = linearCount(f, static_cast<int>(p.size()));
  double g[2];
  if (!basis(f, x, p.data() + L, g)) return false;
  out = 0;
  for (int j = 0; j < L; ++j) out += p[j] * g[j];
  return std::isfinite(out);
}

// d f / d p_j, analytic. Only called where value() succeeded.
void gradient(Family f, const std::vector<double>& p, double x, double* d) {
  switch (f) {
    case Family::Polynomial: {
      double xk = 1;
      for (std::size_t k = 0; k < p.size(); ++k, xk *= x) d[k] = xk;
      return;
    }
    case Family::SaturatingExponential: {
      const double e = std::exp(-p[2] * x);
      d[0] = 1, d[1] = -e, d[2] = p[1] * x * e;
      return;
    }
    case Family::Gompertz: {
      const double g = std::exp(p[1] - p[2] * x), E = std::exp(-g);
      d[0] = E, d[1] = -p[0] * E * g, d[2] = p[0] * E * g * x;
      return;
    }
    case Family::LogLogistic:
    case Family::Hill: {
      const bool hill = f == Family::Hill;
      const double b = hill ? p[0] : p[1], pp = p[hill ? 1 : 2], x0 = p[hill ? 2 : 3];
      double u = 0, lnr = 0;
      powerOf(x / x0, pp, u);
      if (x > 0) lnr = std::log(x / x0);
      const double q = b / ((1 + u) * (1 + u));  // d/du of -b/(1+u)
      const double dp = q * u * lnr, dx0 = q * u * (-pp / x0);
      if (hill) {
        d[0] = u / (1 + u), d[1] = dp, d[2] = dx0;
      } else {
        d[0] = 1, d[1] = -1 / (1 + u), d[2] = dp, d[3] = dx0;
      }
      return;
    }
    case Family::Hyperbolic: {
      const double den = p[1] + x;
      d[0] = x / den, d[1] = -p[0] * x / (den * den);
      return;
    }
    case Family::Weibull: {
      double w = 0;
      powerOf(x, p[3], w);
      const double E = std::exp(-p[2] * w), lnx = x > 0 ? std::log(x) : 0;
      d[0] = 1, d[1] = E, d[2] = -p[1] * w * E, d[3] = -p[1] * p[2] * w * lnx * E;
      return;
    }
    case Family::Power: {
      double w = 0;
      powerOf(x, p[1], w);
      d[0] = w, d[1] = p[0] * w * (x > 0 ? std::log(x) : 0);
      return;
    }
  }
}

// The grid of starting values of the nonlinear parameters, scaled to the data.
std::vector<std::vector<double>> startGrid(Family f, const std::vector<double>& x) {
  double xs = 0, xpos = std::numeric_limits<double>::infinity();
  for (double v : x) {
    xs = std::max(xs, std::abs(v));
    if (v > 0) xpos = std::min(xpos, v);
  }
  if (xs == 0) xs = 1;
  if (!std::isfinite(xpos)) xpos = xs;
  auto logspace = [](double lo, double hi, int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(lo * std::pow(hi / lo, n > 1 ? i / double(n - 1) : 0.0));
    return v;
  };
  std::vector<std::vector<double>> g;
  switch (f) {
    case Family::SaturatingExponential:
      for (double c : logspace(1e-3 / xs, 1e2 / xs, 80)) g.push_back({c});
      for (double c : logspace(1e-3 / xs, 5 / xs, 30)) g.push_back({-c});  // growing exponential
      break;
    case Family::Gompertz:
      for (double c : logspace(1e-2 / xs, 1e2 / xs, 30))
        for (int i = 0; i <= 30; ++i) g.push_back({-3 + 0.5 * i, c});
      break;
    case Family::LogLogistic:
    case Family::Hill:
      for (double p : {0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0})
        for (double x0 : logspace(xpos / 3, 3 * xs, 30)) g.push_back({p, x0});
      break;
    case Family::Hyperbolic:
      for (double b : logspace(1e-3 * xs, 1e3 * xs, 60)) g.push_back({b});
      break;
    case Family::Weibull:
      for (double p : {0.3, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0})
        for (double t : logspace(1e-2, 1e2, 30)) g.push_back({t / std::pow(xs, p), p});
      break;
    case Family::Power:
      for (int i = 1; i <= 80; ++i) g.push_back({0.05 * i});
      if (xpos == *std::min_element(x.begin(), x.end()))  // all x > 0: negative powers too
        for (int i = 1; i <= 60; ++i) g.push_back({-0.05 * i});
      break;
    case Family::Polynomial: break;
  }
  return g;
}

[[noreturn]] void refuse(const Candidate& c, const std::string& why) {
  throw GeometryError(c.label() + " fit: " + why);
}

struct Jacobian {
  Eigen::MatrixXd J;  // n x P
  Eigen::VectorXd r;  // f - y
};

bool residuals(Family f, const std::vector<double>& p, const std::vector<double>& x, const std::vector<double>& y,
               Eigen::VectorXd& r) {
  r.resize(static_cast<Eigen::Index>(x.size()));
  for (std::size_t i = 0; i < x.size(); ++i) {
    double v = 0;
    if (!value(f, p, x[i], v)) return false;
    r[static_cast<Eigen::Index>(i)] = v - y[i];
  }
  return true;
}

Eigen::MatrixXd jacobian(Family f, const std::vector<double>& p, const std::vector<double>& x) {
  Eigen::MatrixXd J(static_cast<Eigen::Index>(x.size()), static_cast<Eigen::Index>(p.size()));
  std::vector<double> d(p.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    gradient(f, p, x[i], d.data());
    for (std::size_t j = 0; j < p.size(); ++j) J(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = d[j];
  }
  return J;
}

// Identifiability and covariance from J (columns scaled to unit norm first, so the condition
// number compares parameters of very different sizes fairly).
void finish(FamilyFit& out, const Candidate& c, const Eigen::MatrixXd& J, const std::vector<std::string>& names) {
  const Eigen::Index P = J.cols();
  Eigen::VectorXd norm(P);
  for (Eigen::Index j = 0; j < P; ++j) {
    norm[j] = J.col(j).norm();
    if (!(norm[j] > 0) || !std::isfinite(norm[j]))
      refuse(c, "parameter " + names[static_cast<std::size_t>(j)] + " does not change the prediction at these points; it cannot be identified");
  }
  const Eigen::MatrixXd Js = J * norm.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const auto s = svd.singularValues();
  const double cond = s[0] / s[P - 1];
  if (!(cond < 1e10))
    refuse(c, "the parameters cannot be separated from these " + std::to_string(J.rows()) +
                  " points (condition number " + num(cond) + "); use fewer parameters or more spread in x");
  out.u.clear();
  if (out.dof > 0) {
    const Eigen::MatrixXd V = svd.matrixV();
    for (Eigen::Index j = 0; j < P; ++j) {
      double var = 0;
      for (Eigen::Index k = 0; k < P; ++k) var += V(j, k) * V(j, k) / (s[k] * s[k]);
      out.u.push_back(out.sigma * std::sqrt(var) / norm[j]);
    }
  }
}

}  // namespace

const char* familyName(Family f) {
  switch (f) {
    case Family::Polynomial: return "polynomial";
    case Family::SaturatingExponential: return "saturating_exponential";
    case Family::Gompertz: return "gompertz";
    case Family::LogLogistic: return "log_logistic";
    case Family::Hill: return "hill";
    case Family::Hyperbolic: return "hyperbolic";
    case Family::Weibull: return "weibull";
    case Family::Power: return "power";
  }
  return "?";
}

std::optional<Family> familyFromName(const std::string& name) {
  for (Family f : kAll)
    if (name == familyName(f)) return f;
  return std::nullopt;
}

std::vector<std::string> familyNames() {
  std::vector<std::string> v;
  for (Family f : kAll) v.push_back(familyName(f));
  return v;
}

std::vector<std::string> parameterNames(Family f, int degree) {
  switch (f) {
    case Family::Polynomial: {
      std::vector<std::string> v;
      for (int k = 0; k <= degree; ++k) v.push_back("c" + std::to_string(k));
      return v;
    }
    case Family::SaturatingExponential:
    case Family::Gompertz: return {"a", "b", "c"};
    case Family::LogLogistic: return {"a", "b", "p", "x0"};
    case Family::Hill: return {"a", "p", "x0"};
    case Family::Hyperbolic: return {"a", "b"};
    case Family::Weibull: return {"a", "b", "k", "p"};
    case Family::Power: return {"a", "p"};
  }
  return {};
}

double RegressionFunction::evaluate(double x) const {
  const auto expected = parameterNames(family, degree()).size();
  if (p.size() != expected || p.empty())
    throw GeometryError(std::string(familyName(family)) + ": " + std::to_string(p.size()) + " parameters given, " +
                        std::to_string(expected) + " expected");
  if (!std::isfinite(x)) throw GeometryError(formula() + ": the input is not a finite number");
  if (x < 0 && needsNonNegativeX(family))
    throw GeometryError(formula() + ": x = " + num(x) + " is negative; this form has x^p (the thesis's exp(p ln x)) and needs x >= 0");
  double v = 0;
  if (!value(family, p, x, v))
    throw GeometryError(formula() + ": not defined at x = " + num(x) + " (a zero denominator, x0 <= 0, 0^p with p <= 0 or an overflow)");
  return v;
}

std::string RegressionFunction::formula() const {
  auto P = [&](std::size_t i) { return i < p.size() ? num(p[i]) : std::string("?"); };
  switch (family) {
    case Family::Polynomial: {
      std::string s;
      for (std::size_t k = 0; k < p.size(); ++k) {
        if (!s.empty()) s += " + ";
        s += num(p[k]) + (k == 0 ? "" : k == 1 ? "*x" : "*x^" + std::to_string(k));
      }
      return s.empty() ? "0" : s;
    }
    case Family::SaturatingExponential: return P(0) + " - " + P(1) + "*exp(-" + P(2) + "*x)";
    case Family::Gompertz: return P(0) + "*exp(-exp(" + P(1) + " - " + P(2) + "*x))";
    case Family::LogLogistic: return P(0) + " - " + P(1) + "/(1 + exp(" + P(2) + "*ln(x/" + P(3) + ")))";
    case Family::Hill: return P(0) + " - " + P(0) + "/(1 + exp(" + P(1) + "*ln(x/" + P(2) + ")))";
    case Family::Hyperbolic: return P(0) + "*x/(" + P(1) + " + x)";
    case Family::Weibull: return P(0) + " + " + P(1) + "*exp(-" + P(2) + "*x^" + P(3) + ")";
    case Family::Power: return P(0) + "*x^" + P(1);
  }
  return "?";
}

std::string Candidate::label() const {
  if (family != Family::Polynomial) return familyName(family);
  return "polynomial(" + std::to_string(degree) + (through_origin ? ", through 0" : "") + ")";
}

FamilyFit fit(const Candidate& c, const std::vector<double>& x, const std::vector<double>& y) {
  const bool poly = c.family == Family::Polynomial;
  if (poly && c.degree < 0) refuse(c, "a negative degree");
  const auto names = parameterNames(c.family, c.degree);
  const int P = static_cast<int>(names.size()) - (poly && c.through_origin ? 1 : 0);
  const int n = static_cast<int>(x.size());
  if (x.size() != y.size())
    refuse(c, std::to_string(x.size()) + " x values and " + std::to_string(y.size()) + " y values");
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i]))
      refuse(c, "point " + std::to_string(i + 1) + " is not a finite number");
    if (x[i] < 0 && needsNonNegativeX(c.family))
      refuse(c, "x = " + num(x[i]) + " at point " + std::to_string(i + 1) +
                    " is negative; this form has x^p (the thesis's exp(p ln x)) and needs x >= 0");
  }
  if (n < P)
    refuse(c, std::to_string(n) + " points for " + std::to_string(P) + " parameters; at least " + std::to_string(P) +
                  " are needed (and " + std::to_string(P + 1) + " for an uncertainty)");

  FamilyFit out;
  out.names = names;
  out.n = n;
  out.parameters = P;
  out.dof = n - P;
  out.function.family = c.family;
  Eigen::Map<const Eigen::VectorXd> Y(y.data(), n);

  if (poly) {
    // Linear: QR on column-scaled powers of x (x up to 1600 mm/min makes x^3 ~ 4e9).
    const int first = c.through_origin ? 1 : 0;
    Eigen::MatrixXd X(n, P);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < P; ++j) X(i, j) = std::pow(x[i], first + j);
    Eigen::VectorXd norm(P);
    for (int j = 0; j < P; ++j) norm[j] = X.col(j).norm() > 0 ? X.col(j).norm() : 1;
    const Eigen::MatrixXd Xs = X * norm.cwiseInverse().asDiagonal();
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Xs);
    if (qr.rank() < P)
      refuse(c, "the " + std::to_string(n) + " points have too few distinct x values for degree " + std::to_string(c.degree));
    const Eigen::VectorXd th = qr.solve(Y).cwiseQuotient(norm);
    out.function.p.assign(static_cast<std::size_t>(c.degree + 1), 0.0);
    for (int j = 0; j < P; ++j) out.function.p[static_cast<std::size_t>(first + j)] = th[j];
    out.ssr = (X * th - Y).squaredNorm();
    out.sigma = out.dof > 0 ? std::sqrt(out.ssr / out.dof) : 0;
    std::vector<std::string> free(names.begin() + first, names.end());
    finish(out, c, X, free);
    if (c.through_origin && !out.u.empty()) out.u.insert(out.u.begin(), 0.0);  // c0 fixed
    return out;
  }

  // Nonlinear: variable-projection grid start, then Levenberg-Marquardt on all parameters.
  const int L = linearCount(c.family, P);
  std::vector<double> best;
  double best_ssr = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd B(n, L);
  for (const auto& nl : startGrid(c.family, x)) {
    bool ok = true;
    double g[2];
    for (int i = 0; i < n && ok; ++i) {
      ok = basis(c.family, x[i], nl.data(), g);
      for (int j = 0; j < L && ok; ++j) B(i, j) = g[j];
    }
    if (!ok) continue;
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(B);
    if (qr.rank() < L) continue;
    const Eigen::VectorXd lin = qr.solve(Y);
    const double s = (B * lin - Y).squaredNorm();
    if (std::isfinite(s) && s < best_ssr) {
      best_ssr = s;
      best.assign(lin.data(), lin.data() + L);
      best.insert(best.end(), nl.begin(), nl.end());
    }
  }
  if (best.empty()) refuse(c, "no starting point gives a finite prediction at every x");

  std::vector<double> th = best;
  Eigen::VectorXd r;
  residuals(c.family, th, x, y, r);
  double ssr = r.squaredNorm();
  const double scale = Y.squaredNorm() + 1e-300;
  double lambda = 1e-3;
  int it = 0;
  bool converged = false;
  for (; it < 500 && !converged; ++it) {
    if (ssr <= 1e-28 * scale) {
      converged = true;
      break;
    }
    const Eigen::MatrixXd J = jacobian(c.family, th, x);
    const Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    Eigen::VectorXd D = A.diagonal();
    for (Eigen::Index j = 0; j < D.size(); ++j) D[j] = D[j] > 0 ? D[j] : 1e-300;
    bool accepted = false;
    while (!accepted) {
      Eigen::MatrixXd M = A;
      M.diagonal() += lambda * D;
      const Eigen::VectorXd step = M.ldlt().solve(-g);
      std::vector<double> trial(th);
      for (int j = 0; j < P; ++j) trial[static_cast<std::size_t>(j)] += step[j];
      Eigen::VectorXd rt;
      if (step.allFinite() && residuals(c.family, trial, x, y, rt) && rt.squaredNorm() < ssr) {
        const double drop = ssr - rt.squaredNorm();
        double rel = 0;
        for (int j = 0; j < P; ++j)
          rel = std::max(rel, std::abs(step[j]) / (std::abs(th[static_cast<std::size_t>(j)]) + 1e-300));
        th = trial, r = rt, ssr = rt.squaredNorm();
        lambda = std::max(lambda / 10, 1e-12);
        accepted = true;
        if (rel < 1e-11 || drop <= 1e-15 * ssr) converged = true;
      } else {
        lambda *= 10;
        // No step along the scaled gradient lowers the sum: a minimum to working precision.
        if (lambda > 1e16) {
          converged = true;
          break;
        }
      }
    }
  }
  if (!converged)
    refuse(c, "Levenberg-Marquardt did not converge in " + std::to_string(it) + " iterations (sum of squares " + num(ssr) + ")");
  out.function.p = th;
  out.iterations = it;
  out.ssr = ssr;
  out.sigma = out.dof > 0 ? std::sqrt(ssr / out.dof) : 0;
  finish(out, c, jacobian(c.family, th, x), names);
  return out;
}

BackwardPrediction backwardPrediction(const std::vector<double>& x, const std::vector<double>& measured,
                                      const std::vector<double>& predicted) {
  if (x.size() != measured.size() || x.size() != predicted.size() || x.empty())
    throw GeometryError("backward prediction: " + std::to_string(x.size()) + " x, " + std::to_string(measured.size()) +
                        " measured and " + std::to_string(predicted.size()) + " predicted values; equal non-zero counts are needed");
  BackwardPrediction b;
  int in5 = 0, in10 = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!std::isfinite(measured[i]) || !std::isfinite(predicted[i]))
      throw GeometryError("backward prediction: point " + std::to_string(i + 1) + " is not a finite number");
    BackwardPoint p;
    p.x = x[i], p.measured = measured[i], p.predicted = predicted[i];
    p.diff = std::abs(predicted[i] - measured[i]);
    if (measured[i] != 0) {
      p.has_percent = true;
      p.percent = 100 * p.diff / std::abs(measured[i]);
      ++b.with_percent;
      in5 += p.percent < 5;
      in10 += p.percent < 10;
    }
    b.sum_abs_diff += p.diff;
    b.points.push_back(p);
  }
  if (b.with_percent > 0) {
    b.share_within_5 = double(in5) / b.with_percent;
    b.share_within_10 = double(in10) / b.with_percent;
    b.meets_thesis_criteria = b.share_within_5 > 0.8 && in10 == b.with_percent;
  }
  return b;
}

Selection selectByBackwardPrediction(const std::vector<double>& x, const std::vector<double>& y,
                                     const std::vector<Candidate>& candidates) {
  Selection s;
  for (const auto& c : candidates) {
    CandidateReport rep;
    rep.candidate = c;
    try {
      rep.fit = fit(c, x, y);
      rep.fitted = true;
    } catch (const GeometryError& e) {
      rep.refusal = e.what();
      s.candidates.push_back(rep);
      continue;
    }
    std::vector<double> pred;
    for (double v : x) pred.push_back(rep.fit.function.evaluate(v));
    rep.backward = backwardPrediction(x, y, pred);
    // Leave-one-out: each point predicted by the fit to the others.
    double sum2 = 0;
    rep.has_loo = true;
    for (std::size_t i = 0; i < x.size() && rep.has_loo; ++i) {
      std::vector<double> xs, ys;
      for (std::size_t j = 0; j < x.size(); ++j)
        if (j != i) xs.push_back(x[j]), ys.push_back(y[j]);
      try {
        const double e = fit(c, xs, ys).function.evaluate(x[i]) - y[i];
        sum2 += e * e;
      } catch (const GeometryError& e) {
        rep.has_loo = false;
        rep.refusal = "leave-one-out without point " + std::to_string(i + 1) + ": " + e.what();
      }
    }
    if (rep.has_loo) rep.loo_rms = std::sqrt(sum2 / double(x.size()));
    s.candidates.push_back(rep);
  }
  for (std::size_t i = 0; i < s.candidates.size(); ++i) {
    const auto& r = s.candidates[i];
    if (!r.has_loo) continue;
    if (s.best < 0) {
      s.best = static_cast<int>(i);
      continue;
    }
    const auto& b = s.candidates[static_cast<std::size_t>(s.best)];
    // Equal within rounding: the simpler candidate.
    const double tol = 1e-12 * std::max(r.loo_rms, b.loo_rms);
    if (r.loo_rms < b.loo_rms - tol || (std::abs(r.loo_rms - b.loo_rms) <= tol && r.fit.parameters < b.fit.parameters))
      s.best = static_cast<int>(i);
  }
  if (s.best < 0) {
    s.sentence = "no candidate could be ranked: each needs a fit to every subset of " + std::to_string(x.size() - 1) + " points";
    return s;
  }
  const auto& b = s.candidates[static_cast<std::size_t>(s.best)];
  s.sentence = b.candidate.label() + " predicts the left-out points best (leave-one-out RMS " + num(b.loo_rms) + " over " +
               std::to_string(x.size()) + " points); on its own points the sum of |diff| is " + num(b.backward.sum_abs_diff) +
               ", " + std::to_string(static_cast<int>(std::lround(b.backward.share_within_5 * b.backward.with_percent))) + " of " +
               std::to_string(b.backward.with_percent) + " points within 5 % and " +
               std::to_string(static_cast<int>(std::lround(b.backward.share_within_10 * b.backward.with_percent))) +
               " within 10 % (the thesis's criteria, L1798, are " + (b.backward.meets_thesis_criteria ? "met" : "not met") + ")";
  return s;
}

}  // namespace probeloop::model
