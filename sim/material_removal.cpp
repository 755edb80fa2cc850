#include "sim/material_removal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/units.hpp"

namespace probeloop::sim {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 2 * kPi;

struct Interval {
  double lo = kInf, hi = -kInf;
  bool empty() const { return !(lo <= hi); }
};

Interval intersect(Interval a, Interval b) { return {std::max(a.lo, b.lo), std::min(a.hi, b.hi)}; }

// s with lo <= a + s b <= hi.
Interval slab(double a, double b, double lo, double hi) {
  if (std::fabs(b) < 1e-15) return a >= lo && a <= hi ? Interval{-kInf, kInf} : Interval{};
  double s0 = (lo - a) / b, s1 = (hi - a) / b;
  if (s0 > s1) std::swap(s0, s1);
  return {s0, s1};
}

// s with |u + s v - c| <= r (2D).
Interval disk(const Vector2d& u, const Vector2d& v, const Vector2d& c, double r) {
  const Vector2d w = u - c;
  const double A = v.squaredNorm(), B = v.dot(w), C = w.squaredNorm() - r * r;
  if (A < 1e-30) return C <= 0 ? Interval{-kInf, kInf} : Interval{};
  const double disc = B * B - A * C;
  if (disc < 0) return {};
  const double q = std::sqrt(disc);
  return {(-B - q) / A, (-B + q) / A};
}

// s with n . (u + s v - c) >= 0 (2D half-plane).
Interval halfPlane(const Vector2d& u, const Vector2d& v, const Vector2d& c, const Vector2d& n) {
  const double g0 = n.dot(u - c), g1 = n.dot(v);
  if (std::fabs(g1) < 1e-15) return g0 >= 0 ? Interval{-kInf, kInf} : Interval{};
  const double s = -g0 / g1;
  return g1 > 0 ? Interval{s, kInf} : Interval{-kInf, s};
}

// s where the 2D line u + s v lies within r of the segment a-b (a capsule: convex, so the
// union of the rectangle's and the two disks' intervals is one interval).
Interval capsule(const Vector2d& u, const Vector2d& v, const Vector2d& a, const Vector2d& b, double r) {
  Interval out = disk(u, v, a, r);
  const Vector2d ab = b - a;
  const double L = ab.norm();
  if (L > 1e-12) {
    const Interval d1 = disk(u, v, b, r);
    const Vector2d e = ab / L, n(-e.y(), e.x());
    const Interval rect = intersect(slab((u - a).dot(e), v.dot(e), 0, L), slab((u - a).dot(n), v.dot(n), -r, r));
    for (const Interval& i : {d1, rect}) {
      if (i.empty()) continue;
      out = out.empty() ? i : Interval{std::min(out.lo, i.lo), std::max(out.hi, i.hi)};
    }
  }
  return out;
}

struct Tagged {
  double lo, hi;
  int tag;
  std::size_t order;  // tie-break: deterministic and independent of the sort's stability
};

Vector2d unit(double a) { return {std::cos(a), std::sin(a)}; }

// The intervals where a line meets one arc piece's swept region {xy within r of the arc,
// z >= bottom}: the annulus sector (the wedge lo..hi is convex for hi - lo <= 90 deg: two
// half-planes) plus the two end disks, plus the disk of radius r - rho about the centre
// when the tool covers the centre. Several intervals; the caller merges them.
template <class Add>
void arcIntervals(const Vector3d& f, const Vector3d& d, const SweptArc& a, Add add) {
  const Interval zi = slab(f.z(), d.z(), a.z_bottom, kInf);
  if (zi.empty()) return;
  const Vector2d u = f.head<2>(), v = d.head<2>();
  auto put = [&](Interval i) {
    i = intersect(i, zi);
    if (!i.empty()) add(i);
  };
  const Vector2d e0 = unit(a.lo_rad), e1 = unit(a.hi_rad);
  put(disk(u, v, a.centre + a.rho * e0, a.radius));
  put(disk(u, v, a.centre + a.rho * e1, a.radius));
  const Interval outer = disk(u, v, a.centre, a.rho + a.radius);
  if (outer.empty()) return;
  // Left of the lo ray and right of the hi ray.
  const Interval wedge = intersect(halfPlane(u, v, a.centre, Vector2d(-e0.y(), e0.x())),
                                   halfPlane(u, v, a.centre, Vector2d(e1.y(), -e1.x())));
  if (a.rho > a.radius) {
    const Interval inner = disk(u, v, a.centre, a.rho - a.radius);
    if (inner.empty()) {
      put(intersect(outer, wedge));
    } else {
      put(intersect(Interval{outer.lo, inner.lo}, wedge));
      put(intersect(Interval{inner.hi, outer.hi}, wedge));
    }
  } else {
    put(intersect(outer, wedge));
    if (a.rho < a.radius) put(disk(u, v, a.centre, a.radius - a.rho));
  }
}

bool boxesOverlap(const Vector2d& alo, const Vector2d& ahi, const Vector2d& blo, const Vector2d& bhi) {
  return alo.x() <= bhi.x() && blo.x() <= ahi.x() && alo.y() <= bhi.y() && blo.y() <= ahi.y();
}

}  // namespace

