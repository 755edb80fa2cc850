// Least-squares circles (ls_detail.hpp).
// - circle2d: Taubin algebraic fit as the start (Chernov, "Circular and Linear Regression",
//   CRC 2010, ch. 5; his Newton form of CircleFitByTaubin), then Gauss-Newton /
//   Levenberg-Marquardt on the geometric distances |q - c| - r.
// - circle3d: the LS plane, then the 2D circle LS of the points projected on that plane
//   (what CMM software reports: the residuals are radial deviations in the circle's plane).
#include "geometry/ls_detail.hpp"

namespace probeloop::geometry::ls {
namespace {

// Circle in 2D on coordinates centred at the data centroid. Parameters: centre offsets
// (and the radius). r = |q - c| - r0, J = [-(q - c) / |q - c| (, -1)].
template <bool Fixed>
struct CircleModel {
  static constexpr int P = Fixed ? 2 : 3;
  struct State {
    Vector2d c = Vector2d::Zero();
    double r = 0.0;
  };
  struct Pre {
    const double* base;
    Vector2d c;
    double r;
  };
  const Points2* q;
  double size;
  double rounding;  // rounding error of one residual (mm)
  std::size_t count() const { return q->size(); }
  Pre prepare(const State& s) const { return {q->front().data(), s.c, s.r}; }
  template <class T>
  [[gnu::always_inline]] void row(const Pre& p, std::size_t i, std::array<T, P + 1>& v) const {
    const T x = gather<T>(p.base, i, 2, 0) - p.c.x();
    const T y = gather<T>(p.base, i, 2, 1) - p.c.y();
    const auto [rho, inv] = lengthAndInverse<T>(x * x + y * y);
    v[0] = -x * inv;
    v[1] = -y * inv;
    if constexpr (!Fixed) v[2] = constant<T>(-1.0);
    v[P] = rho - p.r;
  }
  State apply(const State& s, const Vec<P>& d) const {
    State t = s;
    t.c += d.template head<2>();
    if constexpr (!Fixed) t.r += d(2);
    return t;
  }
  double stepSize(const Vec<P>& d) const { return d.cwiseAbs().maxCoeff() / size; }
  bool valid(const State& s) const { return s.c.allFinite() && std::isfinite(s.r) && s.r > 0.0; }
};

struct CircleGuess {
  Vector2d c = Vector2d::Zero();
  double r = 0.0;
  bool ok = false;
};

// Taubin's algebraic circle fit, in Chernov's Newton form (Chernov 2010, section 5.10;
// MATLAB CircleFitByTaubin): moments of the centred, unit-scaled points, the smallest
// root of the characteristic cubic from 0 by Newton, then the centre.
CircleGuess taubin(const Points2& pts) {
  CircleGuess g;
  const std::size_t n = pts.size();
  Vector2d mean = Vector2d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= static_cast<double>(n);
  double spread = 0.0;
  for (const auto& p : pts) spread += (p - mean).squaredNorm();
  spread = std::sqrt(spread / static_cast<double>(n));
  if (!(spread > 0.0)) return g;
  double mxx = 0, myy = 0, mxy = 0, mxz = 0, myz = 0, mzz = 0;
  for (const auto& p : pts) {
    const double x = (p.x() - mean.x()) / spread, y = (p.y() - mean.y()) / spread;
    const double z = x * x + y * y;
    mxx += x * x, myy += y * y, mxy += x * y, mxz += x * z, myz += y * z, mzz += z * z;
  }
  const double dn = static_cast<double>(n);
  mxx /= dn, myy /= dn, mxy /= dn, mxz /= dn, myz /= dn, mzz /= dn;
  const double mz = mxx + myy;
  const double cov_xy = mxx * myy - mxy * mxy;
  const double var_z = mzz - mz * mz;
  const double a3 = 4.0 * mz;
  const double a2 = -3.0 * mz * mz - mzz;
  const double a1 = var_z * mz + 4.0 * cov_xy * mz - mxz * mxz - myz * myz;
  const double a0 = mxz * (mxz * myy - myz * mxy) + myz * (myz * mxx - mxz * mxy) - var_z * cov_xy;
  double x = 0.0, y = 1e20;
  for (int it = 0; it < 99; ++it) {
    const double yold = y;
    y = a0 + x * (a1 + x * (a2 + x * a3));
    if (std::abs(y) > std::abs(yold)) {
      x = 0.0;
      break;
    }
    const double dy = a1 + x * (2.0 * a2 + x * 3.0 * a3);
    const double xold = x;
    x = xold - y / dy;
    if (!std::isfinite(x) || x < 0.0) {
      x = 0.0;
      break;
    }
    if (std::abs(x - xold) <= 1e-12 * std::abs(x)) break;
  }
  const double det = x * x - x * mz + cov_xy;
  const Vector2d c(mxz * (myy - x) - myz * mxy, myz * (mxx - x) - mxz * mxy);
  const Vector2d centre = c / det / 2.0;
  if (!centre.allFinite() || det == 0.0) return g;
  g.c = mean + spread * centre;
  g.r = spread * std::sqrt(centre.squaredNorm() + mz);
  g.ok = std::isfinite(g.r) && g.r > 0.0;
  return g;
}

struct CircleSolution {
  Vector2d c;
  double r;
  int iterations;
  Eigen::MatrixXd cov;  // x, y (, r)
  ResidualStats stats;  // of the final pass (radial deviations)
};

std::string arcAdvice(const Points2& q, const Vector2d& c) {
  std::vector<double> ang;
  ang.reserve(q.size());
  for (const auto& p : q) ang.push_back(std::atan2(p.y() - c.y(), p.x() - c.x()));
  return "the " + degrees(angularSpan(std::move(ang))) +
         " arc is too short to determine a radius: spread the points over a longer arc or give "
         "the known radius";
}

template <bool Fixed>
CircleSolution solveCircleWith(ElementKind kind, const Points2& q, const CircleGuess& start,
                               double size, int max_iterations) {
  const double eps = std::numeric_limits<double>::epsilon();
  CircleModel<Fixed> model{&q, size, 8.0 * eps * (size + start.r)};
  typename CircleModel<Fixed>::State s{start.c, start.r};
  const auto run = polished(model, levenbergMarquardt(model, s, max_iterations), max_iterations);
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition)) {
    if (Fixed)
      fail(name(kind) + ": the centre is not determined by these points with the known radius: "
           "spread the points around the circle");
    fail(name(kind) + ": " + arcAdvice(q, run.state.c));
  }
  if (!run.converged)
    fail("least-squares " + name(kind) + " did not converge in " +
         std::to_string(max_iterations) + " iterations: raise max_iterations or check that the "
         "points outline one circle");
  return {run.state.c, run.state.r, run.iterations, inverseNormal(run.lin), statsOf(run.lin)};
}

