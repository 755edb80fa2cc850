// Rotary moves of the checking machine (safety_checker.hpp): C turning the level table under
// a still tool (rule rotary-below-clearance), and the table tilted by A or B about its located
// axis line (issue 33, the trunnion's or cradle's swing: rule tilt-swing), where the bodies the
// table carries (sphere, stem, obstacles, the stock's bounding cylinder) and the table itself,
// a disc, are placed by the pose and the tool is checked against them.
//
// Under a tilt the tool's parts are cylinders along the spindle axis seen from the table
// frame: against a sphere the distance is exact, against a vertical cylinder (stem, obstacle,
// stock) it is that of the two axis segments less both radii (the capsules': never more than
// the cylinders' distance, so a clear result is clear), against the table disc the lowest
// point of the part against the table surface where the part reaches over the disc.
#include <algorithm>
#include <cmath>
#include <Eigen/Geometry>

#include "geometry/segment_distance.hpp"
#include "verify/safety_checker.hpp"

namespace probeloop::verify::detail {
namespace {

// Distance of point x from the solid cylinder of radius r along unit u from s0, length L.
double pointToToolCylinder(const Vector3d& x, const Vector3d& s0, const Vector3d& u, double L, double r) {
  const Vector3d v = x - s0;
  const double h = v.dot(u);
  const double dr = std::max((v - h * u).norm() - r, 0.0);
  const double dz = std::max({-h, h - L, 0.0});
  return std::hypot(dr, dz);
}

// 2-D distance of point c from the segment a-b.
double pointSegment2d(const Vector2d& c, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double L2 = ab.squaredNorm();
  const double s = L2 > 0 ? std::clamp((c - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
  return (c - (a + s * ab)).norm();
}

}  // namespace

// --- poses ---

Eigen::Matrix3d Checker::turnRotation(double c_deg) const {
  const double c = m_.c.present ? parts::tableTurnSign(m_.c.positive_is_clockwise) * c_deg * kPi / 180 : 0.0;
  return Eigen::AngleAxisd(c, Vector3d::UnitZ()).toRotationMatrix();
}
Eigen::Matrix3d Checker::tiltRotation(double q_deg) const {
  return Eigen::AngleAxisd(q_deg * kPi / 180, tilt_.direction).toRotationMatrix();
}
Eigen::Matrix3d Checker::tableRotation(double c_deg, double q_deg) const { return tiltRotation(q_deg) * turnRotation(c_deg); }

// A table point x as the machine sees it: P + Rq (Cc + Rc (x - Cc) - P), the tilting body
// carrying C (parts/machine_chain.hpp).
Vector3d Checker::toMachine(const Vector3d& x, double c_deg, double q_deg) const {
  const Vector3d cc(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), 0);
  return tilt_.point + tiltRotation(q_deg) * (cc + turnRotation(c_deg) * (x - cc) - tilt_.point);
}
Vector3d Checker::toTable(const Vector3d& p, double c_deg, double q_deg) const {
  const Vector3d cc(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), 0);
  return cc + turnRotation(c_deg).transpose() * (tilt_.point + tiltRotation(q_deg).transpose() * (p - tilt_.point) - cc);
}

double Checker::tiltedTop(double c_deg, double q_deg) const {
  double top = -kInf;
  for (const auto& s : scene_.spheres) top = std::max(top, toMachine(s.c, c_deg, q_deg).z() + s.r);
  for (const auto& c : scene_.cyls)
    for (double z : {c.z0, c.z1}) top = std::max(top, toMachine(Vector3d(c.c.x(), c.c.y(), z), c_deg, q_deg).z() + c.r);
  if (!scene_.material.empty()) {
    const Vector2d lo = scene_.material.lo(), hi = scene_.material.hi();
    for (double z : {scene_.material.bottom(), scene_.material.maxTop()})
      for (const Vector2d& q : {lo, hi, Vector2d(lo.x(), hi.y()), Vector2d(hi.x(), lo.y())})
        top = std::max(top, toMachine(Vector3d(q.x(), q.y(), z), c_deg, q_deg).z());
  }
  return top;
}

Hit Checker::tiltedDistance(const Tool& tool, const Vector3d& t, double c_deg, double q_deg, Parts which,
                            bool cutting) const {
  const Vector3d tt = toTable(t, c_deg, q_deg);
  const Vector3d u = tableRotation(c_deg, q_deg).transpose() * Vector3d::UnitZ();  // the spindle axis, table frame
  std::vector<Cyl> cyls = scene_.cyls;
  if (!scene_.material.empty()) {
    // The stock as its bounding cylinder: cuts on a tilted table are not modelled.
    const Vector2d lo = scene_.material.lo(), hi = scene_.material.hi();
    cyls.push_back({(lo + hi) / 2, (hi - lo).norm() / 2, scene_.material.bottom(), scene_.material.maxTop(),
                    scene_.material_name});
  }
  const Vector2d axis = m_.c_axis_centre_mm;
  const double table_low = scene_.table_z - kTableDepthMm;
  Hit best;
  auto take = [&](double d, const std::string& part, const std::string& solid) {
    if (d < best.d) best = {d, part, solid};
  };
  for (const ToolPart& p : tool.parts) {
    if (which == Parts::TipOnly && !p.ball) continue;
    if (which == Parts::ExceptTip && p.ball) continue;
    if (p.ball) {
      for (const auto& s : scene_.spheres) take((tt - s.c).norm() - p.r - s.r, p.name, s.name);
      for (const auto& c : cyls) take(pointCyl(tt, c.c, c.r, c.z0, c.z1) - p.r, p.name, c.name);
      take(pointCyl(tt, axis, table_radius_, table_low, scene_.table_z) - p.r, p.name, "the table");
      continue;
    }
    const Vector3d s0 = tt + p.dz0 * u, s1 = tt + p.dz1 * u;
    const double L = p.dz1 - p.dz0;
    for (const auto& s : scene_.spheres) take(pointToToolCylinder(s.c, s0, u, L, p.r) - s.r, p.name, s.name);
    for (const auto& c : cyls) {
      if (cutting && p.cuts && c.name == scene_.material_name) continue;
      take(geometry::segmentDistance(s0, s1, Vector3d(c.c.x(), c.c.y(), c.z0), Vector3d(c.c.x(), c.c.y(), c.z1)) - p.r - c.r,
           p.name, c.name);
    }
    // The table: the part's lowest point against the surface, where the part reaches over the disc.
    const double low = std::min(s0.z(), s1.z()) - p.r * std::sqrt(std::max(0.0, 1 - u.z() * u.z()));
    const double gap = std::max(pointSegment2d(axis, s0.head<2>(), s1.head<2>()) - p.r - table_radius_, 0.0);
    const double above = low - scene_.table_z;
    take(gap > 0 ? std::hypot(gap, std::max(above, 0.0)) : above, p.name, "the table");
  }
  return best;
}

// --- C on the level table ---

double Checker::envelope() const {
  if (envelope_version_ == scene_.material.version()) return envelope_;
  envelope_version_ = scene_.material.version();
  double& env = envelope_;
  env = scene_.material.envelope(m_.c_axis_centre_mm, -kInf);
  for (const auto& s : scene_.spheres) env = std::max(env, (s.c.head<2>() - m_.c_axis_centre_mm).norm() + s.r);
  for (const auto& c : scene_.cyls) env = std::max(env, (c.c - m_.c_axis_centre_mm).norm() + c.r);
  return env;
}

void Checker::checkTurn(const gcode::MachinePosition& to, const Tool& tool, const Motion& mo, bool tilt) {
  const double plane = scene_.clearancePlane();
  const double low = std::min(mo.a.z(), mo.b.z()) + tool.lowest();
  const double r_tool = tool.radiusBelow(plane - std::min(mo.a.z(), mo.b.z()));
  const double rho = std::min((mo.a.head<2>() - m_.c_axis_centre_mm).norm(), (mo.b.head<2>() - m_.c_axis_centre_mm).norm());
  const double env = envelope();
  if (!(tilt || rho - r_tool < env)) return;
  // A tilting axis the machine does not locate: refused below the clearance plane.
  const bool a_moves = std::fabs(to.a_deg - pos_.a_deg) > 1e-9 && std::fabs(to.b_deg - pos_.b_deg) <= 1e-9;
  const std::string axis = tilt ? (a_moves ? "A" : "B") : "C";
  const double from = tilt ? (a_moves ? pos_.a_deg : pos_.b_deg) : pos_.c_deg;
  const double till = tilt ? (a_moves ? to.a_deg : to.b_deg) : to.c_deg;
  add("rotary-below-clearance",
      axis + " moves from " + fmt(from) + " to " + fmt(till) + " deg with the " + (tool.probe ? "probe" : "tool") +
          "'s lowest point at Z " + fmt(low) +
          (tilt ? "" : ", " + fmt(rho - r_tool) + " mm from the C axis, inside the " + fmt(env) + " mm circle the table's bodies sweep"),
      mo.a, "clearance plane Z " + fmt(plane) + " (" + fmt(scene_.clearance) + " mm above the highest body)");
}

// --- the tilting table ---

void Checker::checkSwing(const Tool& tool, const Motion& mo) {
  const Sweep s = sweep(tool, mo, Parts::All, false, kInf, 0.05, kSwingMarginMm);
  if (!s.hit) return;
  const std::string q(1, tilt_.name);
  const bool tilts = std::fabs(mo.q1 - mo.q0) > 1e-9, turns = std::fabs(mo.c1 - mo.c0) > 1e-9;
  std::string moves;
  if (tilts) moves = q + " moves from " + fmt(mo.q0) + " to " + fmt(mo.q1) + " deg";
  if (turns) moves += (tilts ? " and C from " : "C moves from ") + fmt(mo.c0) + " to " + fmt(mo.c1) + " deg";
  if (!tilts) moves += " with the table tilted to " + q + " " + fmt(mo.q0) + " deg";
  const double q_hit = mo.q0 + s.s_hit * (mo.q1 - mo.q0), c_hit = mo.c0 + s.s_hit * (mo.c1 - mo.c0);
  std::string at = q + " " + fmt(q_hit) + " deg";
  if (turns) at += ", C " + fmt(c_hit) + " deg";
  const std::string who = tool.probe ? "the probe's " + s.h.part : "the " + s.h.part + " of T" + std::to_string(tool_);
  std::string what;
  if (s.h.solid == "the table")
    what = s.h.d <= 0 ? who + " is below the table plane tilted to " + at
                      : "the tilting table comes within " + fmt(s.h.d) + " mm of " + who + " at " + at;
  else
    what = s.h.d <= 0 ? "the table swings " + s.h.solid + " into " + who + " at " + at
                      : "the table swings " + s.h.solid + " within " + fmt(s.h.d) + " mm of " + who + " at " + at;
  std::string line = " (" + q + " axis line through ";
  line += tilt_.name == 'B' ? "X" + fmt(tilt_.point.x()) + " Z" + fmt(tilt_.point.z()) + " along Y)"
                            : "Y" + fmt(tilt_.point.y()) + " Z" + fmt(tilt_.point.z()) + " along X)";
  add("tilt-swing", moves + ": " + what, mo.a + s.s_hit * (mo.b - mo.a),
      "clear by " + fmt(kSwingMarginMm, 1) + " mm of what the table carries and of the table, a disc of radius " +
          fmt(table_radius_, 1) + " mm" + line);
}

}  // namespace probeloop::verify::detail
