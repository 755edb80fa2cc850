// Least-squares cylinders and cones (ls_detail.hpp): geometric Gauss-Newton /
// Levenberg-Marquardt in a local frame re-centred every iteration (Forbes DITC 140/89
// section 6; Shakarji 1998): rotate so the current axis is z, translate so the axis point
// (foot of the data centroid) is the origin; the parameters are the axis offsets x0, y0, the
// tilts a, b of the axis direction (a, b, 1), the radius there (and the half angle psi for
// the cone). Starts: options.start if given; otherwise the three principal axes and the
// best directions of a hemisphere grid scored by an algebraic fit for that direction, each
// refined on a subsample, keeping the lowest sum of squares.
//
// Shared by ls_cylinder.cpp and ls_cone.cpp (one translation unit each, compiled in
// parallel); the non-template parts are in ls_axis.cpp.
#pragma once

#include <optional>

#include "geometry/ls_detail.hpp"

namespace probeloop::geometry::ls {


// Axis state shared by cylinder and cone: axis point o (the foot of the data centroid),
// frame u (rows e1, e2, e3 = axis direction), radius at o, half angle (cone; may be
// negative while iterating: the axis then points toward decreasing radius).
struct AxisState {
  Vector3d o = Vector3d::Zero();
  Matrix3d u = Matrix3d::Identity();
  double r = 0.0;
  double psi = 0.0;
};

// Moves the axis point to the foot of `centroid`; for a cone the radius follows the taper.
AxisState recentred(const Vector3d& o, const Vector3d& dir, double r, double psi,
                    const Vector3d& centroid);

// Point i (or i..i + 3) in the frame of the current axis: q = U (p - o), its distance rho from
// the axis and the unit radial direction (cx, cy) = (q0, q1) / rho. Shared by both models'
// rows, so that the cylinder and the cone see the same digits.
template <class T>
struct RadialCoordinates {
  T q0, q1, q2, rho, cx, cy;
};
template <class T>
[[gnu::always_inline]] inline RadialCoordinates<T> radialCoordinates(const double* base, std::size_t i, const Matrix3d& u,
                                              const Vector3d& o) {
  const T dx = gather<T>(base, i, 3, 0) - o.x();
  const T dy = gather<T>(base, i, 3, 1) - o.y();
  const T dz = gather<T>(base, i, 3, 2) - o.z();
  const T q0 = u(0, 0) * dx + u(0, 1) * dy + u(0, 2) * dz;
  const T q1 = u(1, 0) * dx + u(1, 1) * dy + u(1, 2) * dz;
  const T q2 = u(2, 0) * dx + u(2, 1) * dy + u(2, 2) * dz;
  const auto [rho, inv] = lengthAndInverse<T>(q0 * q0 + q1 * q1);
  return {q0, q1, q2, rho, q0 * inv, q1 * inv};
}

// Whether two states' frames are the same up to a small turn (the chord passes reuse J^T J
// only then): frameOf turns e1, e2 by 90 degrees or more when the axis crosses the xy plane.
inline bool axisFramesAgree(const AxisState& a, const AxisState& b) {
  return a.u.row(0).dot(b.u.row(0)) > 0.999 && a.u.row(1).dot(b.u.row(1)) > 0.999;
}

// The axis after the step's offsets (x0, y0) along e1, e2 and tilts (a, b) of the direction
// (a, b, 1): the new axis point (not yet re-centred) and unit direction.
struct SteppedAxis {
  Vector3d o;
  Vector3d dir;
};
inline SteppedAxis steppedAxis(const AxisState& s, double x0, double y0, double a, double b) {
  const Vector3d o = s.o + x0 * s.u.row(0).transpose() + y0 * s.u.row(1).transpose();
  const Vector3d dir =
      (s.u.row(2).transpose() + a * s.u.row(0).transpose() + b * s.u.row(1).transpose())
          .normalized();
  return {o, dir};
}

// Local parameters (Forbes DITC 140/89 section 6): axis through (x0, y0, 0) of the frame,
// direction (a, b, 1) normalised, radius r (and half angle psi for the cone). In the frame,
// q = U (p - o), rho = |(q0, q1)|:
//   cylinder  d = rho - r,                    dd = [-q0/rho, -q1/rho, -q0 q2/rho, -q1 q2/rho, -1]
//   cone      d = (rho - r) cos psi - q2 sin psi
//             dd = [-q0 c/rho, -q1 c/rho, -q0 (q2 c/rho + s), -q1 (q2 c/rho + s), -c,
//                   -(rho - r) s - q2 c]   (c = cos psi, s = sin psi)
template <bool Fixed>
struct CylinderModel {
  static constexpr int P = Fixed ? 4 : 5;
  using State = AxisState;
  struct Pre {
    const double* base;
    Matrix3d u;
    Vector3d o;
    double r;
  };
  const Points3* pts;
  Vector3d centroid;
  double size;
  double rounding;
  std::size_t count() const { return pts->size(); }
  Pre prepare(const State& s) const { return {pts->front().data(), s.u, s.o, s.r}; }
  template <class T>
  [[gnu::always_inline]] void row(const Pre& p, std::size_t i, std::array<T, P + 1>& v) const {
    const auto [q0, q1, q2, rho, cx, cy] = radialCoordinates<T>(p.base, i, p.u, p.o);
    v[0] = -cx;
    v[1] = -cy;
    v[2] = -cx * q2;
    v[3] = -cy * q2;
    if constexpr (!Fixed) v[4] = constant<T>(-1.0);
    v[P] = rho - p.r;
  }
  State apply(const State& s, const Vec<P>& d) const {
    const auto [o, dir] = steppedAxis(s, d(0), d(1), d(2), d(3));
    double r = s.r;
    if constexpr (!Fixed) r += d(4);
    return recentred(o, dir, r, 0.0, centroid);
  }
  double stepSize(const Vec<P>& d) const {
    double lengths = std::max(std::abs(d(0)), std::abs(d(1)));
    if constexpr (!Fixed) lengths = std::max(lengths, std::abs(d(4)));
    return std::max(lengths / size, std::max(std::abs(d(2)), std::abs(d(3))));
  }
  bool valid(const State& s) const { return s.o.allFinite() && s.u.allFinite() && s.r > 0.0; }
  bool sameFrame(const State& a, const State& b) const { return axisFramesAgree(a, b); }
};

struct ConeModel {
  static constexpr int P = 6;
  using State = AxisState;
  struct Pre {
    const double* base;
    Matrix3d u;
    Vector3d o;
    double r, c, s;
  };
  const Points3* pts;
  Vector3d centroid;
  double size;
  double rounding;
  std::size_t count() const { return pts->size(); }
  Pre prepare(const State& s) const {
    return {pts->front().data(), s.u, s.o, s.r, std::cos(s.psi), std::sin(s.psi)};
  }
  template <class T>
  [[gnu::always_inline]] void row(const Pre& p, std::size_t i, std::array<T, P + 1>& v) const {
    const auto [q0, q1, q2, rho, cx, cy] = radialCoordinates<T>(p.base, i, p.u, p.o);
    const T tilt = q2 * p.c;
    v[0] = -cx * p.c;
    v[1] = -cy * p.c;
    v[2] = -(cx * tilt + q0 * p.s);
    v[3] = -(cy * tilt + q1 * p.s);
    v[4] = constant<T>(-p.c);
    v[5] = -(rho - p.r) * p.s - q2 * p.c;
    v[P] = (rho - p.r) * p.c - q2 * p.s;
  }
  State apply(const State& s, const Vec<P>& d) const {
    const auto [o, dir] = steppedAxis(s, d(0), d(1), d(2), d(3));
    return recentred(o, dir, s.r + d(4), s.psi + d(5), centroid);
  }
  double stepSize(const Vec<P>& d) const {
    const double lengths = std::max({std::abs(d(0)), std::abs(d(1)), std::abs(d(4))});
    return std::max(lengths / size, std::max({std::abs(d(2)), std::abs(d(3)), std::abs(d(5))}));
  }
  bool sameFrame(const State& a, const State& b) const { return axisFramesAgree(a, b); }
  bool valid(const State& s) const {
    return s.o.allFinite() && s.u.allFinite() && std::isfinite(s.r) &&
           std::abs(s.psi) < 0.5 * kPi - 1e-6;
  }
};

// Sum of squares of a model at a state (scoring of starts).
template <class Model>
double sumOfSquares(const Model& model, const typename Model::State& s) {
  return accumulate(model, s).s.back();
}

// Algebraic start for a given axis direction: in the frame of `dir` through the centroid,
// x^2 + y^2 = A x + B y + K (cylinder: a circle in projection, Kasa) or
// x^2 + y^2 = A x + B y + K + M z + N z^2 (cone: rho(z)^2 = (r0 + t z)^2 about the axis
// through (A/2, B/2)), linear in the unknowns; scaled coordinates.
std::optional<AxisState> algebraicAxis(const Points3& pts, const Vector3d& centroid, double size,
                                       const Vector3d& dir, bool cone,
                                       const std::optional<double>& fixed);

// Start from options.start: the axis of a cylinder, cone, line3d or circle3d; its radius
// (and half angle) when the kinds match, otherwise the algebraic ones for that axis.
std::optional<AxisState> userAxisStart(const LeastSquaresOptions& o, const Points3& pts,
                                       const Moments& m, bool cone);

// Candidate axis directions: the principal axes, and the best of a hemisphere grid
// (Fibonacci lattice, ~11 deg apart) scored by the geometric sum of squares of the
// algebraic start for each direction.
template <class Model>
std::vector<Vector3d> candidateAxes(const Model& model, const Points3& sample, const Moments& m,
                                    const Axes& ax, bool cone, const std::optional<double>& fixed) {
  std::vector<Vector3d> dirs{ax.vec.col(2), ax.vec.col(1), ax.vec.col(0)};
  constexpr int kGrid = 160;
  constexpr int kKeep = 3;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  std::vector<std::pair<double, Vector3d>> scored;
  for (int k = 0; k < kGrid; ++k) {
    const double z = (k + 0.5) / kGrid;
    const double rxy = std::sqrt(1.0 - z * z);
    const Vector3d d(rxy * std::cos(golden * k), rxy * std::sin(golden * k), z);
    const auto s = algebraicAxis(sample, m.centroid, rmsSize(m), d, cone, fixed);
    if (!s || !model.valid(*s)) continue;
    const double ssr = sumOfSquares(model, *s);
    if (std::isfinite(ssr)) scored.emplace_back(ssr, d);
  }
  std::sort(scored.begin(), scored.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  int kept = 0;
  for (const auto& [ssr, d] : scored) {
    bool distinct = true;
    for (std::size_t i = 3; i < dirs.size(); ++i)
      distinct = distinct && std::abs(d.dot(dirs[i])) < std::cos(0.3);
    if (!distinct) continue;
    dirs.push_back(d);
    if (++kept == kKeep) break;
  }
  return dirs;
}

// Same axis element (orientation, axis position, radius, half angle) within 1e-6.
bool sameAxisElement(const AxisState& a, const AxisState& b, double size);

// The lowest sum of squares. When several starts reach different solutions with the same
// sum of squares to rounding (typically exact fits through as many points as parameters,
// e.g. NIST's 6-point cone, which two cones interpolate), the solution reached from most
// starts, i.e. with the largest basin of attraction, is reported.
template <class Model>
LmRun<Model> pickSolution(const std::vector<LmRun<Model>>& runs, std::size_t n, double size) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& r : runs) lowest = std::min(lowest, r.lin.ssr);
  const double noise = static_cast<double>(n) * (1e-10 * size) * (1e-10 * size);
  const double tie = std::max(lowest * (1.0 + 1e-9), noise);
  std::size_t best = 0;
  int best_votes = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].lin.ssr > tie) continue;
    int votes = 0;
    for (const auto& r : runs)
      if (r.lin.ssr <= tie && sameAxisElement(runs[i].state, r.state, size)) ++votes;
    if (votes > best_votes || (votes == best_votes && runs[i].lin.ssr < runs[best].lin.ssr)) {
      best = i;
      best_votes = votes;
    }
  }
  return runs[best];
}

