#include "evaluate/feature_points.hpp"

#include <cctype>
#include <cmath>

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
    s.n_stated = r.n_points;
    s.n_planned = k;
    s.form_um = r.form_um;
    const int params = n.kind == "plane" ? 3 : n.kind == "sphere" ? 4 : r.kind == "circle" ? 3 : 5;
    s.sigma_from_form_mm = sigmaFromForm(r.form_um * 1e-3, r.n_points > 0 ? r.n_points : k, params);
    s.u_um = r.u_um;
    s.point_scale = r.n_points > 0 ? std::sqrt(static_cast<double>(k) / r.n_points) : 1.0;
    out.scatter[n.id] = s;
  }
  return out;
}

}  // namespace probeloop::evaluate
