// Input checks, moments and result assembly of the least-squares fits (ls_detail.hpp).
#include <cstdint>
#include <cstdio>
#include <numeric>

#include "core/error.hpp"
#include "geometry/ls_detail.hpp"

namespace probeloop::geometry::ls {

std::string num(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}
std::string um(double mm) { return num(mm * 1000.0, 2) + " um"; }
std::string degrees(double rad) { return num(rad * 180.0 / kPi, 3) + " deg"; }
std::string name(ElementKind k) { return std::string(elementName(k)); }
void fail(const std::string& message) { throw GeometryError(message); }

bool isPlanar(ElementKind k) { return k == ElementKind::Line2D || k == ElementKind::Circle2D; }

Vector3d canonical(const Vector3d& d) {
  int k = 0;
  d.cwiseAbs().maxCoeff(&k);
  return d(k) < 0.0 ? Vector3d(-d) : d;
}

// Duff et al., "Building an orthonormal basis, revisited", JCGT 6(1), 2017: continuous
// except at d.z = 0, no division by ~0.
Matrix3d frameOf(const Vector3d& d) {
  const double sign = std::copysign(1.0, d.z());
  const double a = -1.0 / (sign + d.z());
  const double b = d.x() * d.y() * a;
  Matrix3d u;
  u.row(0) << 1.0 + sign * d.x() * d.x() * a, sign * b, -sign * d.x();
  u.row(1) << b, sign + d.y() * d.y() * a, -d.y();
  u.row(2) = d.transpose();
  return u;
}

double angularSpan(std::vector<double> angles) {
  if (angles.size() < 2) return 0.0;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2.0 * kPi - angles.back();
  for (std::size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
  return 2.0 * kPi - gap;
}

void checkOptions(ElementKind kind, const LeastSquaresOptions& o) {
  if (o.max_iterations < 1)
    fail("least-squares " + name(kind) + ": max_iterations is " +
         std::to_string(o.max_iterations) + "; give at least 1 (default 100)");
  if (!o.fixed_radius_mm) return;
  if (kind != ElementKind::Circle2D && kind != ElementKind::Circle3D &&
      kind != ElementKind::Sphere && kind != ElementKind::Cylinder)
    fail("a known radius applies to circle, sphere and cylinder fits; a " + name(kind) +
         " has no single radius: drop the known radius");
  const double r = *o.fixed_radius_mm;
  if (!std::isfinite(r) || !(r > 0.0))
    fail("the known " + name(kind) + " radius must be a positive number of mm (got " + num(r) +
         "): give the nominal radius, or fit without a known radius");
}

void checkCount(ElementKind kind, const Points3& pts) {
  const int need = minimumPoints(kind);
  if (static_cast<long>(pts.size()) < need) {
    fail(name(kind) + " needs >= " + std::to_string(need) + " points; got " +
         std::to_string(pts.size()) + ": probe at least " +
         std::to_string(need - static_cast<long>(pts.size())) + " more points on the " +
         name(kind));
  }
}

namespace {

// One pass: sums of d and d d^T, d = p - shift, four points per vector (in an AVX2 and a
// default version, like the fits' passes: the same sums on every CPU), in blocks of kBlock
// partial sums.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
template <bool Planar>
[[gnu::always_inline]] inline std::array<double, 9> momentSumsWith(const Points3& pts,
                                                                   const Vector3d& shift) {
  const std::size_t n = pts.size();
  const double* base = pts.front().data();
  std::array<double, 9> t{};  // x y z xx xy xz yy yz zz
  for (std::size_t b0 = 0; b0 < n; b0 += kBlock) {
    const std::size_t b1 = std::min(n, b0 + kBlock);
    const Quad zero = {0.0, 0.0, 0.0, 0.0};
    Quad sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero,
         syz = zero, szz = zero;
    std::size_t i = b0;
    for (; i + 4 <= b1; i += 4) {
      const Quad x = gather<Quad>(base, i, 3, 0) - shift.x();
      const Quad y = gather<Quad>(base, i, 3, 1) - shift.y();
      const Quad z = Planar ? zero : gather<Quad>(base, i, 3, 2) - shift.z();
      sx += x, sy += y, sz += z;
      sxx += x * x, sxy += x * y, sxz += x * z;
      syy += y * y, syz += y * z, szz += z * z;
    }
    double tail[9] = {};
    for (; i < b1; ++i) {
      const double x = base[3 * i] - shift.x(), y = base[3 * i + 1] - shift.y();
      const double z = Planar ? 0.0 : base[3 * i + 2] - shift.z();
      const double v[9] = {x, y, z, x * x, x * y, x * z, y * y, y * z, z * z};
      for (int k = 0; k < 9; ++k) tail[k] += v[k];
    }
    const Quad* q[9] = {&sx, &sy, &sz, &sxx, &sxy, &sxz, &syy, &syz, &szz};
    for (int k = 0; k < 9; ++k) t[k] += (((*q[k])[0] + (*q[k])[1]) + ((*q[k])[2] + (*q[k])[3])) + tail[k];
  }
  return t;
}
template <bool Planar>
[[gnu::target("avx2")]] std::array<double, 9> momentSumsAvx2(const Points3& pts,
                                                              const Vector3d& shift) {
  return momentSumsWith<Planar>(pts, shift);
}
template <bool Planar>
std::array<double, 9> momentSums(const Points3& pts, const Vector3d& shift) {
  return useAvx2Passes() ? momentSumsAvx2<Planar>(pts, shift) : momentSumsWith<Planar>(pts, shift);
}
#pragma GCC diagnostic pop

template <bool Planar>
Moments momentsAbout(const Points3& pts, const Vector3d& shift) {
  const std::size_t n = pts.size();
  const std::array<double, 9> t = momentSums<Planar>(pts, shift);
  Moments m;
  m.n = n;
  const double inv = 1.0 / static_cast<double>(n);
  const Vector3d mean(t[0] * inv, t[1] * inv, t[2] * inv);
  m.centroid = shift + mean;
  m.cov << t[3] * inv, t[4] * inv, t[5] * inv,  //
      t[4] * inv, t[6] * inv, t[7] * inv,       //
      t[5] * inv, t[7] * inv, t[8] * inv;
  m.cov -= mean * mean.transpose();
  return m;
}

[[noreturn]] void reportNonFinite(ElementKind kind, const Points3& pts, bool planar) {
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vector3d& p = pts[i];
    const bool finite = planar ? p.head<2>().allFinite() : p.allFinite();
    if (!finite)
      fail(name(kind) + " point " + std::to_string(i + 1) + " is not finite (" + num(p.x()) +
           ", " + num(p.y()) + (planar ? "" : ", " + num(p.z())) +
           "): remove it or re-measure it");
  }
  fail(name(kind) + " point coordinates are too large to square in double precision: "
       "check the units (mm expected)");
}

double maxDistanceFromPlane(const Points3& pts, const Vector3d& c, const Vector3d& n) {
  double worst = 0.0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(n.dot(p - c)));
  return worst;
}

[[noreturn]] void reportDuplicate(ElementKind kind, std::size_t a, std::size_t b) {
  fail(name(kind) + " points " + std::to_string(std::min(a, b) + 1) + " and " +
       std::to_string(std::max(a, b) + 1) + " coincide" + (isPlanar(kind) ? " in x, y" : "") +
       ": remove the duplicate (a repeated point counts twice in the fit)");
}

// Sweep along one axis after sorting: the fallback for coordinates too large for the grid.
void checkDuplicatesBySorting(ElementKind kind, const Points3& pts) {
  const std::size_t n = pts.size();
  const bool planar = isPlanar(kind);
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return pts[a].x() < pts[b].x() || (pts[a].x() == pts[b].x() && a < b);
  });
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      const Vector3d& p = pts[idx[a]];
      const Vector3d& q = pts[idx[b]];
      if (q.x() - p.x() > kCoincidentMm) break;
      const double d = planar ? (p - q).head<2>().norm() : (p - q).norm();
      if (d <= kCoincidentMm) reportDuplicate(kind, idx[a], idx[b]);
    }
}

}  // namespace