CcwArc ccwArc(double start, double sweep) {
  CcwArc a;
  a.span = std::min(std::fabs(sweep), kTwoPi);
  a.lo = sweep >= 0 ? start : start - a.span;
  return a;
}

int Stock::cellX(double x) const {
  return std::clamp(static_cast<int>(std::floor((x - min_.x()) / cx_)), 0, nx_ - 1);
}
int Stock::cellY(double y) const {
  return std::clamp(static_cast<int>(std::floor((y - min_.y()) / cy_)), 0, ny_ - 1);
}

Stock::Stock(const Vector3d& min_mm, const Vector3d& max_mm, double cell_mm, bool cylindrical)
    : min_(min_mm), max_(max_mm), cylindrical_(cylindrical) {
  // Cells at most cell_mm, fitting the box exactly (no phantom material past its faces).
  nx_ = std::max(1, static_cast<int>(std::ceil((max_.x() - min_.x()) / cell_mm - 1e-9)));
  ny_ = std::max(1, static_cast<int>(std::ceil((max_.y() - min_.y()) / cell_mm - 1e-9)));
  cx_ = (max_.x() - min_.x()) / nx_;
  cy_ = (max_.y() - min_.y()) / ny_;
  top_.assign(static_cast<std::size_t>(nx_) * ny_, max_.z());
  centre_ = Vector2d((min_.x() + max_.x()) / 2, (min_.y() + max_.y()) / 2);
  blank_radius_ = std::min(max_.x() - min_.x(), max_.y() - min_.y()) / 2;
  if (cylindrical_)
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const Vector2d c(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
        if ((c - centre_).norm() > blank_radius_) top_[static_cast<std::size_t>(j) * nx_ + i] = -kInf;
      }
}

void Stock::addHole(const Vector2d& c, double r, double z_min, double z_max) {
  holes_.push_back({c, r, z_min, z_max});
  if (nx_ == 0 || z_max < max_.z()) return;  // only a hole open at the top shows in the height field
  const int i0 = cellX(c.x() - r), i1 = cellX(c.x() + r), j0 = cellY(c.y() - r), j1 = cellY(c.y() + r);
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const Vector2d p(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
      if ((p - c).norm() > r) continue;
      double& top = top_[static_cast<std::size_t>(j) * nx_ + i];
      top = std::min(top, z_min <= min_.z() ? -kInf : z_min);
    }
}

Removal Stock::removeHeightField(const Vector3d& p0, const Vector3d& p1, double r) {
  Removal out;
  if (nx_ == 0) return out;
  const Vector2d a = p0.head<2>(), b = p1.head<2>(), ab = b - a;
  const double L2 = ab.squaredNorm();
  const bool plunge = L2 < 1e-18;
  const double lo_x = std::min(a.x(), b.x()) - r, hi_x = std::max(a.x(), b.x()) + r;
  const double lo_y = std::min(a.y(), b.y()) - r, hi_y = std::max(a.y(), b.y()) + r;
  const int i0 = cellX(lo_x), i1 = cellX(hi_x), j0 = cellY(lo_y), j1 = cellY(hi_y);
  const double area = cx_ * cy_;
  const double z_low = std::min(p0.z(), p1.z());
  Vector3d moment = Vector3d::Zero();
  // Plain doubles in the loop (the same arithmetic as the vector forms): this is the hot
  // path of every cut, and a Debug build does not inline Eigen's expressions.
  const double ax = a.x(), ay = a.y(), abx = ab.x(), aby = ab.y();
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double& top = top_[static_cast<std::size_t>(j) * nx_ + i];
      if (top <= z_low) continue;  // no material above the path's lowest point: nothing to remove
      const double cx = min_.x() + (i + 0.5) * cx_, cy = min_.y() + (j + 0.5) * cy_;
      const double t = plunge ? 0.0 : std::clamp(((cx - ax) * abx + (cy - ay) * aby) / L2, 0.0, 1.0);
      const double dx = cx - (ax + t * abx), dy = cy - (ay + t * aby);
      if (std::sqrt(dx * dx + dy * dy) > r) continue;
      const double zb = plunge ? z_low : p0.z() + t * (p1.z() - p0.z());
      if (top <= zb || zb >= max_.z()) continue;
      const double from = std::max(zb, min_.z());
      if (top > from) {
        const double v = (top - from) * area;
        out.volume_mm3 += v;
        moment += v * Vector3d(cx, cy, (top + from) / 2);
      }
      top = zb <= min_.z() ? -kInf : zb;  // cut through: no material left in the column
    }
  if (out.volume_mm3 > 0) out.centroid = moment / out.volume_mm3;
  return out;
}

