// The bodies and tools the safety verifier models (safety_checker.hpp): distances of vertical
// cylinders, the stock as a height field that the programs' own cuts lower, the probe and the
// part's tools as vertical cylinders and the stylus ball, the scene the test piece puts on the
// table, and how far the tilting table reaches.
#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "parts/stepped_workpiece.hpp"
#include "parts/thermal_test_piece.hpp"
#include "verify/safety_checker.hpp"

namespace probeloop::verify::detail {

double pointCyl(const Vector3d& p, const Vector2d& c, double r, double z0, double z1) {
  const double dr = std::max((p.head<2>() - c).norm() - r, 0.0);
  const double dz = std::max({z0 - p.z(), p.z() - z1, 0.0});
  return std::hypot(dr, dz);
}
double cylCyl(const Vector2d& a, double ra, double a0, double a1, const Cyl& b) {
  const double dh = std::max((a - b.c).norm() - ra - b.r, 0.0);
  const double dz = std::max({a0 - b.z1, b.z0 - a1, 0.0});
  return std::hypot(dh, dz);
}

std::string fmt(double v, int dec) { return formatNumber(std::fabs(v) < 0.5 * std::pow(10.0, -dec) ? 0.0 : v, dec); }
std::string xyz(const Vector3d& p) { return "X" + fmt(p.x()) + " Y" + fmt(p.y()) + " Z" + fmt(p.z()); }

// --- the height field ---

HeightField::HeightField(const Vector2d& lo, const Vector2d& hi, double cell, double bottom)
    : lo_(lo), cell_(cell), bottom_(bottom) {
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)));
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)));
  top_.assign(static_cast<std::size_t>(nx_) * ny_, -kInf);
  row_max_.assign(static_cast<std::size_t>(ny_), -kInf);
  row_dirty_.assign(static_cast<std::size_t>(ny_), 1);
}

double HeightField::maxTop() const {
  if (dirty_) {
    max_top_ = -kInf;
    for (int j = 0; j < ny_; ++j) {
      if (row_dirty_[j]) {
        double m = -kInf;
        for (int i = 0; i < nx_; ++i) m = std::max(m, at(i, j));
        row_max_[j] = m;
        row_dirty_[j] = 0;
      }
      max_top_ = std::max(max_top_, row_max_[j]);
    }
    dirty_ = false;
  }
  return max_top_;
}

void HeightField::touched(int j0, int j1) {
  for (int j = j0; j <= j1; ++j) row_dirty_[j] = 1;
  dirty_ = true;
  ++version_;
}

template <class F>
void HeightField::around(const Vector2d& xy, double reach, F f) const {
  if (empty()) return;
  const int i0 = std::max(0, static_cast<int>(std::floor((xy.x() - reach - lo_.x()) / cell_)));
  const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((xy.x() + reach - lo_.x()) / cell_)));
  const int j0 = std::max(0, static_cast<int>(std::floor((xy.y() - reach - lo_.y()) / cell_)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((xy.y() + reach - lo_.y()) / cell_)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double t = at(i, j);
      if (t == -kInf) continue;
      f(centre(i, j), t);
    }
}

double HeightField::distCyl(const Vector2d& xy, double r, double z0, double z1, double cap, double tol) const {
  if (empty() || z0 - maxTop() + tol >= cap || bottom_ - z1 >= cap) return cap;
  double best = cap;
  around(xy, r + cap, [&](const Vector2d& q, double top) {
    const double dh = std::max((q - xy).norm() - (r - tol), 0.0);
    if (dh >= best) return;
    const double dz = std::max({bottom_ - z1, z0 - top + tol, 0.0});
    best = std::min(best, std::hypot(dh, dz));
  });
  return best;
}

double HeightField::distBall(const Vector3d& c, double r, double cap, double tol) const {
  if (empty() || c.z() - r - maxTop() + tol >= cap) return cap;
  double best = cap;
  around(c.head<2>(), r + cap, [&](const Vector2d& q, double top) {
    const double dzs = std::max({bottom_ - c.z(), c.z() - top, 0.0});
    best = std::min(best, std::max(0.0, std::hypot((q - c.head<2>()).norm(), dzs) - r + tol));
  });
  return best;
}

void HeightField::cut(const Vector2d& a, const Vector2d& b, double r, double z) {
  if (empty() || z >= maxTop()) return;
  const Vector2d mid = (a + b) / 2;
  const double reach = (b - a).norm() / 2 + r;
  const Vector2d ab = b - a;
  const double L2 = ab.squaredNorm();
  bool changed = false;
  const int i0 = std::max(0, static_cast<int>(std::floor((mid.x() - reach - lo_.x()) / cell_)));
  const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((mid.x() + reach - lo_.x()) / cell_)));
  const int j0 = std::max(0, static_cast<int>(std::floor((mid.y() - reach - lo_.y()) / cell_)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((mid.y() + reach - lo_.y()) / cell_)));
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      double& t = at(i, j);
      if (t <= z) continue;
      const Vector2d q = centre(i, j);
      const double s = L2 > 0 ? std::clamp((q - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
      if ((q - (a + s * ab)).norm() > r) continue;
      t = z <= bottom_ ? -kInf : z;
      changed = true;
    }
  if (changed) touched(j0, j1);
}

