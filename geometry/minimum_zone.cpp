#include "geometry/minimum_zone.hpp"

// No CGAL header here: the parts that need CGAL are in their own translation units
// (minimum_zone_detail.hpp), each with only the headers it uses.

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <sstream>
#include <utility>

#include "core/error.hpp"
#include "geometry/least_squares.hpp"
#include "geometry/minimum_zone_detail.hpp"

// How the fits work
// -----------------
// Every fit runs in the centroid frame (data ~1000 mm from the origin with um form keep
// their digits) and ends with the same sequential linear-programming (SLP) stage:
// linearise the residuals r_i(p + d) ~ r_i + J_i d around the current element, solve
//   zone:  min hi - lo   s.t. lo <= r_i + J_i d <= hi      (minimum zone)
//   outer: min hi        s.t.       r_i + J_i d <= hi      (minimum circumscribed)
//   inner: max lo        s.t. lo <= r_i + J_i d            (maximum inscribed)
// inside a trust box |d_j| <= D exactly (CGAL QP solver, Gmpzf, on the double data), step,
// repeat; once the binding set repeats, Newton's method on the KKT conditions of that
// active set (Hald & Madsen 1981) finishes quadratically. The LP is solved by constraint
// generation: on the extreme points plus the previous binding set, adding the points the
// linearised solution violates until none does, so 1e5 points cost O(n) per round and the
// LPs stay tiny.
// Where an exact CGAL algorithm fits, it provides the start and the SLP stage certifies
// (and if need be polishes) it:
//   circle2d mz / sphere mz / sphere mi: Min_annulus_d (exact, Gmpzf) on a growing
//     subset. It minimises R^2 - r^2 (the LP form), not the zone width R - r, so the SLP
//     then polishes the width; the two optima differ by second-order terms only.
//   circle2d mc: Min_circle_2 (exact constructions). sphere mc: Min_sphere_of_spheres_d
//     (Gmpq, exact with square-root extension) on a growing subset.
//   circle2d mi: Delaunay triangulation: the largest empty circle whose centre is a local
//     maximum (Voronoi vertex inside its Delaunay triangle) and is surrounded by the
//     points.
//   line2d mz: convex hull (exact orientation predicate) + rotating calipers.
// Own SLP from a start: plane mz from PCA (the orthogonal least-squares plane; CGAL
// Width_3 is exact but takes 0.7 s at 1e4 points, so it serves as the test reference);
// line3d mz from the PCA line; cylinder mz/mi/mc from fitLeastSquares.
//
// Tolerances (S = largest distance of a point from the centroid, mm):
// - convergence: the SLP stops when the linearised LP predicts an improvement below
//   tol = 1e-13 mm + 2e-14 S in a box of at least sqrt(tol rho) (rho = curvature radius of
//   the residuals, e.g. the radius). The nonlinear fits (circle, sphere, cylinder, line3d
//   and the plane's tilt) are then first-order optimal, the zone width / radius within
//   about tol of a local optimum (global for data near the element, form << size; the
//   cylinder and line3d depend on their start for data far from the shape).
// - support points: residual within 1e-9 mm + 1e-12 S of a zone boundary / the radius.
// - alternation: a linearised problem with K unknowns (zone: geometric parameters + lo +
//   hi; MI/MC: geometric parameters + radius) has K support points at a vertex optimum,
//   i.e. k+1 for k element parameters (roundness 4, flatness 4, straightness 3,
//   sphericity 5, cylindricity 6; MC/MI circle 3, sphere 4, cylinder and line3d 5). A
//   nonlinear zone can instead have its optimum in a curved valley with one point fewer,
//   where the curvature of the distances decides (seen for cylinders), and an MC circle
//   can rest on a diametral pair. Both are accepted on the LP certificate above (no
//   first-order improvement in the certification box); a fit without it throws rather
//   than report an unverified zone.
// - MI/MC: the radius is the min/max distance over all points in double, so every point
//   is outside/inside to rounding (~1e-13 S).