Removal Stock::removeHeightFieldArc(const Vector2d& centre, double rho, double start, double sweep, double zb,
                                    double r) {
  Removal out;
  if (nx_ == 0 || zb >= max_.z()) return out;
  const auto [lo, span] = ccwArc(start, sweep);
  const bool full = span >= kTwoPi - 1e-12;
  const Vector2d e0 = centre + rho * unit(lo), e1 = centre + rho * unit(lo + span);
  const double R = rho + r;
  const int i0 = cellX(centre.x() - R), i1 = cellX(centre.x() + R), j0 = cellY(centre.y() - R), j1 = cellY(centre.y() + R);
  const double area = cx_ * cy_;
  Vector3d moment = Vector3d::Zero();
  double radial_moment = 0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double& top = top_[static_cast<std::size_t>(j) * nx_ + i];
      if (top <= zb) continue;
      const Vector2d c(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
      const Vector2d w = c - centre;
      const double dist_c = w.norm();
      // Distance from the cell centre to the arc: radial where its angle lies within the
      // arc, else to the nearer end point.
      bool within = false;
      if (std::fabs(dist_c - rho) <= r) {
        if (full) {
          within = true;
        } else {
          double ang = std::atan2(w.y(), w.x()) - lo;
          ang -= kTwoPi * std::floor(ang / kTwoPi);
          within = ang <= span;
        }
      }
      if (!within && !full) within = (c - e0).norm() <= r || (c - e1).norm() <= r;
      if (!within) continue;
      const double from = std::max(zb, min_.z());
      if (top > from) {
        const double v = (top - from) * area;
        out.volume_mm3 += v;
        moment += v * Vector3d(c.x(), c.y(), (top + from) / 2);
        radial_moment += v * dist_c;
      }
      top = zb <= min_.z() ? -kInf : zb;
    }
  if (out.volume_mm3 > 0) {
    out.centroid = moment / out.volume_mm3;
    out.mean_radius_mm = radial_moment / out.volume_mm3;
  }
  return out;
}

// Can a swept region with this XY bounding box and bottom reach the blank at all?
bool Stock::reachesBlank(const Vector2d& lo, const Vector2d& hi, double z_bottom) const {
  if (z_bottom >= max_.z()) return false;
  const Vector2d pad(1e-9, 1e-9);
  if (!boxesOverlap(lo - pad, hi + pad, min_.head<2>(), max_.head<2>())) return false;
  if (cylindrical_) {
    // Nearest point of the box to the blank's axis.
    const Vector2d q = centre_.cwiseMax(lo).cwiseMin(hi);
    if ((q - centre_).norm() > blank_radius_ + 1e-9) return false;
  }
  return true;
}

bool Stock::segmentReachesBlank(const Vector3d& p0, const Vector3d& p1, double r) const {
  const Vector2d lo = p0.head<2>().cwiseMin(p1.head<2>()) - Vector2d(r, r), hi = p0.head<2>().cwiseMax(p1.head<2>()) + Vector2d(r, r);
  return reachesBlank(lo, hi, std::min(p0.z(), p1.z()));
}

