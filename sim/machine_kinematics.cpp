// Where things really are on the virtual machine: the tool-side errors (drift, the linear
// axes' geometric errors with their Abbe levers, scale, lost motion, squareness), the tip,
// the table's location errors and the sphere artifact on it; and the checks of travel, feed
// and collisions with the artifact. The class: sim/virtual_machine_detail.hpp.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "geometry/kinematic_chain.hpp"
#include "geometry/segment_distance.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim::detail {

namespace {

double poly(const std::vector<double>& c, double x) {
  double v = 0;
  for (std::size_t k = c.size(); k-- > 0;) v = v * x + c[k];
  return v;
}

}  // namespace

Vector3d VirtualMachine::toolDriftUm() const {
  Vector3d d(tr_.static_errors.tool_um[0], tr_.static_errors.tool_um[1], tr_.static_errors.tool_um[2]);
  if (tr_.thermal.present)
    for (int i = 0; i < net_.size(); ++i)
      for (int k = 0; k < 3; ++k) d(k) += tr_.thermal.per_node_K[i].tool_um[k] * nodeRise(i);
  d.z() += settlingUm();
  return d + atc_um_;
}

// A move from pos_ to `to` lasting dt_s winds each moving axis's drive up against its
// direction, in proportion to the axis's speed (capped); a still axis keeps what its last
// move left (MachineTruth::lost_motion_um_per_m_per_min).
void VirtualMachine::noteAxesMotion(const Vector3d& to, double dt_s) {
  if (tr_.lost_motion_um_per_m_per_min == Vector3d::Zero() || !(dt_s > 0)) return;
  for (int k = 0; k < 3; ++k) {
    const double dk = to(k) - pos_.xyz_mm(k);
    lost_motion_moving_[k] = std::fabs(dk) >= 1e-9;
    if (!lost_motion_moving_[k]) continue;
    const double v_m_per_min = std::fabs(dk) / dt_s * 60.0 / 1000.0;
    const double lag = std::min(tr_.lost_motion_um_per_m_per_min(k) * v_m_per_min, tr_.lost_motion_max_um);
    lost_motion_um_(k) = dk > 0 ? -lag : lag;
  }
}

// The axes' scale errors now: static plus each node's per kelvin of its rise (um per mm).
Vector3d VirtualMachine::scaleUmPerMm() const {
  Vector3d s(tr_.static_errors.scale_um_per_mm[0], tr_.static_errors.scale_um_per_mm[1],
             tr_.static_errors.scale_um_per_mm[2]);
  if (tr_.thermal.present)
    for (int i = 0; i < net_.size(); ++i)
      for (int k = 0; k < 3; ++k) s(k) += tr_.thermal.per_node_K[i].scale_um_per_mm[k] * nodeRise(i);
  return s;
}

std::array<double, 7> VirtualMachine::locationErrors() const {
  auto v = tr_.static_errors.location;
  const auto kf = tr_.keyframeAt(t_).values();
  for (int j = 0; j < 7; ++j) v[j] += kf[j];
  if (tr_.thermal.present)
    for (int i = 0; i < net_.size(); ++i)
      for (int j = 0; j < 7; ++j) v[j] += tr_.thermal.per_node_K[i].location[j] * nodeRise(i);
  return v;
}

std::array<double, 6> VirtualMachine::tiltLocationErrors() const {
  auto v = tr_.static_errors.tilt_location;
  if (tr_.thermal.present)
    for (int i = 0; i < net_.size(); ++i)
      for (int j = 0; j < 6; ++j) v[j] += tr_.thermal.per_node_K[i].tilt_location[j] * nodeRise(i);
  return v;
}