namespace probeloop::geometry {
namespace mz {

std::string fmt(double v, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// Indices of the k largest and/or k smallest residuals (all of them for small n).
void addExtremes(const VectorXd& r, Goal g, int k, std::vector<int>& out) {
  const int n = static_cast<int>(r.size());
  if (n <= 4 * k) {
    for (int i = 0; i < n; ++i) out.push_back(i);
    return;
  }
  std::vector<int> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  if (g != Goal::Inner) {
    std::nth_element(idx.begin(), idx.begin() + k, idx.end(),
                     [&](int a, int b) { return r[a] > r[b]; });
    out.insert(out.end(), idx.begin(), idx.begin() + k);
  }
  if (g != Goal::Outer) {
    std::nth_element(idx.begin(), idx.begin() + k, idx.end(),
                     [&](int a, int b) { return r[a] < r[b]; });
    out.insert(out.end(), idx.begin(), idx.begin() + k);
  }
}

void dedupe(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace mz

namespace {

// The frame, the goals, the LP and the exact CGAL parts (minimum_zone_detail.hpp).
using namespace mz;

// ------------------------------------------------------------------ small helpers


std::string methodLabel(FitMethod m) {
  switch (m) {
    case FitMethod::MinimumZone: return "minimum-zone";
    case FitMethod::MaximumInscribed: return "maximum-inscribed";
    case FitMethod::MinimumCircumscribed: return "minimum-circumscribed";
    case FitMethod::LeastSquares: return "least-squares";
  }
  return "unknown";
}

// Canonical sign of a direction: largest-magnitude component positive (elements.hpp).
Vector3d canonical(const Vector3d& d) {
  Eigen::Index i = 0;
  d.cwiseAbs().maxCoeff(&i);
  return d[i] < 0.0 ? Vector3d(-d) : d;
}

Vector3d anyPerpendicular(const Vector3d& d) {
  const Vector3d a = std::abs(d.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY();
  return (a - d * d.dot(a)).normalized();
}

// Eigen decomposition of the scatter of centred points (ascending eigenvalues).
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> scatter(const Points3& q) {
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (const auto& p : q) c += p * p.transpose();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c);
}

double maxAbsDot(const Points3& q, const Vector3d& n) {
  double m = 0.0;
  for (const auto& p : q) m = std::max(m, std::abs(n.dot(p)));
  return m;
}

// ------------------------------------------------------------------ the problem


bool planar2d(ElementKind k) { return k == ElementKind::Line2D || k == ElementKind::Circle2D; }

Frame makeFrame(ElementKind kind, const Points3& points) {
  Frame f;
  const bool flat = planar2d(kind);
  Vector3d c = Vector3d::Zero();
  for (const auto& p : points) c += p;
  c /= static_cast<double>(points.size());
  if (flat) c.z() = 0.0;
  f.origin = c;
  f.q.reserve(points.size());
  double s = 0.0;
  for (const auto& p : points) {
    Vector3d v = p - c;
    if (flat) v.z() = 0.0;
    s = std::max(s, v.norm());
    f.q.push_back(v);
  }
  f.size = std::max(s, 1e-300);
  f.tol = 1e-13 + 2e-14 * f.size;
  f.support = 1e-9 + 1e-12 * f.size;
  f.noise = 1e-15 * (f.size + 1.0);
  return f;
}

// The centred problem, after rejecting degenerate input with what is wrong and what would
// fix it (same wording style as least squares).
Frame prepare(ElementKind kind, FitMethod method, const Points3& points) {
  const std::string what = methodLabel(method) + " " + std::string(elementName(kind));
  const int need = minimumPoints(kind);
  if (static_cast<int>(points.size()) < need)
    throw GeometryError(what + " needs at least " + std::to_string(need) + " points, got " +
                        std::to_string(points.size()) + "; probe more points");
  for (size_t i = 0; i < points.size(); ++i)
    if (!points[i].allFinite())
      throw GeometryError(what + ": point " + std::to_string(i) + " is not finite (" +
                          fmt(points[i].x()) + ", " + fmt(points[i].y()) + ", " +
                          fmt(points[i].z()) + "); remove or re-measure it");
  Frame f = makeFrame(kind, points);
  const std::string n = std::to_string(points.size());
  if (f.size <= 1e-12 + 1e-14 * f.origin.norm())
    throw GeometryError(what + " needs at least 2 distinct points; all " + n +
                        " points coincide" + (planar2d(kind) ? " in x, y" : ""));
  const auto eig = scatter(f.q);
  // Thickness of the point set across its best line / plane (relative to its size).
  const double rel = 1e-9;
  auto acrossLine = [&] {
    const Vector3d axis = eig.eigenvectors().col(2);
    double m = 0.0;
    for (const auto& p : f.q) m = std::max(m, (p - axis * axis.dot(p)).norm());
    return m;
  };
  switch (kind) {
    case ElementKind::Circle2D:
    case ElementKind::Plane:
    case ElementKind::Cylinder: {
      const double t = acrossLine();
      if (t <= rel * f.size)
        throw GeometryError(what + " needs at least " + std::to_string(need) +
                            " non-collinear points; these " + n + " points lie within " +
                            fmt(t) + " mm of a line. Probe points off that line.");
      if (kind == ElementKind::Cylinder) {
        const double h = maxAbsDot(f.q, eig.eigenvectors().col(0));
        if (h <= rel * f.size)
          throw GeometryError(what + " needs points that are not coplanar (more than one "
                              "section along the axis); these " + n + " points lie within " +
                              fmt(h) + " mm of a plane. Probe a second section.");
      }
      break;
    }
    case ElementKind::Sphere: {
      const double h = maxAbsDot(f.q, eig.eigenvectors().col(0));
      if (h <= rel * f.size)
        throw GeometryError(what + " needs at least 4 non-coplanar points; these " + n +
                            " points lie within " + fmt(h) + " mm of a plane. Probe points "
                            "off that plane (e.g. the pole).");
      break;
    }
    default: break;
  }
  return f;
}

void requireKind(ElementKind kind, FitMethod method, std::initializer_list<ElementKind> ok) {
  if (std::find(ok.begin(), ok.end(), kind) != ok.end()) return;
  std::string list;
  for (auto k : ok) list += (list.empty() ? "" : ", ") + std::string(elementName(k));
  throw GeometryError(methodLabel(method) + " fit of a " + std::string(elementName(kind)) +
                      " is not defined; supported kinds: " + list);
}

// ------------------------------------------------------------------ models

// Every model: int params() const; double residual(int i, double* grad) const (grad: the
// row of J, may be null); Model stepped(const VectorXd& delta) const (a retraction: the
// model moved by delta in its own chart).
template <class Model>
void evaluateAll(const Model& m, VectorXd& r, RowMatrix* J) {
  const int n = static_cast<int>(r.size());
  for (int i = 0; i < n; ++i) r[i] = m.residual(i, J ? J->row(i).data() : nullptr);
}

// Circle (D = 2) or sphere (D = 3) centre; residual = distance from the centre.
template <int D>
struct CentreModel {
  using Vec = Eigen::Matrix<double, D, 1>;
  const Points3* q = nullptr;
  Vec c = Vec::Zero();
  int params() const { return D; }
  // Length over which the linearisation error grows to the residual's size: 1/curvature.
  double curvatureRadius(const VectorXd& r) const { return r.maxCoeff(); }
  double residual(int i, double* g) const {
    const Vec v = (*q)[i].template head<D>() - c;
    const double d = v.norm();
    if (g)
      for (int k = 0; k < D; ++k) g[k] = d > 0.0 ? -v[k] / d : 0.0;
    return d;
  }
  CentreModel stepped(const VectorXd& delta) const {
    CentreModel m = *this;
    m.c += delta.head<D>();
    return m;
  }
};

// Plane through the centroid frame; residual = n . q. Parameters: tilt of n toward e1,
// e2 (times the frame size L, so they are mm at the rim).
struct PlaneModel {
  const Points3* q = nullptr;
  Vector3d n, e1, e2;
  double L = 1.0;
  PlaneModel(const Points3* pts, const Vector3d& normal, double size) : q(pts), L(size) {
    setNormal(normal.normalized(), anyPerpendicular(normal.normalized()));
  }
  void setNormal(const Vector3d& normal, const Vector3d& hint) {
    n = normal;
    e1 = (hint - n * n.dot(hint)).normalized();
    e2 = n.cross(e1);
  }
  int params() const { return 2; }
  double curvatureRadius(const VectorXd&) const { return L; }
  double residual(int i, double* g) const {
    const Vector3d& p = (*q)[i];
    if (g) g[0] = e1.dot(p) / L, g[1] = e2.dot(p) / L;
    return n.dot(p);
  }
  PlaneModel stepped(const VectorXd& d) const {
    PlaneModel m = *this;
    m.setNormal((n + (d[0] * e1 + d[1] * e2) / L).normalized(), e1);
    return m;
  }
};

// Line in the xy plane through the centroid frame; residual = left normal . q.
// Parameter: rotation angle (times L).
struct Line2Model {
  const Points3* q = nullptr;
  Vector2d d;  // unit direction
  double L = 1.0;
  Vector2d normal() const { return Vector2d(-d.y(), d.x()); }
  int params() const { return 1; }
  double curvatureRadius(const VectorXd&) const { return L; }
  double residual(int i, double* g) const {
    const Vector2d p = (*q)[i].head<2>();
    if (g) g[0] = -d.dot(p) / L;  // d(normal)/d(angle) = -d
    return normal().dot(p);
  }
  Line2Model stepped(const VectorXd& delta) const {
    Line2Model m = *this;
    const double a = delta[0] / L;
    m.d = Vector2d(std::cos(a) * d.x() - std::sin(a) * d.y(),
                   std::sin(a) * d.x() + std::cos(a) * d.y())
              .normalized();
    return m;
  }
};

// Axis (cylinder, line3d); residual = distance from the axis. p0 is the axis point
// nearest the centroid, a the unit axis, e1/e2 complete the frame. Parameters: shift of
// the axis point along e1, e2 (mm) and tilt of a toward e1, e2 (times L).
// Derivatives (v = q - p0, s = v.a, w = v - s a, u = w/|w|):
//   d|w|/d shift_k = -u.e_k,  d|w|/d tilt_k = -s (u.e_k) / L.
struct AxisModel {
  const Points3* q = nullptr;
  Vector3d p0, a, e1, e2;
  double L = 1.0;
  AxisModel(const Points3* pts, const Vector3d& point, const Vector3d& axis, double size)
      : q(pts), L(size) {
    set(point, axis.normalized(), anyPerpendicular(axis.normalized()));
  }
  void set(const Vector3d& point, const Vector3d& axis, const Vector3d& hint) {
    a = axis;
    p0 = point - a * a.dot(point);  // nearest the centroid (the frame origin)
    e1 = (hint - a * a.dot(hint)).normalized();
    e2 = a.cross(e1);
  }
  int params() const { return 4; }
  double curvatureRadius(const VectorXd& r) const { return r.maxCoeff(); }
  double residual(int i, double* g) const {
    const Vector3d v = (*q)[i] - p0;
    const double s = v.dot(a);
    const Vector3d w = v - s * a;
    const double d = w.norm();
    if (g) {
      const double u1 = d > 0.0 ? w.dot(e1) / d : 0.0;
      const double u2 = d > 0.0 ? w.dot(e2) / d : 0.0;
      g[0] = -u1;
      g[1] = -u2;
      g[2] = -s * u1 / L;
      g[3] = -s * u2 / L;
    }
    return d;
  }
  AxisModel stepped(const VectorXd& d) const {
    AxisModel m = *this;
    m.set(p0 + d[0] * e1 + d[1] * e2, (a + (d[2] * e1 + d[3] * e2) / L).normalized(), e1);
    return m;
  }
};

// ------------------------------------------------------------------ linearised LP


double objective(const VectorXd& r, Goal g) {
  switch (g) {
    case Goal::Zone: return r.maxCoeff() - r.minCoeff();
    case Goal::Outer: return r.maxCoeff();
    case Goal::Inner: return -r.minCoeff();
  }
  return 0.0;
}



struct SlpOutcome {
  int iterations = 0;
  bool converged = false;
  double objective = 0.0;
};

// Second stage of Hald & Madsen (1981, "Combined LP and quasi-Newton methods for minimax
// optimization", Math. Programming 20): once the LP stage has found the active set, solve
// the KKT conditions on it by Newton's method. This converges quadratically also where the
// optimum is not a vertex of the linearised problem (a curved valley of the objective with
// fewer than k+1 active points, common for cylinders), where the LP stage alone crawls.
// Unknowns: step t (m), hi, lo, multipliers l_i; with s_i = +1 (upper), -1 (lower):
//   sum_i s_i l_i g_i + W t = 0,  W = sum_i s_i l_i' H_i (l' = current multipliers)
//   sum_upper l_i = 1, sum_lower l_i = 1
//   r_i + g_i.t - hi = 0 (upper),  r_i + g_i.t - lo = 0 (lower)
// H_i by central second differences of r_i in the model's chart. Returns the improved
// model, or nothing when the active set is not the right one (negative multipliers, a
// singular system, or a worse objective over all points).
template <class Model>
std::optional<Model> newtonStage(const Model& start, const std::vector<int>& upper,
                                 const std::vector<int>& lower, Goal goal, double obj,
                                 double rho, const Frame& f) {
  const int m = start.params();
  std::vector<int> idx(upper);
  idx.insert(idx.end(), lower.begin(), lower.end());
  const int p = static_cast<int>(idx.size());
  const int nu = static_cast<int>(upper.size());
  const bool two = goal == Goal::Zone;
  const int nv = m + (two ? 2 : 1) + p;  // unknowns
  if (p == 0 || p > m + (two ? 2 : 1) || (two && (upper.empty() || lower.empty()))) return {};
  auto sign = [&](int k) { return k < nu ? 1.0 : -1.0; };
  // Difference step: truncation ~ (h/rho)^2, rounding ~ 1e-16 S / h^2 relative to 1/rho.
  const double h = 1e-3 * rho;
  Model model = start;
  Eigen::VectorXd lambda;  // current multipliers
  for (int iter = 0; iter < 12; ++iter) {
    RowMatrix G(p, m);
    Eigen::VectorXd r(p);
    for (int k = 0; k < p; ++k) r[k] = model.residual(idx[k], G.row(k).data());
    if (iter == 0) {  // multipliers from the stationarity conditions (least squares)
      Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m + (two ? 2 : 1), p);
      Eigen::VectorXd b = Eigen::VectorXd::Zero(A.rows());
      for (int k = 0; k < p; ++k) {
        A.col(k).head(m) = sign(k) * G.row(k).transpose();
        A(m + ((two && k >= nu) ? 1 : 0), k) = 1.0;
      }
      b.tail(two ? 2 : 1).setOnes();
      lambda = A.colPivHouseholderQr().solve(b);
      if (!lambda.allFinite() || lambda.minCoeff() <= 0.0) return {};
    }
    // Hessians of the active residuals (central differences in this chart).
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = a; b < m; ++b) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(m);
        auto at = [&](double sa, double sb) {
          e.setZero();
          e[a] += sa * h;
          e[b] += sb * h;
          const Model t = model.stepped(e);
          Eigen::VectorXd v(p);
          for (int k = 0; k < p; ++k) v[k] = t.residual(idx[k], nullptr);
          return v;
        };
        // With a == b, at(+-1, +-1) moves by 2h: the second difference with step 2h.
        const Eigen::VectorXd d2 = a == b ? Eigen::VectorXd((at(1, 1) - 2 * r + at(-1, -1)) / (4 * h * h))
                                          : Eigen::VectorXd((at(1, 1) - at(1, -1) - at(-1, 1) + at(-1, -1)) / (4 * h * h));
        double w = 0.0;
        for (int k = 0; k < p; ++k) w += sign(k) * lambda[k] * d2[k];
        W(a, b) = W(b, a) = w;
      }
    if (goal == Goal::Inner) W = -W;  // objective -lo: stationarity of -lo + sum l (lo - r)
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nv, nv);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(nv);
    const int ihi = m, ilo = two ? m + 1 : m, il = m + (two ? 2 : 1);
    K.topLeftCorner(m, m) = W;
    for (int k = 0; k < p; ++k) {
      const double sk = goal == Goal::Inner ? -1.0 : sign(k);
      K.block(0, il + k, m, 1) = sk * G.row(k).transpose();
      const int norm_row = m + ((two && k >= nu) ? 1 : 0);
      K(norm_row, il + k) = 1.0;
      const int row = il + k;
      K.block(row, 0, 1, m) = G.row(k);
      K(row, (k < nu && goal != Goal::Inner) ? ihi : ilo) = -1.0;
      rhs[row] = -r[k];
    }
    rhs.segment(m, two ? 2 : 1).setOnes();
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(K);
    if (lu.rank() < nv) return {};
    const Eigen::VectorXd z = lu.solve(rhs);
    if (!z.allFinite()) return {};
    lambda = z.tail(p);
    if (lambda.minCoeff() <= 0.0) return {};
    const Eigen::VectorXd t = z.head(m);
    model = model.stepped(t);
    if (t.cwiseAbs().maxCoeff() <= 1e-15 * f.size) break;
  }
  VectorXd all(f.q.size());
  evaluateAll(model, all, nullptr);
  if (!(objective(all, goal) < obj)) return {};
  return model;
}

// Trust-region sequential LP (stage 1) with the Newton stage above once the active set
// repeats. All parameters are in mm (angles scaled by the frame size) so one box fits all.
// Converged when the LP, in a box of at least sqrt(tol rho) (rho = curvature radius of the
// residuals: the box beyond which a remaining slope would mean more than tol to gain),
// predicts less than tol improvement.
template <class Model>
SlpOutcome runSlp(Model& model, Goal goal, const Frame& f, double box, int max_iterations) {
  const int n = static_cast<int>(f.q.size());
  const int m = model.params();
  VectorXd r(n), rt(n);
  RowMatrix J(n, m);
  evaluateAll(model, r, &J);
  double obj = objective(r, goal);
  const double box_max = 4.0 * f.size;
  const double box_min = 1e-15 * f.size;
  const double rho = std::max(model.curvatureRadius(r), 1e-9 * f.size + 1e-12);
  const double box_cert = std::sqrt(f.tol * rho);
  box = std::clamp(box, 16.0 * box_min, box_max);
  std::vector<int> keep, last_upper, last_lower;
  SlpOutcome out;
  for (int it = 0; it < max_iterations; ++it) {
    std::vector<int> active = keep;
    addExtremes(r, goal, m + 2, active);
    const LpStep step = solveLinearised(r, J, goal, box, active, f.noise);
    keep = step.upper;
    keep.insert(keep.end(), step.lower.begin(), step.lower.end());
    const double predicted = obj - step.model;
    ++out.iterations;
    if (predicted <= f.tol) {
      if (box >= box_cert) {
        out.converged = true;
        break;
      }
      box = box_cert;  // certify in a meaningful box
      continue;
    }
    if (step.upper == last_upper && step.lower == last_lower) {
      if (auto better = newtonStage(model, step.upper, step.lower, goal, obj, rho, f)) {
        model = *better;
        evaluateAll(model, r, &J);
        obj = objective(r, goal);
        box = std::max(box, box_cert);
        continue;
      }
    }
    last_upper = step.upper;
    last_lower = step.lower;
    const double len = step.delta.cwiseAbs().maxCoeff();
    Model trial = model.stepped(step.delta);
    evaluateAll(trial, rt, nullptr);
    double trial_obj = objective(rt, goal);
    const double ratio = (obj - trial_obj) / predicted;  // actual / predicted decrease
    double taken = len;  // length of the accepted step
    if (ratio < 0.25) {
      // Curvature the LP does not see: minimise the quadratic through f(0), its predicted
      // slope and f(delta) along delta instead of only shrinking the box.
      const double c = trial_obj - obj + predicted;
      if (c > 0.0) {
        const double t = std::clamp(predicted / (2.0 * c), 0.02, 0.98);
        Model mid = model.stepped(t * step.delta);
        evaluateAll(mid, rt, nullptr);
        const double mid_obj = objective(rt, goal);
        if (mid_obj < trial_obj) {
          trial = mid;
          trial_obj = mid_obj;
          taken = t * len;
        }
      }
    }
    if (trial_obj < obj) {
      model = trial;
      obj = trial_obj;
      evaluateAll(model, r, &J);
      if (ratio > 0.75 && len >= 0.9 * box) box = std::min(2.0 * box, box_max);
      else if (ratio < 0.25) box = std::max(box_min, std::min(2.0 * taken, box));
    } else {
      box = 0.25 * len;
      if (box < box_min) break;  // steps at rounding level without certificate
    }
  }
  out.objective = obj;
  return out;
}

// ------------------------------------------------------------------ exact CGAL parts

// ------------------------------------------------------------------ exact CGAL parts
// (minimum_zone_detail.hpp: each in its own translation unit)

// ------------------------------------------------------------------ starts

// The least-squares cylinder (the one LS engine, least_squares.hpp): points it cannot fit a
// cylinder to (too few, collinear, coplanar on a line...) have no minimum-zone cylinder either,
// and its GeometryError says why.
AxisModel cylinderStart(const Frame& f, const Points3& points) {
  const FitResult ls = fitLeastSquares(ElementKind::Cylinder, points);
  const Element& e = ls.element;
  if (e.kind != ElementKind::Cylinder || !e.position_mm.allFinite() || !e.direction.allFinite() || !(e.direction.norm() > 0.5))
    throw GeometryError("the least-squares cylinder that starts the minimum-zone fit has no finite axis");
  return AxisModel(&f.q, e.position_mm - f.origin, e.direction, f.size);
}

// ------------------------------------------------------------------ results

// Indices whose residual is within tol of lo or hi (the zone boundaries).
std::vector<int> supportOf(const VectorXd& r, Goal goal, double tol) {
  const double hi = r.maxCoeff(), lo = r.minCoeff();
  std::vector<int> s;
  for (int i = 0; i < r.size(); ++i)
    if ((goal != Goal::Inner && r[i] >= hi - tol) || (goal != Goal::Outer && r[i] <= lo + tol))
      s.push_back(i);
  return s;
}

// Final verification: the SLP certificate (no first-order improvement of the linearised
// problem; see the alternation note at the top). Throws when the fit did not converge.
void certify(const SlpOutcome& o, FitMethod method, ElementKind kind) {
  if (!o.converged)
    throw GeometryError(methodLabel(method) + " " + std::string(elementName(kind)) +
                        " did not converge (" + std::to_string(o.iterations) +
                        " iterations); the points are probably far from the element's shape "
                        "(check for outliers or a wrong element kind)");
}

FitResult finish(const Element& e, FitMethod method, const Points3& points, int k,
                 std::vector<int> support, int iterations) {
  FitResult res;
  res.element = e;
  res.method = method;
  res.iterations = iterations;
  fillResiduals(res, points, k);
  std::sort(support.begin(), support.end());
  res.support_points = std::move(support);
  return res;
}

// Number of free parameters reported in dof (elements.hpp order).
int freeParameters(ElementKind kind) {
  switch (kind) {
    case ElementKind::Line2D: return 2;
    case ElementKind::Line3D: return 4;
    case ElementKind::Plane: return 3;
    case ElementKind::Circle2D: return 3;
    case ElementKind::Sphere: return 4;
    case ElementKind::Cylinder: return 5;
    default: return 0;
  }
}

// Start trust box: the zone width (the optimum is within about a width of a good start in
// the mm-scaled parameters), at least a tiny fraction of the size.
double startBox(const Frame& f, double width) { return std::max(width, 1e-7 * f.size); }

// ---- circle / sphere (centre models)

template <int D>
FitResult centreFit(ElementKind kind, FitMethod method, const Points3& points, const Frame& f) {
  using Vec = Eigen::Matrix<double, D, 1>;
  CentreModel<D> model;
  model.q = &f.q;
  const Goal goal = method == FitMethod::MinimumZone ? Goal::Zone
                    : method == FitMethod::MaximumInscribed ? Goal::Inner
                                                            : Goal::Outer;
  double box = 0.0;
  if constexpr (D == 2) {
    if (method == FitMethod::MinimumCircumscribed) model.c = minCircleCentre(f);
    else if (method == FitMethod::MaximumInscribed) model.c = maxInscribedCircleCentre(f);
    else model.c = annulusCentre<2>(f);
  } else {
    model.c = method == FitMethod::MinimumCircumscribed ? minSphereCentre(f) : annulusCentre<3>(f);
  }
  {
    VectorXd r(f.q.size());
    evaluateAll(model, r, nullptr);
    // Exact starts: only a polish/certificate is expected, except MI sphere (from the
    // annulus centre) which moves by up to about the zone width.
    box = startBox(f, r.maxCoeff() - r.minCoeff());
  }
  const SlpOutcome o = runSlp(model, goal, f, box, 200);
  const Vec c = model.c;
  if (method == FitMethod::MaximumInscribed && (!o.converged || c.norm() > f.size)) {
    throw GeometryError(
        "maximum-inscribed " + std::string(elementName(kind)) +
        " is ill-defined: the points do not surround the centre (a cap or partial surface lets "
        "the inscribed sphere grow without bound). Probe points in every direction from the "
        "centre, or use the least-squares or minimum-zone sphere.");
  }
  certify(o, method, kind);
  VectorXd r(f.q.size());
  evaluateAll(model, r, nullptr);
  Element e;
  e.kind = kind;
  e.position_mm = f.origin;
  e.position_mm.template head<D>() += c;
  const double lo = r.minCoeff(), hi = r.maxCoeff();
  e.radius_mm = goal == Goal::Zone ? 0.5 * (lo + hi) : goal == Goal::Outer ? hi : lo;
  e.direction = Vector3d::UnitZ();
  return finish(e, method, points, freeParameters(kind), supportOf(r, goal, f.support), o.iterations);
}

// ---- axis models (cylinder, line3d)

FitResult axisFit(ElementKind kind, FitMethod method, const Points3& points, const Frame& f) {
  const Goal goal = kind == ElementKind::Line3D || method == FitMethod::MinimumCircumscribed
                        ? Goal::Outer
                        : method == FitMethod::MaximumInscribed ? Goal::Inner
                                                                : Goal::Zone;
  AxisModel model = kind == ElementKind::Line3D
                        ? AxisModel(&f.q, Vector3d::Zero(), scatter(f.q).eigenvectors().col(2), f.size)
                        : cylinderStart(f, points);
  VectorXd r(f.q.size());
  evaluateAll(model, r, nullptr);
  const double width = kind == ElementKind::Line3D ? r.maxCoeff() : r.maxCoeff() - r.minCoeff();
  const SlpOutcome o = runSlp(model, goal, f, startBox(f, width), 300);
  if (method == FitMethod::MaximumInscribed && (!o.converged || model.p0.norm() > f.size))
    throw GeometryError(
        "maximum-inscribed cylinder is ill-defined: the points do not surround the axis (a "
        "partial cylinder, less than half way round, lets the inscribed cylinder grow without "
        "bound). Probe all the way round, or use the least-squares or minimum-zone cylinder.");
  certify(o, method, kind);
  evaluateAll(model, r, nullptr);
  Element e;
  e.kind = kind;
  e.position_mm = f.origin + model.p0;
  e.direction = canonical(model.a);
  const double lo = r.minCoeff(), hi = r.maxCoeff();
  if (kind == ElementKind::Cylinder)
    e.radius_mm = goal == Goal::Zone ? 0.5 * (lo + hi) : goal == Goal::Outer ? hi : lo;
  return finish(e, method, points, freeParameters(kind), supportOf(r, goal, f.support), o.iterations);
}

// ---- plane and line2d (zone between two parallel planes / lines)

FitResult planeFit(const Points3& points, const Frame& f) {
  PlaneModel model(&f.q, scatter(f.q).eigenvectors().col(0), f.size);
  VectorXd r(f.q.size());
  evaluateAll(model, r, nullptr);
  const SlpOutcome o = runSlp(model, Goal::Zone, f, startBox(f, r.maxCoeff() - r.minCoeff()), 200);
  certify(o, FitMethod::MinimumZone, ElementKind::Plane);
  evaluateAll(model, r, nullptr);
  const double mid = 0.5 * (r.maxCoeff() + r.minCoeff());
  Element e;
  e.kind = ElementKind::Plane;
  e.direction = canonical(model.n);
  e.position_mm = f.origin + model.n * mid;  // foot of the centroid on the mid plane
  return finish(e, FitMethod::MinimumZone, points, 3, supportOf(r, Goal::Zone, f.support), o.iterations);
}

FitResult line2dFit(const Points3& points, const Frame& f) {
  Line2Model model;
  model.q = &f.q;
  model.L = f.size;
  model.d = minWidthDirection(f.q);
  VectorXd r(f.q.size());
  evaluateAll(model, r, nullptr);
  const SlpOutcome o = runSlp(model, Goal::Zone, f, 1e-7 * f.size, 100);  // certificate
  certify(o, FitMethod::MinimumZone, ElementKind::Line2D);
  evaluateAll(model, r, nullptr);
  const double mid = 0.5 * (r.maxCoeff() + r.minCoeff());
  Element e;
  e.kind = ElementKind::Line2D;
  e.direction = canonical(Vector3d(model.d.x(), model.d.y(), 0.0));
  e.position_mm = f.origin + Vector3d(model.normal().x(), model.normal().y(), 0.0) * mid;
  return finish(e, FitMethod::MinimumZone, points, 2, supportOf(r, Goal::Zone, f.support), o.iterations);
}

}  // namespace

