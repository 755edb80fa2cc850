// The parts of the minimum-zone fits that need CGAL (minimum_zone_detail.hpp), in one
// translation unit so that CGAL's headers are compiled once for the library:
// - the linearised LP: CGAL's QP solver (QP_models, QP_functions) on Gmpzf;
// - the minimum annulus: Min_annulus_d with its 2D/3D traits, Cartesian<double>, Gmpzf;
// - the smallest enclosing circle (Min_circle_2, exact constructions) and sphere
//   (Min_sphere_of_spheres_d, Cartesian<Gmpq>);
// - the largest inscribed circle: Delaunay_triangulation_2 (inexact constructions) with
//   exact circumcentres;
// - the convex hull (exact orientation predicate) and the minimum-width strip.
// One unit per part would include only its own headers, but each would pay for CGAL's kernel
// and number types again: measured (issue 29), the five units and minimum_zone.cpp took 1.65
// times the CPU time of the file they came from; this unit and minimum_zone.cpp take less.
#include "geometry/minimum_zone_detail.hpp"

#include <CGAL/Cartesian.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Gmpq.h>
#include <CGAL/Gmpzf.h>
#include <CGAL/Min_annulus_d.h>
#include <CGAL/Min_circle_2.h>
#include <CGAL/Min_circle_2_traits_2.h>
#include <CGAL/Min_sphere_annulus_d_traits_2.h>
#include <CGAL/Min_sphere_annulus_d_traits_3.h>
#include <CGAL/Min_sphere_of_spheres_d.h>
#include <CGAL/Min_sphere_of_spheres_d_traits_3.h>
#include <CGAL/QP_functions.h>
#include <CGAL/QP_models.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <type_traits>
#include <utility>

#include "core/error.hpp"

