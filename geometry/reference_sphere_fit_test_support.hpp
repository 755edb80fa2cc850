// A least-squares sphere fit independent of the LS engine (least_squares.hpp), kept for the
// tests that check the engine against a second implementation (least_squares_degenerate_test,
// minimum_zone_test). Test support only: it was the sphere-artifact evaluation's own fit until
// issue 29 made geometry::fitSphere an adapter over the one engine. Kasa start, then
// Gauss-Newton with Levenberg-Marquardt damping on the orthogonal distances, relative to the
// centroid; the same contract as sphere_fit.hpp.
#pragma once
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "geometry/sphere_fit.hpp"

namespace probeloop::geometry {

namespace reference_detail {

inline std::string um(double mm) {
  std::ostringstream s;
  s.precision(3);
  s << mm * 1000.0 << " um";
  return s.str();
}

inline void checkInput(const std::vector<Eigen::Vector3d>& p) {
  if (p.size() < 4) {
    throw GeometryError("sphere needs >= 4 non-coplanar points; got " +
                        std::to_string(p.size()) + ": probe more points on the sphere");
  }
  for (size_t i = 0; i < p.size(); ++i) {
    if (!p[i].allFinite())
      throw GeometryError("sphere point " + std::to_string(i + 1) + " is not finite (NaN or inf)");
  }
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j)
      if ((p[i] - p[j]).norm() < 1e-9)
        throw GeometryError("sphere points " + std::to_string(i + 1) + " and " +
                            std::to_string(j + 1) + " coincide; remove the duplicate");
}

}  // namespace reference_detail

inline SphereFit referenceSphereFit(const std::vector<Eigen::Vector3d>& pts, const SphereFitOptions& opt = {}) {
  using namespace reference_detail;
  checkInput(pts);
  const int n = static_cast<int>(pts.size());
  // Work relative to the centroid: data 1000 mm from the origin with um noise would lose
  // digits in the algebraic normal equations otherwise.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : pts) centroid += p;
  centroid /= n;
  Eigen::MatrixXd q(n, 3);
  for (int i = 0; i < n; ++i) q.row(i) = (pts[i] - centroid).transpose();
  const double extent = q.rowwise().norm().maxCoeff();

  // Coplanarity: smallest singular value of the centred cloud = RMS distance to the best
  // plane times sqrt(n).
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(q, Eigen::ComputeThinV);
  const double plane_rms = svd.singularValues()(2) / std::sqrt(static_cast<double>(n));
  if (plane_rms < 1e-7 * std::max(extent, 1.0)) {
    const double max_dev = (q * svd.matrixV().col(2)).cwiseAbs().maxCoeff();
    throw GeometryError("sphere needs >= 4 non-coplanar points; these " + std::to_string(n) +
                        " lie within " + um(max_dev) +
                        " of a plane: add a point off that plane (e.g. the top of the sphere)");
  }

  // Algebraic start (Kasa): |q|^2 = 2 c.q + k, linear in (c, k).
  Eigen::MatrixXd A(n, 4);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    A.row(i) << 2.0 * q(i, 0), 2.0 * q(i, 1), 2.0 * q(i, 2), 1.0;
    b(i) = q.row(i).squaredNorm();
  }
  const Eigen::Vector4d alg = A.colPivHouseholderQr().solve(b);
  Eigen::Vector3d c = alg.head<3>();
  double r = std::sqrt(std::max(alg(3) + c.squaredNorm(), 0.0));
  const bool fixed = opt.fixed_radius_mm.has_value();
  if (fixed) {
    if (!(*opt.fixed_radius_mm > 0.0) || !std::isfinite(*opt.fixed_radius_mm))
      throw GeometryError("known sphere radius must be a positive number");
    r = *opt.fixed_radius_mm;
  }
  if (!c.allFinite() || !(r > 0.0)) {
    throw GeometryError("sphere start values are undefined: the points do not outline a sphere");
  }

  // Gauss-Newton with Levenberg-Marquardt damping on orthogonal distances.
  const int np = fixed ? 3 : 4;
  Eigen::MatrixXd J(n, np);
  Eigen::VectorXd res(n);
  auto evaluate = [&](const Eigen::Vector3d& cc, double rr) {
    double ssr = 0.0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d d = q.row(i).transpose() - cc;
      const double dist = d.norm();
      if (dist == 0.0) throw GeometryError("a point coincides with the sphere centre estimate");
      res(i) = dist - rr;
      J.block(i, 0, 1, 3) = -(d / dist).transpose();
      if (!fixed) J(i, 3) = -1.0;
      ssr += res(i) * res(i);
    }
    return ssr;
  };
  double ssr = evaluate(c, r);
  double lambda = 1e-6;
  int it = 0;
  for (; it < opt.max_iterations; ++it) {
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * res;
    bool improved = false;
    Eigen::VectorXd step;
    for (int tries = 0; tries < 30; ++tries) {
      Eigen::MatrixXd H = JtJ;
      H.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
      step = H.ldlt().solve(-g);
      Eigen::Vector3d c2 = c + step.head<3>();
      double r2 = fixed ? r : r + step(3);
      Eigen::MatrixXd Jsave = J;
      Eigen::VectorXd rsave = res;
      const double ssr2 = evaluate(c2, r2);
      if (ssr2 <= ssr) {
        c = c2;
        r = r2;
        ssr = ssr2;
        lambda = std::max(lambda * 0.1, 1e-12);
        improved = true;
        break;
      }
      J = Jsave;
      res = rsave;
      lambda *= 10.0;
    }
    if (!improved || step.norm() < 1e-14 * std::max(extent, 1.0)) break;
  }
  if (!fixed && !(r > 0.0)) throw GeometryError("sphere fit did not converge to a positive radius");

  SphereFit out;
  out.centre_mm = c + centroid;
  out.radius_mm = r;
  out.radius_fixed = fixed;
  out.iterations = it;
  out.residuals_mm.assign(res.data(), res.data() + n);
  out.rms_mm = std::sqrt(ssr / n);
  const auto [mn, mx] = std::minmax_element(out.residuals_mm.begin(), out.residuals_mm.end());
  out.form_mm = *mx - *mn;
  out.dof = n - np;
  out.residual_variance_mm2 = out.dof > 0 ? ssr / out.dof : 0.0;

  const Eigen::MatrixXd JtJ = J.transpose() * J;
  Eigen::JacobiSVD<Eigen::MatrixXd> s(JtJ);
  const double cond = s.singularValues()(0) / s.singularValues()(np - 1);
  if (!std::isfinite(cond) || cond > 1e14) {
    throw GeometryError(
        "sphere parameters are not determined by these points (the cap is too small to fix the "
        "radius): spread the points wider or use the known radius");
  }
  out.covariance_unscaled.setZero();
  out.covariance_unscaled.topLeftCorner(np, np) = JtJ.inverse();
  return out;
}

}  // namespace probeloop::geometry