Eigen::Isometry3d VirtualMachine::tiltTransform() const {
  const auto e = tiltLocationErrors();
  const bool on_a = m_.a.present;
  const double q = on_a ? pos_.a_deg : pos_.b_deg;
  const bool errors = std::any_of(e.begin(), e.end(), [](double v) { return v != 0; });
  if (q == 0 && !errors) return Eigen::Isometry3d::Identity();
  const auto& centre = on_a ? m_.a_axis_centre_yz_mm : m_.b_axis_centre_xz_mm;
  if (!centre)
    throw SafetyError(std::string("the table is tilted (") + (on_a ? "A " : "B ") + formatNumber(q) + " deg) but " + m_.file +
                      " does not say where the " + (on_a ? "A axis lies (a_axis: centre_y" : "B axis lies (b_axis: centre_x") +
                      ", centre_z)");
  // The tilting axis's line with its location errors, as the evaluation's chain has it
  // (ISO 230-7: the table turns about the displaced and tilted line; parts/machine_chain.hpp).
  geometry::Joint j;
  j.kind = geometry::JointKind::Rotary;
  j.axis = on_a ? "A" : "B";
  const parts::RotaryAxis& ax = on_a ? m_.a : m_.b;
  j.direction = (on_a ? Vector3d::UnitX() : Vector3d::UnitY()) * (ax.positive_is_clockwise ? -1.0 : 1.0);
  j.point_mm = on_a ? Vector3d(0, centre->x(), centre->y()) : Vector3d(centre->x(), 0, centre->y());
  geometry::Twist t;
  t.translation_mm = Vector3d(e[0], e[1], e[2]) * 1e-3;
  t.rotation_rad = Vector3d(e[3], e[4], e[5]) * 1e-6;
  return geometry::rotaryJointTransform(j, q, t);
}

double VirtualMachine::tipRadius() const {
  // A piece may name its own stylus (the stepped workpiece's d2 ball); else the machine's.
  if (tool_ == m_.probe.tool)
    return (w_ && w_->probe_tip_diameter_mm > 0 ? w_->probe_tip_diameter_mm : m_.probe.tip_diameter_mm) / 2;
  if (const auto* t = cutter()) return t->diameter_mm / 2;
  return 0.0;
}

// Tool-side error of the tip (mm) at a commanded gauge-line position.
Vector3d VirtualMachine::toolError(const Vector3d& g) const {
  Vector3d d = toolDriftUm() * 1e-3;
  if (tr_.axes.any) {
    // Abbe levers: a tool-side axis's angular error turns the tool about the gauge line
    // (lever gauge line -> tip); a workpiece-side axis's turns the table about its surface
    // under the tip (lever table -> tip). Errors are tool-relative-to-workpiece (ISO 230-1).
    const double tip_z = g.z() - currentToolLength();
    const Vector3d tool_lever(0, 0, -currentToolLength()), table_lever(0, 0, tip_z - m_.table_surface_z_mm);
    for (int ax = 0; ax < 3; ++ax) {
      const auto& c = tr_.axes.coeff[ax];
      const double p = g(ax);
      Vector3d trans(poly(c[0], p), poly(c[1], p), poly(c[2], p));
      Vector3d rot(poly(c[3], p), poly(c[4], p), poly(c[5], p));
      d += trans * 1e-3 + (rot * 1e-6).cross(m_.workpiece_side[ax] ? table_lever : tool_lever);
    }
  }
  // Scale errors (static and thermal): EXX = s x at the machine coordinate.
  d += scaleUmPerMm().cwiseProduct(g) * 1e-3;
  d += lost_motion_um_ * 1e-3;
  // Squareness as right-hand rotations of the Y and Z axes (docs/simulator.md).
  d.x() += -tr_.EC0Y_urad * 1e-6 * g.y() + tr_.EB0Z_urad * 1e-6 * g.z();
  d.y() += -tr_.EA0Z_urad * 1e-6 * g.z();
  return d;
}

// The axes stand at the commanded position plus the live loop's external offsets (zero without one).
Vector3d VirtualMachine::tipActual(const Vector3d& gauge) const {
  const Vector3d axes = gauge + offset_mm_;
  return axes - Vector3d(0, 0, currentToolLength()) + toolError(axes);
}