Moments computeMoments(ElementKind kind, const Points3& pts) {
  const bool planar = isPlanar(kind);
  auto run = [&](Vector3d shift) {
    if (planar) shift.z() = 0.0;
    return planar ? momentsAbout<true>(pts, shift) : momentsAbout<false>(pts, shift);
  };
  Moments m = run(pts.front());
  if (!m.centroid.allFinite() || !m.cov.allFinite()) reportNonFinite(kind, pts, planar);
  // A data point as the shift keeps the cancellation in E[dd^T] - E[d]E[d]^T small; only
  // when that point lies far out from the rest is a second pass about the centroid needed.
  if ((pts.front() - m.centroid).head(planar ? 2 : 3).squaredNorm() > 1e4 * m.cov.trace())
    m = run(m.centroid);
  return m;
}

Axes principalAxes(const Moments& m) {
  Eigen::SelfAdjointEigenSolver<Matrix3d> es(m.cov);
  return {es.eigenvalues().cwiseMax(0.0), es.eigenvectors()};
}

double rmsSize(const Moments& m) { return std::sqrt(std::max(m.cov.trace(), 0.0)); }

double maxDistanceFromLine(const Points3& pts, const Vector3d& c, const Vector3d& d, bool planar) {
  double worst = 0.0;
  for (const auto& p : pts) {
    Vector3d v = p - c;
    if (planar) v.z() = 0.0;
    worst = std::max(worst, (v - d * d.dot(v)).norm());
  }
  return worst;
}