bool Stock::recordCut(const Vector3d& p0, const Vector3d& p1, double r, double time_s, int tag) {
  const std::size_t before = cuts_.size();
  auto push = [&](const Vector3d& a, const Vector3d& b) {
    SweptCut c{a, b, r, time_s, tag, a.head<2>().cwiseMin(b.head<2>()) - Vector2d(r, r),
               a.head<2>().cwiseMax(b.head<2>()) + Vector2d(r, r)};
    if (reachesBlank(c.lo, c.hi, std::min(a.z(), b.z()))) cuts_.push_back(c);
  };
  const Vector3d d = p1 - p0;
  const double xy = d.head<2>().norm();
  if (xy < 1e-12) {  // plunge: a cylinder from the lowest point up
    const double z = std::min(p0.z(), p1.z());
    push(Vector3d(p0.x(), p0.y(), z), Vector3d(p0.x(), p0.y(), z));
    return cuts_.size() > before;
  }
  if (std::fabs(d.z()) < 1e-12) {
    push(p0, p1);
    return cuts_.size() > before;
  }
  // A ramp: horizontal pieces at their upper Z. The floor error of a piece is its z change,
  // so pieces of 1e-5 mm in z; a table tilted by a few urad turns a horizontal program move
  // into such a ramp in the part frame, and this keeps it to a few pieces per pass. A steep
  // ramp gets one piece per 0.05 mm of length.
  // (less 1e-9 of a piece: 1e-3 / 1e-5 is 100 pieces, not 101 for a last-digit rounding)
  const double by_height = std::ceil(std::fabs(d.z()) / 1e-5 - 1e-9);
  const double by_length = std::ceil(d.norm() / 0.05 - 1e-9);
  const int n = static_cast<int>(std::max(1.0, std::min(by_height, by_length)));
  for (int k = 0; k < n; ++k) {
    Vector3d a = p0 + d * (static_cast<double>(k) / n), b = p0 + d * (static_cast<double>(k + 1) / n);
    const double z = std::max(a.z(), b.z());
    a.z() = z;
    b.z() = z;
    push(a, b);
  }
  return cuts_.size() > before;
}

bool Stock::recordArc(const Vector2d& centre, double rho, double start, double sweep, double zb, double r,
                      double time_s, int tag) {
  const auto [lo, span] = ccwArc(start, sweep);
  if (!(span > 0) || nx_ == 0) return false;
  // The annulus misses the blank: the tool went around it (or the blank around the tool).
  if (zb >= max_.z()) return false;
  {
    const double off = (centre - centre_).norm();
    const double blank_r = cylindrical_ ? blank_radius_ : (max_.head<2>() - min_.head<2>()).norm() / 2;
    if (rho - r > off + blank_r + 1e-9 || off - blank_r > rho + r + 1e-9) return false;
  }
  const std::size_t before = arcs_.size();
  const int n = std::max(1, static_cast<int>(std::ceil(span / (kPi / 2) - 1e-12)));
  // Shared junction angles: the two pieces meeting at a junction compute its half-planes from
  // the same cos/sin, so a line crossing there sees no gap between them.
  std::vector<double> a(static_cast<std::size_t>(n) + 1);
  for (int k = 0; k <= n; ++k) a[static_cast<std::size_t>(k)] = k == n ? lo + span : lo + span * k / n;
  for (int k = 0; k < n; ++k) {
    SweptArc p;
    p.centre = centre;
    p.rho = rho;
    p.radius = r;
    p.lo_rad = a[static_cast<std::size_t>(k)];
    p.hi_rad = a[static_cast<std::size_t>(k) + 1];
    p.z_bottom = zb;
    p.time_s = time_s;
    p.tag = tag;
    // Bounding box: the sector's corners and the axis extremes it contains, padded by r
    // (covers the end disks) and by the centre disk when the tool covers the centre.
    const double ro = rho + r, ri = std::max(0.0, rho - r);
    Vector2d lo_b = centre + ro * unit(p.lo_rad), hi_b = lo_b;
    auto grow = [&](const Vector2d& q) {
      lo_b = lo_b.cwiseMin(q);
      hi_b = hi_b.cwiseMax(q);
    };
    grow(centre + ro * unit(p.hi_rad));
    grow(centre + ri * unit(p.lo_rad));
    grow(centre + ri * unit(p.hi_rad));
    for (int q = static_cast<int>(std::floor(p.lo_rad / (kPi / 2))); q <= static_cast<int>(std::ceil(p.hi_rad / (kPi / 2))); ++q) {
      const double ang = q * (kPi / 2);
      if (ang >= p.lo_rad && ang <= p.hi_rad) grow(centre + ro * unit(ang));
    }
    if (rho < r) grow(centre);
    p.lo = lo_b - Vector2d(r, r);
    p.hi = hi_b + Vector2d(r, r);
    if (reachesBlank(p.lo, p.hi, zb)) arcs_.push_back(p);
  }
  return arcs_.size() > before;
}