namespace probeloop::geometry::mz {

// ================================================================== the linearised LP

namespace {

// CGAL's default (partial filtered Dantzig) pricing can cycle on a degenerate LP and never return:
// a plane fitted to a dozen points on a 0.1 um grid has more than m + 1 points tied on the
// zone's boundary after one step (found on a thermal-test-piece Z path). Bland's rule
// cannot cycle (CGAL manual, QP_solver/cycling.cpp); the LPs here have a few dozen rows.
const CGAL::Quadratic_program_options& blandPricing() {
  static const CGAL::Quadratic_program_options options = [] {
    CGAL::Quadratic_program_options o;
    o.set_pricing_strategy(CGAL::QP_BLAND);
    return o;
  }();
  return options;
}

}  // namespace

// Exact solution (on the double data) of the linearised problem over all points inside
// the box |delta_j| <= box, by constraint generation starting from `active`.
LpStep solveLinearised(const VectorXd& r, const RowMatrix& J, Goal goal, double box,
                       std::vector<int> active, double noise) {
  const int m = static_cast<int>(J.cols());
  const int n = static_cast<int>(r.size());
  const int hi = m;
  const int lo = goal == Goal::Zone ? m + 1 : m;
  dedupe(active);
  for (int round = 0; round < 200; ++round) {
    CGAL::Quadratic_program<double> lp(CGAL::SMALLER, false, 0.0, false, 0.0);
    int row = 0;
    for (int i : active) {
      if (goal != Goal::Inner) {  // r_i + J_i d <= hi
        for (int j = 0; j < m; ++j) lp.set_a(j, row, J(i, j));
        lp.set_a(hi, row, -1.0);
        lp.set_b(row, -r[i]);
        lp.set_r(row, CGAL::SMALLER);
        ++row;
      }
      if (goal != Goal::Outer) {  // r_i + J_i d >= lo
        for (int j = 0; j < m; ++j) lp.set_a(j, row, J(i, j));
        lp.set_a(lo, row, -1.0);
        lp.set_b(row, -r[i]);
        lp.set_r(row, CGAL::LARGER);
        ++row;
      }
    }
    for (int j = 0; j < m; ++j) {
      lp.set_l(j, true, -box);
      lp.set_u(j, true, box);
    }
    if (goal != Goal::Inner) lp.set_c(hi, 1.0);
    if (goal != Goal::Outer) lp.set_c(lo, -1.0);
    const auto sol = CGAL::solve_linear_program(lp, CGAL::Gmpzf(), blandPricing());
    if (!sol.is_optimal())  // bounded box and free hi/lo: always optimal
      throw GeometryError("internal error: linearised Chebyshev LP not optimal");
    std::vector<double> x;
    for (auto it = sol.variable_values_begin(); it != sol.variable_values_end(); ++it)
      x.push_back(CGAL::to_double(*it));
    x.resize(m + 2, 0.0);
    LpStep step;
    step.delta = Eigen::Map<const VectorXd>(x.data(), m);
    const double vhi = x[hi];
    const double vlo = x[lo];
    const VectorXd lin = r + J * step.delta;
    // Worst violators on each side.
    std::vector<std::pair<double, int>> up, down;
    for (int i = 0; i < n; ++i) {
      if (goal != Goal::Inner && lin[i] - vhi > noise) up.push_back({lin[i] - vhi, i});
      if (goal != Goal::Outer && vlo - lin[i] > noise) down.push_back({vlo - lin[i], i});
    }
    const size_t per_round = static_cast<size_t>(m + 2);
    std::vector<int> fresh;  // violators not yet in the (sorted) active set
    auto take = [&](std::vector<std::pair<double, int>>& v) {
      std::sort(v.begin(), v.end(), std::greater<>());
      for (size_t k = 0; k < v.size() && k < per_round; ++k)
        if (!std::binary_search(active.begin(), active.end(), v[k].second))
          fresh.push_back(v[k].second);
    };
    take(up);
    take(down);
    const size_t added = fresh.size();
    active.insert(active.end(), fresh.begin(), fresh.end());
    if (added == 0) {  // no violator outside the active set: optimal over all points
      step.model = goal == Goal::Zone ? vhi - vlo : goal == Goal::Outer ? vhi : -vlo;
      const double bind = 64.0 * noise;  // exact LP: binding rows differ by rounding only
      for (int i : active) {
        if (goal != Goal::Inner && std::abs(lin[i] - vhi) <= bind) step.upper.push_back(i);
        if (goal != Goal::Outer && std::abs(lin[i] - vlo) <= bind) step.lower.push_back(i);
      }
      return step;
    }
    dedupe(active);
  }
  throw GeometryError("internal error: constraint generation for the Chebyshev LP did not "
                      "terminate");
}

// ================================================================== the minimum annulus

// Min_annulus_d (exact, Gmpzf) centre of the centred points, on a growing subset: the
// problem is an LP (minimise R^2 - r^2), so adding the points outside the current
// annulus converges to the annulus of all points in a few small solves.
template <int D>
Eigen::Matrix<double, D, 1> annulusCentre(const Frame& f) {
  using K = CGAL::Cartesian<double>;
  using Traits = std::conditional_t<D == 2, CGAL::Min_sphere_annulus_d_traits_2<K, CGAL::Gmpzf, double>,
                                    CGAL::Min_sphere_annulus_d_traits_3<K, CGAL::Gmpzf, double>>;
  using Point = std::conditional_t<D == 2, K::Point_2, K::Point_3>;
  using Vec = Eigen::Matrix<double, D, 1>;
  const int n = static_cast<int>(f.q.size());
  auto point = [&](int i) {
    if constexpr (D == 2) return Point(f.q[i].x(), f.q[i].y());
    else return Point(f.q[i].x(), f.q[i].y(), f.q[i].z());
  };
  // Start: extremes of the distance from the centroid, plus an even sample.
  VectorXd d0(n);
  for (int i = 0; i < n; ++i) d0[i] = f.q[i].template head<D>().norm();
  std::vector<int> active;
  addExtremes(d0, Goal::Zone, 8, active);
  const int stride = std::max(1, n / 48);
  for (int i = 0; i < n; i += stride) active.push_back(i);
  dedupe(active);
  Vec c = Vec::Zero();
  for (int round = 0; round < 100; ++round) {
    std::vector<Point> pts;
    for (int i : active) pts.push_back(point(i));
    CGAL::Min_annulus_d<Traits> ann(pts.begin(), pts.end());
    std::vector<double> h;
    for (auto it = ann.center_coordinates_begin(); it != ann.center_coordinates_end(); ++it)
      h.push_back(CGAL::to_double(*it));
    for (int k = 0; k < D; ++k) c[k] = h[k] / h[D];  // homogeneous, last = denominator
    const double den = CGAL::to_double(ann.squared_radii_denominator());
    const double ro = std::sqrt(std::max(0.0, CGAL::to_double(ann.squared_outer_radius_numerator()) / den));
    const double ri = std::sqrt(std::max(0.0, CGAL::to_double(ann.squared_inner_radius_numerator()) / den));
    std::vector<std::pair<double, int>> out;
    const double eps = 1e-12 * (ro + 1.0);
    for (int i = 0; i < n; ++i) {
      const double d = (f.q[i].template head<D>() - c).norm();
      if (d > ro + eps) out.push_back({d - ro, i});
      else if (d < ri - eps) out.push_back({ri - d, i});
    }
    std::sort(out.begin(), out.end(), std::greater<>());
    const size_t before = active.size();
    for (size_t k = 0; k < out.size() && k < 16; ++k) active.push_back(out[k].second);
    dedupe(active);
    if (active.size() == before) break;
  }
  return c;
}

template Eigen::Matrix<double, 2, 1> annulusCentre<2>(const Frame& f);
template Eigen::Matrix<double, 3, 1> annulusCentre<3>(const Frame& f);

// ================================================================== the smallest enclosing circle

Vector2d minCircleCentre(const Frame& f) {
  using K = CGAL::Exact_predicates_exact_constructions_kernel;
  std::vector<K::Point_2> pts;
  pts.reserve(f.q.size());
  for (const auto& p : f.q) pts.emplace_back(p.x(), p.y());
  CGAL::Min_circle_2<CGAL::Min_circle_2_traits_2<K>> mc(pts.begin(), pts.end(), true);
  const auto c = mc.circle().center();
  return Vector2d(CGAL::to_double(c.x()), CGAL::to_double(c.y()));
}

// Smallest enclosing sphere: Min_sphere_of_spheres_d with Gmpq and the square-root
// extension (exact), on a growing subset (points outside the current ball are added).
Vector3d minSphereCentre(const Frame& f) {
  using K = CGAL::Cartesian<CGAL::Gmpq>;
  using Traits = CGAL::Min_sphere_of_spheres_d_traits_3<K, CGAL::Gmpq, CGAL::Tag_false>;
  const int n = static_cast<int>(f.q.size());
  VectorXd d0(n);
  for (int i = 0; i < n; ++i) d0[i] = f.q[i].norm();
  std::vector<int> active;
  addExtremes(d0, Goal::Outer, 8, active);
  for (int k = 0; k < 3; ++k) {  // extremes along the axes
    int lo = 0, hi = 0;
    for (int i = 0; i < n; ++i) {
      if (f.q[i][k] < f.q[lo][k]) lo = i;
      if (f.q[i][k] > f.q[hi][k]) hi = i;
    }
    active.push_back(lo);
    active.push_back(hi);
  }
  dedupe(active);
  Vector3d c = Vector3d::Zero();
  for (int round = 0; round < 100; ++round) {
    std::vector<Traits::Sphere> balls;
    for (int i : active)
      balls.emplace_back(K::Point_3(f.q[i].x(), f.q[i].y(), f.q[i].z()), CGAL::Gmpq(0));
    CGAL::Min_sphere_of_spheres_d<Traits> ms(balls.begin(), balls.end());
    const double disc = std::sqrt(std::max(0.0, CGAL::to_double(ms.discriminant())));
    auto it = ms.center_cartesian_begin();
    for (int k = 0; k < 3; ++k, ++it)
      c[k] = CGAL::to_double(it->first) + CGAL::to_double(it->second) * disc;
    const double R = CGAL::to_double(ms.radius().first) + CGAL::to_double(ms.radius().second) * disc;
    std::vector<std::pair<double, int>> out;
    for (int i = 0; i < n; ++i) {
      const double d = (f.q[i] - c).norm();
      if (d > R + 1e-12 * (R + 1.0)) out.push_back({d - R, i});
    }
    std::sort(out.begin(), out.end(), std::greater<>());
    const size_t before = active.size();
    for (size_t k = 0; k < out.size() && k < 16; ++k) active.push_back(out[k].second);
    dedupe(active);
    if (active.size() == before) break;
  }
  return c;
}

// ================================================================== the largest inscribed circle

namespace {

// Largest angle (rad) between consecutive directions from c to the points, seen in xy.
double largestAngularGap(const Points3& q, const Vector2d& c) {
  std::vector<double> ang;
  ang.reserve(q.size());
  for (const auto& p : q) {
    const Vector2d v = p.head<2>() - c;
    if (v.squaredNorm() > 0.0) ang.push_back(std::atan2(v.y(), v.x()));
  }
  if (ang.size() < 2) return 2.0 * M_PI;
  std::sort(ang.begin(), ang.end());
  double gap = ang.front() + 2.0 * M_PI - ang.back();
  for (size_t i = 1; i < ang.size(); ++i) gap = std::max(gap, ang[i] - ang[i - 1]);
  return gap;
}

}  // namespace

// Largest empty circle through a Delaunay triangle whose circumcentre lies inside (or on)
// the triangle (a local maximum of the distance to the nearest point: the Voronoi vertex
// lies in the convex hull of its nearest points) and is surrounded by all the points
// (largest angular gap < 180 deg, i.e. the centre is strictly inside their hull).
Vector2d maxInscribedCircleCentre(const Frame& f) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using E = CGAL::Exact_predicates_exact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb>;
  using Dt = CGAL::Delaunay_triangulation_2<K, Tds>;
  std::vector<std::pair<K::Point_2, int>> pts;
  for (size_t i = 0; i < f.q.size(); ++i)
    pts.push_back({K::Point_2(f.q[i].x(), f.q[i].y()), static_cast<int>(i)});
  Dt dt(pts.begin(), pts.end());
  struct Candidate {
    double r2;
    Vector2d c;
  };
  std::vector<Candidate> cand;
  for (auto fh = dt.finite_faces_begin(); fh != dt.finite_faces_end(); ++fh) {
    E::Point_2 v[3];
    for (int k = 0; k < 3; ++k) v[k] = E::Point_2(fh->vertex(k)->point().x(), fh->vertex(k)->point().y());
    if (CGAL::angle(v[2], v[0], v[1]) == CGAL::OBTUSE || CGAL::angle(v[0], v[1], v[2]) == CGAL::OBTUSE ||
        CGAL::angle(v[1], v[2], v[0]) == CGAL::OBTUSE)
      continue;
    const E::Point_2 cc = CGAL::circumcenter(v[0], v[1], v[2]);
    cand.push_back({CGAL::to_double(CGAL::squared_distance(cc, v[0])),
                    Vector2d(CGAL::to_double(cc.x()), CGAL::to_double(cc.y()))});
  }
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) { return a.r2 > b.r2; });
  double best_gap = 2.0 * M_PI;
  for (size_t k = 0; k < cand.size() && k < 32; ++k) {
    const double gap = largestAngularGap(f.q, cand[k].c);
    if (gap < M_PI * (1.0 - 1e-12)) return cand[k].c;
    best_gap = std::min(best_gap, gap);
  }
  const std::string seen =
      cand.empty() ? "no Delaunay triangle contains its circumcentre"
                   : "every candidate centre sees a gap of at least " +
                         fmt(best_gap * 180.0 / M_PI, 4) + " deg between them; it must be < 180 deg";
  throw GeometryError(
      "maximum-inscribed circle2d is ill-defined: the points do not surround an empty circle (" +
      seen + "). An arc lets the inscribed circle grow without bound; probe the whole profile "
      "or use the least-squares or minimum-zone circle.");
}

