#include "evaluate/feature_points.hpp"

#include <cctype>
#include <cmath>

#include <algorithm>
#include <map>
#include <mutex>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::evaluate {

namespace {

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// Perpendicular to the axis a (unit), from the axis to p.
Eigen::Vector3d radial(const Eigen::Vector3d& p, const Eigen::Vector3d& c, const Eigen::Vector3d& a) {
  const Eigen::Vector3d d = p - c;
  return d - d.dot(a) * a;
}

}  // namespace

double expectedRangeOfNormals(int n) {
  if (n < 2) return 0;
  // Simpson's rule on [-12, 12]: the integrand is below 1e-30 beyond for any n < 1e9.
  const int steps = 4800;
  const double a = -12, h = 24.0 / steps;
  auto f = [n](double x) {
    const double P = normalCdf(x);
    return 1 - std::pow(P, n) - std::pow(1 - P, n);
  };
  double s = f(a) + f(a + steps * h);
  for (int i = 1; i < steps; ++i) s += (i % 2 ? 4 : 2) * f(a + i * h);
  return s * h / 3;
}

double rangeStdOfNormals(int n) {
  if (n < 2) return 0;
  // A few hundred thousand terms per n: each n once per process.
  static std::mutex mutex;
  static std::map<int, double> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  if (const auto it = cache.find(n); it != cache.end()) return it->second;
  // E[R^2] on a grid over [-9, 9]^2 (the integrand vanishes beyond for n < 1e7), the triangle
  // x < y by the trapezoidal rule (the diagonal, where the integrand is 1 - P^n - (1-P)^n, at
  // half weight).
  const int steps = 900;
  const double a = -9, h = 18.0 / steps;
  std::vector<double> P(steps + 1), Pn(steps + 1), Qn(steps + 1);
  for (int i = 0; i <= steps; ++i) {
    P[i] = normalCdf(a + i * h);
    Pn[i] = std::pow(P[i], n);
    Qn[i] = std::pow(1 - P[i], n);
  }
  double s = 0;
  for (int i = 0; i <= steps; ++i) {
    s += 0.5 * (1 - Pn[i] - Qn[i]);
    for (int j = i + 1; j <= steps; ++j) s += 1 - Pn[j] - Qn[i] + std::pow(P[j] - P[i], n);
  }
  const double er2 = 2 * s * h * h, d2 = expectedRangeOfNormals(n);
  return cache[n] = std::sqrt(std::max(0.0, er2 - d2 * d2));
}

double rangeDof(int n) {
  if (n < 2) return 0;
  const double r = expectedRangeOfNormals(n) / rangeStdOfNormals(n);
  return 0.5 * r * r;
}

double StatedScatter::sigmaFromStatedU_mm() const {
  if (!u_um) return NAN;
  const Eigen::Vector3d u = *u_um * 1e-3, a = direction.norm() > 0 ? Eigen::Vector3d(direction.normalized()) : Eigen::Vector3d::Zero();
  const double n = nAveraging();
  if (kind == "plane") return a.cwiseProduct(u).norm() * std::sqrt(n);
  if (kind == "sphere") return std::sqrt(u.squaredNorm() / 3) * std::sqrt(n / 3.0);
  const double across2 = std::max(0.0, u.squaredNorm() - a.cwiseProduct(u).squaredNorm());
  return std::sqrt(across2 / 2) * std::sqrt(n / 2.0);
}

std::string unmatchedText(const UnmatchedFeature& u) {
  return u.actual.file + ":" + std::to_string(u.actual.line) + ": " + u.actual.kind + " '" + u.actual.id + "' (nearest " +
         (u.nearest.empty() ? std::string("feature: none of its kind") : u.nearest + ", " + formatSignificant4(u.distance_mm) + " mm") +
         (u.why.empty() ? "" : ": " + u.why) + ")";
}

std::vector<std::string> statedScatterNotes(const std::map<std::string, StatedScatter>& s) {
  std::vector<std::string> out;
  std::string more, bare;
  for (const auto& [id, x] : s) {
    if (x.n_stated > x.n_planned) more += (more.empty() ? "" : ", ") + id + " (" + std::to_string(x.n_stated) + ")";
    if (!std::isfinite(x.form_um) && !x.u_um) bare += (bare.empty() ? "" : ", ") + id;
  }
  if (!more.empty())
    out.push_back("More points stated than planned for " + more + ": their scatter is not averaged below the planned layout's "
                  "(scanned points are correlated, and the MPE, mostly systematic, does not average down).");
  if (!bare.empty())
    out.push_back("Neither a form nor an uncertainty stated for " + bare + ": the specification alone carries their scatter, and U "
                  "may be below the point route's (a surface rougher than the MPE is invisible without its form).");
  return out;
}