double HeightField::envelope(const Vector2d& axis, double z) const {
  double r = -kInf;
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i)
      if (at(i, j) > z) r = std::max(r, (centre(i, j) - axis).norm() + cell_ * 0.7072);
  return r;
}

// --- the tilting axis ---

TiltAxis tiltAxisOf(const parts::Machine& m) {
  TiltAxis t;
  // parts/machine_chain.cpp: the tilting body turns by +q about -X / -Y when +A / +B turns it
  // clockwise seen from +X / +Y, about +X / +Y otherwise.
  if (m.b.present) {
    t.name = 'B';
    t.direction = Vector3d::UnitY() * (m.b.positive_is_clockwise ? -1.0 : 1.0);
    if (m.b_axis_centre_xz_mm) {
      t.located = true;
      t.point = Vector3d(m.b_axis_centre_xz_mm->x(), 0, m.b_axis_centre_xz_mm->y());
    }
  } else if (m.a.present) {
    t.name = 'A';
    t.direction = Vector3d::UnitX() * (m.a.positive_is_clockwise ? -1.0 : 1.0);
    if (m.a_axis_centre_yz_mm) {
      t.located = true;
      t.point = Vector3d(0, m.a_axis_centre_yz_mm->x(), m.a_axis_centre_yz_mm->y());
    }
  }
  return t;
}

// --- the checking machine: tools and scene ---

Checker::Checker(const parts::Machine& m, const parts::TestPiece& piece, const Options& o) : m_(m), o_(o) {
  buildTools(piece);
  buildScene(piece);
  tilt_ = tiltAxisOf(m);
  buildTiltReach();
  pos_.xyz_mm = Vector3d(std::clamp(m.c_axis_centre_mm.x(), m.x.min_mm, m.x.max_mm),
                         std::clamp(m.c_axis_centre_mm.y(), m.y.min_mm, m.y.max_mm), m.z.max_mm);
}

const Tool& Checker::toolOf(int n) const {
  static const Tool empty;
  if (n == -1 || n == m_.tool_change.empty_tool) return empty;
  const auto it = tools_.find(n);
  if (it == tools_.end())
    throw InputError("", 0, "T" + std::to_string(n) + " is neither the machine's probe (T" + std::to_string(m_.probe.tool) +
                                ") nor a tool of the part description");
  return it->second;
}

void Checker::buildTools(const parts::TestPiece& piece) {
  Tool p;
  p.number = m_.probe.tool;
  p.probe = true;
  p.length = m_.probe.length_mm;
  // A piece probed with a stylus of its own (the stepped workpiece's 2 mm ball): that ball,
  // and a shaft no thicker than 0.75 x it.
  double tip = m_.probe.tip_diameter_mm, shaft = m_.probe.stylus_diameter_mm;
  if (piece.stock && piece.stock->probe_tip_diameter_mm > 0) {
    tip = piece.stock->probe_tip_diameter_mm;
    shaft = std::min(shaft, 0.75 * tip);
  }
  p.parts = {{"stylus tip", true, tip / 2, 0, 0, false},
             {"stylus shaft", false, shaft / 2, 0, m_.probe.stylus_length_mm, false},
             {"probe body", false, m_.probe.body_diameter_mm / 2, m_.probe.stylus_length_mm, m_.probe.length_mm, false}};
  tools_[p.number] = p;
  if (!piece.stock) return;
  for (const auto& t : piece.stock->tools) {
    Tool c;
    c.number = t.number;
    c.cutter = true;
    c.length = t.length_mm;
    const double r = t.diameter_mm / 2;
    const double flutes = std::min(t.flute_length_mm > 0 ? t.flute_length_mm : t.stickout_mm, t.length_mm);
    const double stick = std::clamp(t.stickout_mm > 0 ? t.stickout_mm : flutes, flutes, t.length_mm);
    c.parts.push_back({"cutter", false, r, 0, flutes, true});
    if (stick > flutes) c.parts.push_back({"shank", false, r, flutes, stick, false});
    if (t.length_mm > stick) c.parts.push_back({"holder", false, m_.tool_change.holder_diameter_mm / 2, stick, t.length_mm, false});
    tools_[c.number] = c;
  }
}