// ================================================================== the convex hull

namespace {

// Convex hull (counterclockwise, no collinear vertices) by Andrew's monotone chain with
// CGAL's exact orientation predicate; indices into q.
std::vector<int> convexHull2(const Points3& q) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::vector<int> idx(q.size());
  std::iota(idx.begin(), idx.end(), 0);
  std::sort(idx.begin(), idx.end(), [&](int a, int b) {
    return q[a].x() < q[b].x() || (q[a].x() == q[b].x() && q[a].y() < q[b].y());
  });
  idx.erase(std::unique(idx.begin(), idx.end(),
                        [&](int a, int b) { return q[a].head<2>() == q[b].head<2>(); }),
            idx.end());
  if (idx.size() < 3) return idx;
  auto P = [&](int i) { return K::Point_2(q[i].x(), q[i].y()); };
  std::vector<int> h(2 * idx.size());
  size_t k = 0;
  for (size_t i = 0; i < idx.size(); ++i) {
    while (k >= 2 && CGAL::orientation(P(h[k - 2]), P(h[k - 1]), P(idx[i])) != CGAL::LEFT_TURN) --k;
    h[k++] = idx[i];
  }
  for (size_t i = idx.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && CGAL::orientation(P(h[k - 2]), P(h[k - 1]), P(idx[i])) != CGAL::LEFT_TURN) --k;
    h[k++] = idx[i];
  }
  h.resize(k - 1);
  return h;
}

}  // namespace