// 2D circle LS on coordinates centred at their centroid (q has zero mean).
CircleSolution solveCircle(ElementKind kind, const Points2& q, const Vector2d& minor_axis,
                           const LeastSquaresOptions& o) {
  double s2 = 0.0;
  for (const auto& p : q) s2 += p.squaredNorm();
  s2 /= static_cast<double>(q.size());
  const double size = std::sqrt(s2);
  CircleGuess g = taubin(q);
  if (!g.ok) fail(name(kind) + ": the points lie on a straight line: " +
                  "spread them over a longer arc or give the known radius");
  if (o.fixed_radius_mm) {
    g.c = knownRadiusCentre<Vector2d>(Vector2d::Zero(), s2, g.c, *o.fixed_radius_mm, minor_axis);
    g.r = *o.fixed_radius_mm;
    return solveCircleWith<true>(kind, q, g, size, o.max_iterations);
  }
  return solveCircleWith<false>(kind, q, g, size, o.max_iterations);
}

}  // namespace

FitResult fitCircle2D(const Points3& pts, const Moments& m, const LeastSquaresOptions& o) {
  const std::size_t n = pts.size();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(m.cov.topLeftCorner<2, 2>());
  const Vector2d lam = es.eigenvalues().cwiseMax(0.0);
  if (std::sqrt(lam(1)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " circle2d points coincide in x, y (within " +
         num(kCoincidentMm) + " mm): probe points spread around the circle");
  if (std::sqrt(lam(0)) < kRankTol * std::max(std::sqrt(lam(0) + lam(1)), 1.0)) {
    const Vector2d d = es.eigenvectors().col(1);
    const double dev = maxDistanceFromLine(pts, m.centroid, Vector3d(d.x(), d.y(), 0.0), true);
    fail("circle2d needs >= 3 non-collinear points; these " + std::to_string(n) + " lie within " +
         um(dev) + " of a line: spread the points around the circle");
  }
  Points2 q(n);
  for (std::size_t i = 0; i < n; ++i) q[i] = (pts[i] - m.centroid).head<2>();
  const CircleSolution c = solveCircle(ElementKind::Circle2D, q, es.eigenvectors().col(0), o);
  Element e;
  e.kind = ElementKind::Circle2D;
  e.position_mm = Vector3d(m.centroid.x() + c.c.x(), m.centroid.y() + c.c.y(), 0.0);
  e.radius_mm = o.fixed_radius_mm ? *o.fixed_radius_mm : c.r;
  std::vector<std::string> names{"x_mm", "y_mm"};
  if (!o.fixed_radius_mm) names.push_back("r_mm");
  return makeResult(e, pts, o.fixed_radius_mm ? 2 : 3, names, c.cov, c.iterations, o, &c.stats);
}

FitResult fitCircle3D(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkPlaneDetermined(ElementKind::Circle3D, pts, m, ax);
  const std::size_t n = pts.size();
  // In-plane coordinates along the principal axes e1 = e_max, e2 = e_mid; the plane's
  // local parameters (t, alpha, beta) are defined along the same axes.
  const Vector3d nrm = ax.vec.col(0), e1 = ax.vec.col(2), e2 = ax.vec.col(1);
  Points2 q(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3d v = pts[i] - m.centroid;
    q[i] = Vector2d(e1.dot(v), e2.dot(v));
  }
  const CircleSolution c = solveCircle(ElementKind::Circle3D, q, Vector2d(0.0, 1.0), o);
  Element e;
  e.kind = ElementKind::Circle3D;
  e.position_mm = m.centroid + c.c.x() * e1 + c.c.y() * e2;
  e.direction = canonical(nrm);
  e.radius_mm = o.fixed_radius_mm ? *o.fixed_radius_mm : c.r;
  const double sign = e.direction.dot(nrm) > 0 ? 1.0 : -1.0;
  // Local parameters [t, alpha, beta | cx, cy (, r)], the plane and circle blocks
  // independent to first order (a tilt moves the projections by tilt x out-of-plane
  // deviation). Centre = centroid + t n + cx e1' + cy e2' with e1' = e1 - alpha n,
  // e2' = e2 - beta n.
  const bool fixed = o.fixed_radius_mm.has_value();
  const int pc = fixed ? 2 : 3;
  Eigen::MatrixXd local = Eigen::MatrixXd::Zero(3 + pc, 3 + pc);
  local.topLeftCorner<3, 3>() = planeLocalCovariance(ax, n).asDiagonal();
  local.bottomRightCorner(pc, pc) = c.cov;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(6 + (fixed ? 0 : 1), 3 + pc);
  g.block<3, 1>(0, 0) = nrm;
  g.block<3, 1>(0, 1) = -c.c.x() * nrm;
  g.block<3, 1>(0, 2) = -c.c.y() * nrm;
  g.block<3, 1>(0, 3) = e1;
  g.block<3, 1>(0, 4) = e2;
  g.block<3, 1>(3, 1) = sign * e1;
  g.block<3, 1>(3, 2) = sign * e2;
  if (!fixed) g(6, 5) = 1.0;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
  if (!fixed) names.push_back("r_mm");
  // The residuals are radial deviations in the plane: only the in-plane centre and the
  // radius move them to first order, hence 3 (2) free parameters for the dof.
  return makeResult(e, pts, pc, names, g * local * g.transpose(), c.iterations, o, &c.stats);
}

}  // namespace probeloop::geometry::ls
