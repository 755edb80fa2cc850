// Least-squares sphere (ls_detail.hpp): Kasa algebraic start (or options.start), then
// geometric Gauss-Newton / Levenberg-Marquardt, like fitSphere().
#include "geometry/ls_detail.hpp"

namespace probeloop::geometry::ls {
namespace {

// Sphere on the original coordinates (the centre estimate is near the data, so p - c
// keeps its digits). Parameters: centre offsets (and the radius).
// r = |p - c| - r0, J = [-(p - c) / |p - c| (, -1)].
template <bool Fixed>
struct SphereModel {
  static constexpr int P = Fixed ? 3 : 4;
  struct State {
    Vector3d c = Vector3d::Zero();
    double r = 0.0;
  };
  struct Pre {
    const double* base;
    Vector3d c;
    double r;
  };
  const Points3* pts;
  double size;
  double rounding;
  std::size_t count() const { return pts->size(); }
  Pre prepare(const State& s) const { return {pts->front().data(), s.c, s.r}; }
  template <class T>
  [[gnu::always_inline]] void row(const Pre& p, std::size_t i, std::array<T, P + 1>& v) const {
    const T x = gather<T>(p.base, i, 3, 0) - p.c.x();
    const T y = gather<T>(p.base, i, 3, 1) - p.c.y();
    const T z = gather<T>(p.base, i, 3, 2) - p.c.z();
    const auto [rho, inv] = lengthAndInverse<T>(x * x + y * y + z * z);
    v[0] = -x * inv;
    v[1] = -y * inv;
    v[2] = -z * inv;
    if constexpr (!Fixed) v[3] = constant<T>(-1.0);
    v[P] = rho - p.r;
  }
  State apply(const State& s, const Vec<P>& d) const {
    State t = s;
    t.c += d.template head<3>();
    if constexpr (!Fixed) t.r += d(3);
    return t;
  }
  double stepSize(const Vec<P>& d) const { return d.cwiseAbs().maxCoeff() / size; }
  bool valid(const State& s) const { return s.c.allFinite() && std::isfinite(s.r) && s.r > 0.0; }
};

struct SphereGuess {
  Vector3d c = Vector3d::Zero();
  double r = 0.0;
  bool ok = false;
};

// Kasa: |q|^2 = 2 c.q + k, linear in (c, k), on coordinates centred at the centroid and
// scaled by the RMS size (Forbes DITC 140/89 section 5: the linear sphere start).
SphereGuess kasaSphere(const Points3& pts, const Moments& m) {
  const double size = rmsSize(m);
  Mat<4> a = Mat<4>::Zero();
  Vec<4> b = Vec<4>::Zero();
  for (const auto& p : pts) {
    const Vector3d q = (p - m.centroid) / size;
    const Vec<4> v(2.0 * q.x(), 2.0 * q.y(), 2.0 * q.z(), 1.0);
    a.selfadjointView<Eigen::Upper>().rankUpdate(v);
    b += v * q.squaredNorm();
  }
  const Vec<4> x = Mat<4>(a.selfadjointView<Eigen::Upper>()).colPivHouseholderQr().solve(b);
  SphereGuess g;
  g.c = m.centroid + size * x.head<3>();
  g.r = size * std::sqrt(x(3) + x.head<3>().squaredNorm());
  g.ok = g.c.allFinite() && std::isfinite(g.r) && g.r > 0.0;
  return g;
}

std::string capAdvice(const Points3& pts, const Vector3d& c) {
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : pts) mean += (p - c).normalized();
  double half = 0.0;
  if (mean.norm() > 0.0) {
    mean.normalize();
    for (const auto& p : pts) {
      const Vector3d u = (p - c).normalized();
      half = std::max(half, std::atan2(u.cross(mean).norm(), u.dot(mean)));
    }
  }
  return "the points cover a spherical cap of only " + degrees(2.0 * half) +
         " (seen from the centre), too small to determine a radius: spread the points wider or "
         "give the known radius";
}

template <bool Fixed>
FitResult fitSphereWith(const Points3& pts, const Moments& m, const Axes& ax,
                        const LeastSquaresOptions& o) {
  using Model = SphereModel<Fixed>;
  const double eps = std::numeric_limits<double>::epsilon();
  const double rounding = 8.0 * eps * (m.centroid.cwiseAbs().maxCoeff() + 2.0 * rmsSize(m));
  const Model model{&pts, rmsSize(m), rounding};
  auto fromGuess = [&](SphereGuess g) {
    if (Fixed) {
      g.c = knownRadiusCentre<Vector3d>(m.centroid, m.cov.trace(), g.c, *o.fixed_radius_mm,
                                        ax.vec.col(0));
      g.r = *o.fixed_radius_mm;
    }
    return typename Model::State{g.c, g.r};
  };
  // A large set first converges on an evenly spread subsample: the full set then needs
  // only the last, quadratically converging steps.
  const Points3 sample = pts.size() >= kCoarseMin ? strideSample(pts, kStartSample) : Points3{};
  const Model coarse{&sample, rmsSize(m), rounding};
  auto solve = [&](const typename Model::State& start) {
    typename Model::State s = start;
    if (!sample.empty()) {
      const auto c = levenbergMarquardt(coarse, start, o.max_iterations);
      if (c.converged && c.lin.ok) s = c.state;
    }
    return polished(model, levenbergMarquardt(model, s, o.max_iterations), o.max_iterations);
  };
  LmRun<Model> run;
  bool have = false;
  if (o.start && o.start->kind == ElementKind::Sphere && o.start->position_mm.allFinite() &&
      o.start->radius_mm > 0.0) {
    run = solve(fromGuess({o.start->position_mm, o.start->radius_mm, true}));
    have = run.converged && run.lin.ok;
  }
  if (!have) {
    const SphereGuess g = kasaSphere(pts, m);
    if (!g.ok)
      fail("sphere: the algebraic start is undefined, the points do not outline a sphere: "
           "probe points spread over the sphere");
    run = solve(fromGuess(g));
  }
  const auto cond = conditioning(run.lin);
  if (!run.lin.ok || !(cond.condition <= kMaxCondition)) {
    if (Fixed)
      fail("sphere: the centre is not determined by these points with the known radius: "
           "spread the points over the sphere");
    fail("sphere: " + capAdvice(pts, run.state.c));
  }
  if (!run.converged)
    fail("least-squares sphere did not converge in " + std::to_string(o.max_iterations) +
         " iterations: raise max_iterations or check that the points outline one sphere");
  Element e;
  e.kind = ElementKind::Sphere;
  e.position_mm = run.state.c;
  e.radius_mm = Fixed ? *o.fixed_radius_mm : run.state.r;
  std::vector<std::string> names{"x_mm", "y_mm", "z_mm"};
  if (!Fixed) names.push_back("r_mm");
  const ResidualStats stats = statsOf(run.lin);
  return makeResult(e, pts, Model::P, names, inverseNormal(run.lin), run.iterations, o, &stats);
}

}  // namespace

FitResult fitSphereLs(const Points3& pts, const Moments& m, const Axes& ax,
                      const LeastSquaresOptions& o) {
  checkNotCoplanar(ElementKind::Sphere, pts, m, ax, ">= 4 non-coplanar points",
                   "add a point off that plane (e.g. at the pole)");
  return o.fixed_radius_mm ? fitSphereWith<true>(pts, m, ax, o)
                           : fitSphereWith<false>(pts, m, ax, o);
}

}  // namespace probeloop::geometry::ls