// Minimum-width strip of the xy points: rotating calipers over the hull edges (the
// optimal strip has one side through a hull edge; Toussaint 1983, "Solving geometric
// problems with the rotating calipers"). Returns the unit direction of that edge.
Vector2d minWidthDirection(const Points3& q) {
  const std::vector<int> h = convexHull2(q);
  if (h.size() < 2) return Vector2d::UnitX();
  if (h.size() == 2) return (q[h[1]] - q[h[0]]).head<2>().normalized();
  const size_t m = h.size();
  auto P = [&](size_t i) { return Vector2d(q[h[i % m]].head<2>()); };
  auto area = [&](size_t i, size_t j) {  // twice the area of (edge i, vertex j)
    const Vector2d e = P(i + 1) - P(i);
    const Vector2d v = P(j) - P(i);
    return e.x() * v.y() - e.y() * v.x();
  };
  size_t j = 1;
  double best = std::numeric_limits<double>::infinity();
  Vector2d dir = Vector2d::UnitX();
  for (size_t i = 0; i < m; ++i) {
    if (j <= i) j = i + 1;
    while (area(i, j + 1) > area(i, j)) ++j;
    const double len = (P(i + 1) - P(i)).norm();
    const double w = area(i, j) / len;
    if (w < best) {
      best = w;
      dir = (P(i + 1) - P(i)) / len;
    }
  }
  return dir;
}

}  // namespace probeloop::geometry::mz