template <class Model>
LmRun<Model> fitAxisElement(const Points3& pts, const Moments& m, const Axes& ax,
                            const LeastSquaresOptions& o, bool cone) {
  const double size = rmsSize(m);
  const double rounding = 8.0 * std::numeric_limits<double>::epsilon() *
                          (m.centroid.cwiseAbs().maxCoeff() + 2.0 * size);
  const Model full{&pts, m.centroid, size, rounding};
  // Starts are compared on a subsample of large sets, and a start is brought close on it
  // before the full set is iterated on; the winner is polished on all points.
  const bool subsampled = pts.size() > kStartSample;
  const Points3 sample = subsampled ? strideSample(pts, kStartSample) : Points3{};
  const Points3& sp = subsampled ? sample : pts;
  const Model sub{&sp, m.centroid, size, rounding};
  if (const auto start = userAxisStart(o, pts, m, cone)) {
    AxisState s = *start;
    if (pts.size() >= kCoarseMin) {
      const auto coarse = levenbergMarquardt(sub, s, o.max_iterations);
      if (coarse.converged && coarse.lin.ok) s = coarse.state;
    }
    auto run = polished(full, levenbergMarquardt(full, s, o.max_iterations), o.max_iterations);
    if (run.converged && run.lin.ok) return run;
  }
  const int sub_iterations = subsampled ? std::min(o.max_iterations, 50) : o.max_iterations;
  std::vector<LmRun<Model>> runs;
  for (const Vector3d& d : candidateAxes(sub, sp, m, ax, cone, o.fixed_radius_mm)) {
    const auto start = algebraicAxis(sp, m.centroid, size, d, cone, o.fixed_radius_mm);
    if (!start) continue;
    auto run = levenbergMarquardt(sub, *start, sub_iterations);
    if (run.lin.ok) runs.push_back(run);
  }
  if (runs.empty()) return LmRun<Model>{};
  const LmRun<Model> best = pickSolution(runs, sp.size(), size);
  if (!subsampled) return polished(full, best, o.max_iterations);
  return polished(full, levenbergMarquardt(full, best.state, o.max_iterations), o.max_iterations);
}