// Points are hashed by their cell of a grid of kCell >> kCoincidentMm; two points within
// kCoincidentMm share a cell unless one lies within kCoincidentMm of a cell face, and only
// then are the neighbouring cells across that face looked at too (about 1 point in 100).
// Open addressing with linear probing over a power-of-two table; an entry holds the cell's
// 64-bit hash and the point's index, and a hit is confirmed by the distance itself.
void checkDuplicates(ElementKind kind, const Points3& pts) {
  constexpr double kPerMm = 1e6;     // cells per mm: 1 nm cells
  constexpr double kLimit = 4.0e18;  // |cell index| that still fits an int64 with room
  const std::size_t n = pts.size();
  const bool planar = isPlanar(kind);
  const int dims = planar ? 2 : 3;
  if (n >= std::numeric_limits<std::uint32_t>::max()) return checkDuplicatesBySorting(kind, pts);
  std::size_t size = 16;
  while (size < 2 * n) size *= 2;
  const std::size_t mask = size - 1;
  struct Entry {
    std::uint32_t key;    // high half of the cell's hash (the low bits give the slot)
    std::uint32_t index;  // point index + 1; 0 marks an empty slot
  };
  std::vector<Entry> table(size, Entry{0, 0});
  auto keyOf = [](std::int64_t a, std::int64_t b, std::int64_t c) {
    std::uint64_t h = static_cast<std::uint64_t>(a) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(b) * 0xC2B2AE3D27D4EB4FULL;
    h ^= static_cast<std::uint64_t>(c) * 0x165667B19E3779F9ULL;
    return h ^ (h >> 29);
  };
  auto lookIn = [&](std::size_t i, std::uint64_t key) {
    const auto high = static_cast<std::uint32_t>(key >> 32);
    for (std::size_t s = key & mask;; s = (s + 1) & mask) {
      const Entry& e = table[s];
      if (e.index == 0) return;
      if (e.key != high) continue;
      const Vector3d d = pts[i] - pts[e.index - 1];
      if ((planar ? d.head<2>().norm() : d.norm()) <= kCoincidentMm)
        reportDuplicate(kind, e.index - 1, i);
    }
  };
  for (std::size_t i = 0; i < n; ++i) {
    std::int64_t cell[3] = {0, 0, 0};
    int side[3] = {0, 0, 0};  // -1 / +1: within kCoincidentMm of the lower / upper face
    for (int c = 0; c < dims; ++c) {
      const double v = pts[i](c) * kPerMm;
      if (!(std::abs(v) < kLimit)) return checkDuplicatesBySorting(kind, pts);
      std::int64_t k = static_cast<std::int64_t>(v);
      if (v < static_cast<double>(k)) --k;  // floor without a libm call
      cell[c] = k;
      const double frac = v - static_cast<double>(k);  // cells above the lower face
      // Twice the tolerance: frac is rounded, and a margin costs nothing.
      if (frac <= 2.0 * kCoincidentMm * kPerMm) side[c] = -1;
      else if (1.0 - frac <= 2.0 * kCoincidentMm * kPerMm) side[c] = 1;
    }
    const std::uint64_t own = keyOf(cell[0], cell[1], cell[2]);
    if (side[0] == 0 && side[1] == 0 && side[2] == 0) {
      lookIn(i, own);
    } else {
      for (int a = 0; a <= (side[0] != 0); ++a)
        for (int b = 0; b <= (side[1] != 0); ++b)
          for (int d = 0; d <= (side[2] != 0); ++d)
            lookIn(i, keyOf(cell[0] + a * side[0], cell[1] + b * side[1], cell[2] + d * side[2]));
    }
    std::size_t s = own & mask;
    while (table[s].index != 0) s = (s + 1) & mask;
    table[s] = Entry{static_cast<std::uint32_t>(own >> 32), static_cast<std::uint32_t>(i + 1)};
  }
}