double sigmaFromForm(double form_mm, int n, int p) {
  if (!std::isfinite(form_mm) || n <= p || n < 2) return NAN;
  return form_mm / (expectedRangeOfNormals(n) * std::sqrt(static_cast<double>(n - p) / n));
}

bool isLeastSquares(const std::string& algorithm) {
  std::string s;
  for (const unsigned char c : algorithm)
    if (!std::isspace(c) && c != '_' && c != '-') s += static_cast<char>(std::toupper(c));
  return s == "LEASTSQUARES" || s == "LSQ" || s == "LS";
}

std::string fittingCriterionNote(const FeatureMatch& match) {
  int ls = 0, none = 0;
  std::string others;
  for (const auto& m : match.matched) {
    const auto& a = m.actual.algorithm;
    if (a.empty()) ++none;
    else if (isLeastSquares(a)) ++ls;
    else others += (others.empty() ? "" : ", ") + m.feature->nominal.id + " (" + a + ")";
  }
  const int n = static_cast<int>(match.matched.size());
  if (none == n)
    return "The file does not say how its features were fitted: taken as least squares, the point route's criterion (a "
           "minimum-zone or Chebyshev feature differs from it by a fraction of its form).";
  std::string o = "The file states the fitting criterion of " + std::to_string(n - none) + " of its " + std::to_string(n) +
                  " features: least squares for " + std::to_string(ls) + " (the point route's criterion)";
  if (!others.empty())
    o += "; another for " + others + ": their values differ from least squares' by a fraction of their form and are taken as stated";
  if (none) o += "; " + std::to_string(none) + " state none, taken as least squares";
  return o + ".";
}

PointsOnStatedFeatures pointsOnStatedFeatures(const FeatureMatch& match,
                                              const std::map<std::string, std::vector<Eigen::Vector3d>>& planned,
                                              const std::string& file, const std::string& format) {
  PointsOnStatedFeatures out;
  out.points.file = file;
  out.points.format = format;
  out.points.route = TtpRoute::Cmm;
  out.points.assigned_by = match.assigned_by;
  for (const auto& mf : match.matched) {
    const auto& r = mf.actual;
    const auto& n = mf.feature->nominal;
    const auto it = planned.find(n.id);
    if (it == planned.end() || it->second.empty())
      throw InputError(r.file, r.line, r.kind + " '" + r.id + "' is " + n.id + ", which the plan has no points for: nothing to place "
                                       "the stated feature's points on");
    const bool round = n.kind == "cylinder" || n.kind == "sphere";
    if (round && !(r.size_mm > 0))
      throw InputError(r.file, r.line, r.kind + " '" + r.id + "' (" + n.id + ") states no diameter: a " + r.kind +
                                           " is placed at its diameter");
    const Eigen::Vector3d c = r.location_mm, a = r.direction.normalized();
    const double R = r.size_mm / 2;
    int k = 0;
    for (const auto& p : it->second) {
      Eigen::Vector3d q;
      if (n.kind == "plane") {
        q = p - (p - c).dot(a) * a;
      } else {
        const Eigen::Vector3d d = n.kind == "sphere" ? Eigen::Vector3d(p - c) : radial(p, c, a);
        if (!(d.norm() > 1e-9))
          throw InputError(r.file, r.line, r.kind + " '" + r.id + "' (" + n.id + "): planned point " + std::to_string(k + 1) +
                                               " lies on the stated " + (n.kind == "sphere" ? "centre" : "axis"));
        q = p + (R - d.norm()) * d.normalized();
      }
      TtpPoint t;
      t.feature = n.id;
      t.point = ++k;
      t.line = r.line;
      t.p_mm = q;
      out.points.points.push_back(t);
    }
    StatedScatter s;
    s.id = n.id;
    s.row = r.id + " (" + r.file + ":" + std::to_string(r.line) + ")";
    s.kind = r.kind;
    s.direction = r.direction;
    s.n_stated = r.n_points;
    s.n_planned = k;
    s.form_um = r.form_um;
    const int params = n.kind == "plane" ? 3 : n.kind == "sphere" ? 4 : r.kind == "circle" ? 3 : 5;
    s.sigma_from_form_mm = sigmaFromForm(r.form_um * 1e-3, s.nFit(), params);
    // One range's dof, but never more than the fit's residuals have (n - p).
    s.form_dof = std::isfinite(s.sigma_from_form_mm) ? std::min(rangeDof(s.nFit()), static_cast<double>(s.nFit() - params)) : 0.0;
    s.u_um = r.u_um;
    s.point_scale = std::sqrt(static_cast<double>(k) / s.nAveraging());
    out.scatter[n.id] = s;
  }
  return out;
}

}  // namespace probeloop::evaluate