// Why an axis fit is ill-determined: along-axis extent or angular sector of the points.
template <int P>
std::string axisAdvice(ElementKind kind, const Points3& pts, const AxisState& s,
                       const Conditioning<P>& cond, bool fixed) {
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  std::vector<double> ang;
  ang.reserve(pts.size());
  for (const auto& p : pts) {
    const Vector3d q = s.u * (p - s.o);
    zmin = std::min(zmin, q.z());
    zmax = std::max(zmax, q.z());
    ang.push_back(std::atan2(q.y(), q.x()));
  }
  double axial = cond.weakest(2) * cond.weakest(2) + cond.weakest(3) * cond.weakest(3);
  if (kind == ElementKind::Cone) axial += cond.weakest(5) * cond.weakest(5);
  if (axial > 0.5)
    return name(kind) + ": the points span only " + num(zmax - zmin) + " mm along the axis, too "
           "little to fix its direction: probe at two or more levels further apart";
  return name(kind) + ": the " + degrees(angularSpan(std::move(ang))) + " sector is too narrow "
         "to determine the radius: probe further around the " + name(kind) +
         (kind == ElementKind::Cylinder && !fixed ? " or give the known radius" : "");
}

// Propagation of the local covariance to the reported axis parameters. With w = centroid -
// o (w1, w2 in the frame) the reported point (foot of the centroid on the moved axis) is
// o + x0 e1 + y0 e2 + (a w1 + b w2) e3 to first order; the direction moves by a e1 + b e2
// (times the sign flip to the reported direction).
Eigen::MatrixXd axisJacobian(const AxisState& s, const Vector3d& centroid, double sign,
                             int rows, int cols);

}  // namespace probeloop::geometry::ls