void Checker::buildScene(const parts::TestPiece& piece) {
  scene_.table_z = m_.table_surface_z_mm;
  scene_.clearance = 5;
  if (const auto* a = piece.sphereArtifact()) {
    const double th = a->angle_at_c0_deg * kPi / 180;
    const Vector3d c(m_.c_axis_centre_mm.x() + a->radius_from_axis_mm * std::cos(th),
                     m_.c_axis_centre_mm.y() + a->radius_from_axis_mm * std::sin(th),
                     m_.table_surface_z_mm + a->centreHeightAboveTable());
    scene_.spheres.push_back({c, a->sphereRadius(), "the sphere of the artifact"});
    scene_.cyls.push_back({c.head<2>(), a->stem_diameter_mm / 2, m_.table_surface_z_mm, c.z() - a->sphereRadius(),
                           "the artifact's stem"});
    scene_.clearance = a->clearance_mm;
    return;
  }
  if (!piece.stock) return;
  const parts::Workpiece& w = *piece.stock;
  Vector3d origin = w.frame_origin_mm;
  if (const auto* t = piece.thermalTestPiece()) {
    origin = parts::partOriginOnMachine(*t, m_.c_axis_centre_mm, m_.table_surface_z_mm);
    scene_.clearance = t->probing.clearance_mm;
  } else if (const auto* sw = piece.steppedWorkpiece()) {
    origin = parts::steppedWorkpieceOrigin(*sw, m_);
    scene_.clearance = sw->machining.clearance_mm;
  }
  for (const auto& o : w.obstacles)
    scene_.cyls.push_back({o.centre_mm + origin.head<2>(), o.radius_mm, o.z_min_mm + origin.z(), o.z_max_mm + origin.z(),
                           "the " + o.name});
  const Vector3d lo = w.stock_min_mm + origin, hi = w.stock_max_mm + origin;
  scene_.material = HeightField(lo.head<2>(), hi.head<2>(), o_.cell_mm, lo.z());
  scene_.material_name = "the stock";
  const Vector2d cc = (lo.head<2>() + hi.head<2>()) / 2;
  const double cr = (hi.x() - lo.x()) / 2;
  auto& hf = scene_.material;
  for (int j = 0; j < hf.ny(); ++j)
    for (int i = 0; i < hf.nx(); ++i) {
      const Vector2d q = hf.centre(i, j);
      const bool in = w.cylindrical ? (q - cc).norm() <= cr
                                    : q.x() >= lo.x() && q.x() <= hi.x() && q.y() >= lo.y() && q.y() <= hi.y();
      if (!in) continue;
      double top = hi.z();
      for (const auto& h : w.holes)  // only a hole open at the top shows from above
        if (h.z_max_mm + origin.z() >= hi.z() - 1e-9 && (q - h.centre_mm - origin.head<2>()).norm() <= h.radius_mm)
          top = std::min(top, h.z_min_mm + origin.z() <= lo.z() + 1e-9 ? -kInf : h.z_min_mm + origin.z());
      hf.at(i, j) = top;
    }
  hf.touched(0, hf.ny() - 1);
}

// The table disc's radius and how far the bodies reach from C and from the tilting axis line:
// bounds of how fast a body point moves when the table turns or tilts (the swing's advancement).
void Checker::buildTiltReach() {
  const Vector2d axis = m_.c_axis_centre_mm;
  double r = 0, top = scene_.table_z;
  for (const auto& s : scene_.spheres) {
    r = std::max(r, (s.c.head<2>() - axis).norm() + s.r);
    top = std::max(top, s.c.z() + s.r);
  }
  for (const auto& c : scene_.cyls) {
    r = std::max(r, (c.c - axis).norm() + c.r);
    top = std::max(top, c.z1);
  }
  if (!scene_.material.empty()) {
    const Vector2d lo = scene_.material.lo(), hi = scene_.material.hi();
    for (const Vector2d& q : {lo, hi, Vector2d(lo.x(), hi.y()), Vector2d(hi.x(), lo.y())}) r = std::max(r, (q - axis).norm());
    top = std::max(top, scene_.material.maxTop());
  }
  table_radius_ = r + kTableRimMm;
  reach_c_ = table_radius_;
  if (!tilt_.located) return;
  // Every body point lies within reach_c_ of the C axis, between the table's bottom and the
  // highest top: its distance from the tilting axis line is at most that of the C axis's points
  // at those heights plus reach_c_.
  const Vector3d& d = tilt_.direction;
  for (double z : {scene_.table_z - kTableDepthMm, top}) {
    const Vector3d p(axis.x(), axis.y(), z);
    const Vector3d v = p - tilt_.point;
    reach_tilt_ = std::max(reach_tilt_, (v - v.dot(d) * d).norm() + reach_c_);
  }
}

}  // namespace probeloop::verify::detail