FitResult fitMinimumZone(ElementKind kind, const Points3& points) {
  const FitMethod method = FitMethod::MinimumZone;
  requireKind(kind, method,
              {ElementKind::Line2D, ElementKind::Line3D, ElementKind::Plane, ElementKind::Circle2D,
               ElementKind::Sphere, ElementKind::Cylinder});
  const Frame f = prepare(kind, method, points);
  switch (kind) {
    case ElementKind::Line2D: return line2dFit(points, f);
    case ElementKind::Plane: return planeFit(points, f);
    case ElementKind::Circle2D: return centreFit<2>(kind, method, points, f);
    case ElementKind::Sphere: return centreFit<3>(kind, method, points, f);
    default: return axisFit(kind, method, points, f);
  }
}

FitResult fitMaximumInscribed(ElementKind kind, const Points3& points) {
  const FitMethod method = FitMethod::MaximumInscribed;
  requireKind(kind, method, {ElementKind::Circle2D, ElementKind::Sphere, ElementKind::Cylinder});
  const Frame f = prepare(kind, method, points);
  if (kind == ElementKind::Circle2D) return centreFit<2>(kind, method, points, f);
  if (kind == ElementKind::Sphere) return centreFit<3>(kind, method, points, f);
  return axisFit(kind, method, points, f);
}

FitResult fitMinimumCircumscribed(ElementKind kind, const Points3& points) {
  const FitMethod method = FitMethod::MinimumCircumscribed;
  requireKind(kind, method, {ElementKind::Circle2D, ElementKind::Sphere, ElementKind::Cylinder});
  const Frame f = prepare(kind, method, points);
  if (kind == ElementKind::Circle2D) return centreFit<2>(kind, method, points, f);
  if (kind == ElementKind::Sphere) return centreFit<3>(kind, method, points, f);
  return axisFit(kind, method, points, f);
}

}  // namespace probeloop::geometry
