#include "sim/material_removal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace probeloop::sim {

using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

}  // namespace

int Stock::cellX(double x) const {
  return std::clamp(static_cast<int>(std::floor((x - min_.x()) / cx_)), 0, nx_ - 1);
}
int Stock::cellY(double y) const {
  return std::clamp(static_cast<int>(std::floor((y - min_.y()) / cy_)), 0, ny_ - 1);
}

Stock::Stock(const Vector3d& min_mm, const Vector3d& max_mm, double cell_mm) : min_(min_mm), max_(max_mm) {
  // Cells at most cell_mm, fitting the box exactly (no phantom material past its faces).
  nx_ = std::max(1, static_cast<int>(std::ceil((max_.x() - min_.x()) / cell_mm - 1e-9)));
  ny_ = std::max(1, static_cast<int>(std::ceil((max_.y() - min_.y()) / cell_mm - 1e-9)));
  cx_ = (max_.x() - min_.x()) / nx_;
  cy_ = (max_.y() - min_.y()) / ny_;
  top_.assign(static_cast<std::size_t>(nx_) * ny_, max_.z());
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
  Vector3d moment = Vector3d::Zero();
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const Vector2d c(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
      const double t = plunge ? 0.0 : std::clamp((c - a).dot(ab) / L2, 0.0, 1.0);
      if ((c - (a + t * ab)).norm() > r) continue;
      const double zb = plunge ? std::min(p0.z(), p1.z()) : p0.z() + t * (p1.z() - p0.z());
      double& top = top_[static_cast<std::size_t>(j) * nx_ + i];
      if (top <= zb || zb >= max_.z()) continue;
      const double from = std::max(zb, min_.z());
      if (top > from) {
        const double v = (top - from) * area;
        out.volume_mm3 += v;
        moment += v * Vector3d(c.x(), c.y(), (top + from) / 2);
      }
      top = zb <= min_.z() ? -kInf : zb;  // cut through: no material left in the column
    }
  if (out.volume_mm3 > 0) out.centroid = moment / out.volume_mm3;
  return out;
}

void Stock::recordCut(const Vector3d& p0, const Vector3d& p1, double r, double time_s) {
  const Vector3d d = p1 - p0;
  const double xy = d.head<2>().norm();
  if (xy < 1e-12) {  // plunge: a cylinder from the lowest point up
    const double z = std::min(p0.z(), p1.z());
    cuts_.push_back({Vector3d(p0.x(), p0.y(), z), Vector3d(p0.x(), p0.y(), z), r, time_s});
    return;
  }
  if (std::fabs(d.z()) < 1e-12) {
    cuts_.push_back({p0, p1, r, time_s});
    return;
  }
  const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / 0.1)));
  for (int k = 0; k < n; ++k) {
    Vector3d a = p0 + d * (static_cast<double>(k) / n), b = p0 + d * (static_cast<double>(k + 1) / n);
    const double z = std::max(a.z(), b.z());
    a.z() = z;
    b.z() = z;
    cuts_.push_back({a, b, r, time_s});
  }
}

double Stock::topUnder(const Vector2d& xy, double r) const {
  double best = -kInf;
  if (nx_ == 0) return best;
  if (xy.x() + r < min_.x() || xy.x() - r > max_.x() || xy.y() + r < min_.y() || xy.y() - r > max_.y()) return best;
  const int i0 = cellX(xy.x() - r), i1 = cellX(xy.x() + r), j0 = cellY(xy.y() - r), j1 = cellY(xy.y() + r);
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const Vector2d c(min_.x() + (i + 0.5) * cx_, min_.y() + (j + 0.5) * cy_);
      if ((c - xy).norm() <= r) best = std::max(best, top_[static_cast<std::size_t>(j) * nx_ + i]);
    }
  return best;
}

std::optional<double> Stock::firstMaterial(const Vector3d& f, const Vector3d& d, double max_s) const {
  if (nx_ == 0) return std::nullopt;
  Interval box{-kInf, kInf};
  for (int k = 0; k < 3; ++k) box = intersect(box, slab(f(k), d(k), min_(k), max_(k)));
  box = intersect(box, {0.0, max_s});
  if (box.empty()) return std::nullopt;
  std::vector<Interval> removed;
  for (const auto& c : cuts_) {
    Interval i = capsule(f.head<2>(), d.head<2>(), c.p0.head<2>(), c.p1.head<2>(), c.radius);
    if (i.empty()) continue;
    i = intersect(i, slab(f.z(), d.z(), c.p0.z(), kInf));
    if (!i.empty() && i.hi >= box.lo && i.lo <= box.hi) removed.push_back(i);
  }
  std::sort(removed.begin(), removed.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
  double cur = box.lo;
  for (const auto& i : removed) {
    if (i.lo > cur) break;
    cur = std::max(cur, i.hi);
  }
  if (cur >= box.hi) return std::nullopt;  // the removed region reaches the exit: no surface
  return cur;
}

}  // namespace probeloop::sim