void checkNotCoincident(ElementKind kind, const Axes& ax, std::size_t n) {
  if (std::sqrt(ax.value(2)) <= kCoincidentMm)
    fail("all " + std::to_string(n) + " " + name(kind) + " points coincide" +
         (isPlanar(kind) ? " in x, y" : "") + " (within " + num(kCoincidentMm) +
         " mm): probe points spread over the " + name(kind));
}

void checkNotCollinear(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                       const std::string& need, const std::string& fix) {
  if (std::sqrt(ax.value(1)) >= kRankTol * std::max(rmsSize(m), 1.0)) return;
  const double dev = maxDistanceFromLine(pts, m.centroid, ax.vec.col(2), isPlanar(kind));
  fail(name(kind) + " needs " + need + "; these " + std::to_string(pts.size()) + " lie within " +
       um(dev) + " of a line: " + fix);
}

void checkNotCoplanar(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax,
                      const std::string& need, const std::string& fix) {
  if (std::sqrt(ax.value(0)) >= kRankTol * std::max(rmsSize(m), 1.0)) return;
  const double dev = maxDistanceFromPlane(pts, m.centroid, ax.vec.col(0));
  fail(name(kind) + " needs " + need + "; these " + std::to_string(pts.size()) + " lie within " +
       um(dev) + " of a plane: " + fix);
}

void checkPlaneDetermined(ElementKind kind, const Points3& pts, const Moments& m, const Axes& ax) {
  const std::size_t n = pts.size();
  checkNotCoincident(kind, ax, n);
  checkNotCollinear(kind, pts, m, ax, ">= 3 non-collinear points", "add a point off that line");
  if (ax.value(1) - ax.value(0) <= 1e-12 * ax.value(2))
    fail(name(kind) + ": the " + std::to_string(n) + " points spread equally in two directions "
         "across a line, so no plane is preferred: probe points over a flat area");
}

// Plane local parameters: offset t along the normal n = e_min, tilts alpha, beta toward the
// principal axes e_max, e_mid. J_i = [-1, e_max.q, e_mid.q] and, the axes being principal,
// J^T J = diag(n, n var_max, n var_mid).
Eigen::Vector3d planeLocalCovariance(const Axes& ax, std::size_t n) {
  const double dn = static_cast<double>(n);
  return {1.0 / dn, 1.0 / (dn * ax.value(2)), 1.0 / (dn * ax.value(1))};
}

Points3 strideSample(const Points3& pts, std::size_t count) {
  Points3 sample;
  sample.reserve(count);
  for (std::size_t i = 0; i < count; ++i) sample.push_back(pts[i * pts.size() / count]);
  return sample;
}

FitResult makeResult(const Element& e, const Points3& pts, int free_parameters,
                     std::vector<std::string> names, const Eigen::MatrixXd& cov, int iterations,
                     const LeastSquaresOptions& o, const ResidualStats* stats) {
  if (!e.position_mm.allFinite() || !e.direction.allFinite() || !std::isfinite(e.radius_mm) ||
      !std::isfinite(e.half_angle_rad))
    fail("least-squares " + name(e.kind) + " fit produced no finite element: the points do not "
         "determine a " + name(e.kind));
  FitResult out;
  out.element = e;
  out.method = FitMethod::LeastSquares;
  if (o.keep_residuals) {
    fillResiduals(out, pts, free_parameters);
  } else {
    ResidualStats st;
    if (stats) {
      st = *stats;
    } else {
      st.min = std::numeric_limits<double>::infinity();
      st.max = -st.min;
      for (const auto& p : pts) {
        const double d = signedDistance(e, p);
        st.ssr += d * d;
        st.min = std::min(st.min, d);
        st.max = std::max(st.max, d);
      }
    }
    const std::size_t n = pts.size();
    out.ssr_mm2 = st.ssr;
    out.rms_mm = std::sqrt(st.ssr / static_cast<double>(n));
    out.form_mm = e.kind == ElementKind::Line3D ? 2.0 * st.max : st.max - st.min;
    out.dof = static_cast<int>(n) - free_parameters;
    out.residual_variance_mm2 = out.dof > 0 ? st.ssr / out.dof : 0.0;
  }
  out.parameter_names = std::move(names);
  out.covariance_unscaled = cov;
  out.iterations = iterations;
  return out;
}

}  // namespace probeloop::geometry::ls