double Stock::topUnder(const Vector2d& xy, double r) const {
  double best = -kInf;
  if (nx_ == 0) return best;
  if (xy.x() + r < min_.x() || xy.x() - r > max_.x() || xy.y() + r < min_.y() || xy.y() - r > max_.y()) return best;
  const int i0 = cellX(xy.x() - r), i1 = cellX(xy.x() + r), j0 = cellY(xy.y() - r), j1 = cellY(xy.y() + r);
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double top = top_[static_cast<std::size_t>(j) * nx_ + i];
      if (top <= best) continue;  // cannot raise it (a collision check's hot path: plain doubles)
      const double dx = min_.x() + (i + 0.5) * cx_ - xy.x(), dy = min_.y() + (j + 0.5) * cy_ - xy.y();
      if (std::sqrt(dx * dx + dy * dy) <= r) best = top;
    }
  return best;
}

double Stock::maxMaterialRadius(const Vector2d& axis, double above_z) const {
  auto& o = radius_order_;
  if (!o.ready) {
    const double half_diagonal = std::hypot(cx_, cy_) / 2;
    std::vector<std::pair<double, std::uint32_t>> d;
    d.reserve(top_.size());
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const Vector2d p(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
        d.emplace_back((p - axis).norm() + half_diagonal, static_cast<std::uint32_t>(j * nx_ + i));
      }
    std::sort(d.begin(), d.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    o.axis = axis;
    for (const auto& [r, c] : d) {
      o.radius.push_back(r);
      o.cells.push_back(c);
    }
    o.ready = true;
  }
  const double shift = (axis - o.axis).norm();
  // Material is only ever removed: a leading cell with none left never has any again.
  while (o.first < o.cells.size() && top_[o.cells[o.first]] == -kInf) ++o.first;
  for (std::size_t k = o.first; k < o.cells.size(); ++k)
    if (top_[o.cells[k]] > above_z) return o.radius[k] + shift;
  return -kInf;
}

std::optional<double> Stock::firstMaterial(const Vector3d& f, const Vector3d& d, double max_s) const {
  const auto h = firstMaterialHit(f, d, max_s);
  if (!h) return std::nullopt;
  return h->s;
}

std::optional<Stock::Hit> Stock::firstMaterialHit(const Vector3d& f, const Vector3d& d, double max_s) const {
  if (nx_ == 0) return std::nullopt;
  Interval box{-kInf, kInf};
  for (int k = 0; k < 3; ++k) box = intersect(box, slab(f(k), d(k), min_(k), max_(k)));
  if (cylindrical_) box = intersect(box, disk(f.head<2>(), d.head<2>(), centre_, blank_radius_));
  box = intersect(box, {0.0, max_s});
  if (box.empty()) return std::nullopt;
  // The part of the line that matters, for quick rejection of swept volumes far from it.
  const Vector2d a = (f + box.lo * d).head<2>(), b = (f + box.hi * d).head<2>();
  const Vector2d pad(1e-9, 1e-9);
  const Vector2d seg_lo = a.cwiseMin(b) - pad, seg_hi = a.cwiseMax(b) + pad;
  std::vector<Tagged> removed;
  auto add = [&](const Interval& i, int tag) {
    if (!i.empty() && i.hi >= box.lo && i.lo <= box.hi) removed.push_back({i.lo, i.hi, tag, removed.size()});
  };
  for (const auto& h : holes_) {
    const Interval i = intersect(disk(f.head<2>(), d.head<2>(), h.centre, h.radius), slab(f.z(), d.z(), h.z_min, h.z_max));
    add(i, -1);
  }
  for (const auto& c : cuts_) {
    if (!boxesOverlap(c.lo, c.hi, seg_lo, seg_hi)) continue;
    Interval i = capsule(f.head<2>(), d.head<2>(), c.p0.head<2>(), c.p1.head<2>(), c.radius);
    if (i.empty()) continue;
    i = intersect(i, slab(f.z(), d.z(), c.p0.z(), kInf));
    add(i, c.tag);
  }
  for (const auto& arc : arcs_) {
    if (!boxesOverlap(arc.lo, arc.hi, seg_lo, seg_hi)) continue;
    arcIntervals(f, d, arc, [&](const Interval& i) { add(i, arc.tag); });
  }
  std::sort(removed.begin(), removed.end(),
            [](const Tagged& x, const Tagged& y) { return x.lo != y.lo ? x.lo < y.lo : x.order < y.order; });
  double cur = box.lo;
  int tag = -1;
  for (const auto& i : removed) {
    if (i.lo > cur) break;
    if (i.hi > cur) {
      cur = i.hi;
      tag = i.tag;
    }
  }
  if (cur >= box.hi) return std::nullopt;  // the removed region reaches the exit: no surface
  return Hit{cur, tag};
}

}  // namespace probeloop::sim