VirtualMachine::Artifact VirtualMachine::artifact() const {
  Artifact art;
  art.dT = nodeRise(tr_.artifact.node);
  const double grow = 1.0 + partAlpha() * art.dT;
  const double th = degToRad(a_->angle_at_c0_deg + cSense() * pos_.c_deg);
  const Vector3d& pe = tr_.artifact.placement_error_mm;
  const Eigen::Vector2d pe_turned = parts::turnedByTable(pe.head<2>(), pos_.c_deg, m_.c.positive_is_clockwise);
  const Vector3d placement(pe_turned.x(), pe_turned.y(), pe.z());
  const Vector3d nominal(m_.c_axis_centre_mm.x() + a_->radius_from_axis_mm * grow * std::cos(th),
                         m_.c_axis_centre_mm.y() + a_->radius_from_axis_mm * grow * std::sin(th),
                         m_.table_surface_z_mm + a_->centreHeightAboveTable() * grow);
  art.location = locationErrors();
  art.centre = geometry::displacedOnTable(nominal + placement, m_.c_axis_centre_mm,
                                          geometry::LocationErrors::fromValues(art.location));
  art.radius = a_->sphereRadius() * grow;
  art.stem_radius = a_->stem_diameter_mm / 2;
  art.table_z = m_.table_surface_z_mm;
  art.table_point = Vector3d(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), m_.table_surface_z_mm);
  const Eigen::Isometry3d tilt = tiltTransform();
  if (!tilt.isApprox(Eigen::Isometry3d::Identity(), 0.0)) {
    art.centre = tilt * art.centre;
    art.table_point = tilt * art.table_point;
    art.up = tilt.linear() * Vector3d::UnitZ();
  }
  return art;
}

void VirtualMachine::checkStemAndTable(const Vector3d& a, const Vector3d& b, const Artifact& art,
                                       const std::string& what) const {
  const double r = tipRadius();
  if (art.up != Vector3d::UnitZ()) {
    // A tilted table: the stem along its normal, the tip above its plane.
    const double h = (art.centre - art.table_point).dot(art.up);
    if (geometry::segmentDistance(a, b, art.centre - h * art.up, art.centre - art.radius * art.up) < art.stem_radius + r - 1e-9)
      throw SafetyError(what + " would hit the artifact's stem");
    const double above = std::min((a - art.table_point).dot(art.up), (b - art.table_point).dot(art.up));
    if (above - r < -1e-9)
      throw SafetyError(what + " would hit the tilted table: tip " + formatNumber(above, 4) + " mm above its plane, radius " +
                        formatNumber(r, 4) + " mm");
    return;
  }
  const Vector3d stem_top(art.centre.x(), art.centre.y(), art.centre.z() - art.radius);
  const Vector3d stem_bottom(art.centre.x(), art.centre.y(), art.table_z);
  if (geometry::segmentDistance(a, b, stem_bottom, stem_top) < art.stem_radius + r - 1e-9)
    throw SafetyError(what + " would hit the artifact's stem");
  if (std::min(a.z(), b.z()) - r < art.table_z - 1e-9)
    throw SafetyError(what + " would hit the table: tip at Z " + formatNumber(std::min(a.z(), b.z()), 4) +
                      " mm, radius " + formatNumber(r, 4) + " mm, table surface Z " + formatNumber(art.table_z, 4));
}

// A non-probing move must not touch anything.
void VirtualMachine::checkPath(const MachinePosition& to, const std::string& what) const {
  if (w_) return checkWorkpiecePath(to, what);
  if (!a_) return;
  const Artifact art = artifact();
  if (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg || to.a_deg != pos_.a_deg) {
    // The table turns under a still tip: it must be clear of the sphere's circle.
    const Vector3d tip = tipActual(pos_.xyz_mm);
    if (tip.z() - tipRadius() < art.centre.z() + art.radius + 1e-9) {
      const double r_tip = std::hypot(tip.x() - m_.c_axis_centre_mm.x(), tip.y() - m_.c_axis_centre_mm.y());
      const double r_art = std::hypot(art.centre.x() - m_.c_axis_centre_mm.x(), art.centre.y() - m_.c_axis_centre_mm.y());
      if (std::fabs(r_tip - r_art) < art.radius + tipRadius())
        throw SafetyError(what + " turns the table while the tip is below the top of the sphere at its radius");
    }
    if (to.xyz_mm == pos_.xyz_mm) return;
  }
  const Vector3d a = tipActual(pos_.xyz_mm), b = tipActual(to.xyz_mm);
  const double Rt = art.radius + tipRadius();
  // After a trigger the stylus is deflected into the surface by pre-travel, delay and
  // overshoot (< 0.5 mm); a move that leaves from there outward is the retract.
  const bool retract = (a - art.centre).norm() > Rt - 0.5 && (a - art.centre).dot(b - a) >= 0;
  if (!retract && geometry::segmentDistance(a, b, art.centre, art.centre) < Rt - 1e-9)
    throw SafetyError(what + " would pass through the sphere artifact");
  checkStemAndTable(a, b, art, what);
}

void VirtualMachine::checkFeed(double F) const {
  const double fmax = std::min({m_.x.max_feed_mm_per_min, m_.y.max_feed_mm_per_min, m_.z.max_feed_mm_per_min});
  if (F > fmax + 1e-9)
    throw SafetyError("feed F" + formatNumber(F) + " exceeds the machine's maximum feed " + formatNumber(fmax) + " mm/min");
}

void VirtualMachine::checkRotaryFeed(const MachinePosition& to, double F_deg_per_min) const {
  const double rpm = F_deg_per_min / 360.0;
  auto check = [&](const parts::RotaryAxis& ax, const char* name, double delta) {
    if (delta == 0) return;
    const double limit = ax.max_turning_speed_rpm > 0 ? ax.max_turning_speed_rpm : ax.max_speed_rpm;
    if (rpm > limit + 1e-9)
      throw SafetyError(std::string("rotary feed F") + formatNumber(F_deg_per_min) + " deg/min (" + formatNumber(rpm) +
                        " rpm) exceeds the " + name + " axis's maximum turning speed " + formatNumber(limit) + " rpm");
  };
  check(m_.c, "C", to.c_deg - pos_.c_deg);
  check(m_.b, "B", to.b_deg - pos_.b_deg);
}

void VirtualMachine::checkTravel(const MachinePosition& to) const {
  const parts::LinearAxis* ax[] = {&m_.x, &m_.y, &m_.z};
  const char* names[] = {"X", "Y", "Z"};
  for (int k = 0; k < 3; ++k)
    if (!(to.xyz_mm(k) >= ax[k]->min_mm - 1e-9 && to.xyz_mm(k) <= ax[k]->max_mm + 1e-9))
      throw SafetyError(std::string("move outside travel: ") + names[k] + " " + formatNumber(to.xyz_mm(k)) +
                        " mm (gauge line, machine coordinates) is outside [" + formatNumber(ax[k]->min_mm) +
                        ", " + formatNumber(ax[k]->max_mm) + "]");
  if (to.b_deg != 0 && !m_.b.present) throw SafetyError("move of B on a machine without a B axis");
  if (!std::isfinite(to.b_deg) || !std::isfinite(to.c_deg)) throw SafetyError("a rotary target that is not a number");
  if (m_.b.present && !m_.b.continuous && !(to.b_deg >= m_.b.min_deg - 1e-9 && to.b_deg <= m_.b.max_deg + 1e-9))
    throw SafetyError("move outside travel: B " + formatNumber(to.b_deg) + " deg");
  if (to.c_deg != 0 && !m_.c.present) throw SafetyError("move of C on a machine without a C axis");
  if (m_.c.present && !m_.c.continuous && !(to.c_deg >= m_.c.min_deg - 1e-9 && to.c_deg <= m_.c.max_deg + 1e-9))
    throw SafetyError("move outside travel: C " + formatNumber(to.c_deg) + " deg");
}

}  // namespace probeloop::sim::detail
