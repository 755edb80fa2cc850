// The workpiece on the virtual machine: the part frame (the table's errors, C, the warm
// support and the part's expansion undone), collisions with its material and its obstacles,
// turning the table near it, and cutting: material removed exactly, the cutting force, the
// tool's and the structure's deflection, the cut surfaces (cuts.json) and the machine's
// state at each cut. The class: sim/virtual_machine_detail.hpp.
#include <algorithm>
#include <cmath>
#include <string>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim::detail {

namespace {

// Closest distance from point p to the arc of radius rho about c from angle lo over span
// (counterclockwise, rad), 2D.
double arcDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double rho, double lo, double span) {
  const Eigen::Vector2d w = p - c;
  if (span >= 2 * kPi - 1e-12) return std::fabs(w.norm() - rho);
  double ang = std::atan2(w.y(), w.x()) - lo;
  ang -= 2 * kPi * std::floor(ang / (2 * kPi));
  if (ang <= span) return std::fabs(w.norm() - rho);
  const Eigen::Vector2d e0 = c + rho * Eigen::Vector2d(std::cos(lo), std::sin(lo));
  const Eigen::Vector2d e1 = c + rho * Eigen::Vector2d(std::cos(lo + span), std::sin(lo + span));
  return std::min((p - e0).norm(), (p - e1).norm());
}

}  // namespace

// Machine coordinates of a point (tip coordinates) -> the part frame at 20 °C: undo the
// table's location errors (a rigid motion), turn back to C = 0, then tableToPart.
Vector3d VirtualMachine::toWorkpiece(const Vector3d& q) const {
  // The table's location errors as a rigid motion about the C axis at the table surface
  // (a clamped workpiece moves with the table as one body; ER0T, a radial growth of the
  // table, does not move it).
  const auto e = locationErrors();
  const Vector3d pivot(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), m_.table_surface_z_mm);
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(e[4] * 1e-6, Vector3d::UnitX()) *
                             Eigen::AngleAxisd(e[5] * 1e-6, Vector3d::UnitY()) *
                             Eigen::AngleAxisd(-e[6] * 1e-6, Vector3d::UnitZ())).toRotationMatrix();
  const Vector3d t(e[0] * 1e-3, e[1] * 1e-3, e[2] * 1e-3);
  Vector3d p = pivot + R.transpose() * (q - t - pivot);
  const Eigen::Vector2d c = m_.c_axis_centre_mm;
  p.head<2>() = c + parts::unturnedByTable(p.head<2>() - c, pos_.c_deg, m_.c.positive_is_clockwise);
  return tableToPart(p);
}

// A point on the table at C = 0 (machine coordinates, the table's errors undone) -> the
// part frame at 20 °C: less `artifact.placement_error`, less the part frame's origin
// (machine coordinates at C = 0), less the lift of a warm support (adapter and washers of
// the part's alloy at its temperature: alpha dT support_height; kind: workpiece has none),
// and the part's own expansion about its datum (the blank's bottom centre) undone.
Vector3d VirtualMachine::tableToPart(Vector3d p) const {
  const double e = partAlpha() * workpieceAbove20K();
  p -= tr_.artifact.placement_error_mm;  // where the part really sits on the table
  p -= w_->frame_origin_mm;              // machine at C = 0 -> part frame
  if (w_->support_height_mm != 0) p.z() -= e * w_->support_height_mm;
  return w_->datum() + (p - w_->datum()) / (1.0 + e);
}

// Where the C axis is in the part frame (at 20 °C); the tool circles about it when C
// turns. For the thermal test piece it is the origin.
Eigen::Vector2d VirtualMachine::cAxisInPart() const {
  return tableToPart(Vector3d(m_.c_axis_centre_mm.x(), m_.c_axis_centre_mm.y(), 0)).head<2>();
}

// The part's expansion coefficient: the truth's when it states one, else the material's.
double VirtualMachine::partAlpha() const {
  if (tr_.artifact.alpha_per_K) return *tr_.artifact.alpha_per_K;
  return w_ ? w_->material.alpha_per_K : 0.0;
}

// The workpiece's temperature above 20 °C, where the CMM measures it.
double VirtualMachine::workpieceAbove20K() const {
  return tr_.artifact.node >= 0 && tr_.thermal.present ? net_.temperatures_C()(tr_.artifact.node) - 20.0 : 0.0;
}

// A direction in the workpiece frame -> machine frame (rotation by C only).
Vector3d VirtualMachine::workpieceDirToMachine(const Vector3d& v) const {
  const Eigen::Vector2d m = parts::turnedByTable(v.head<2>(), pos_.c_deg, m_.c.positive_is_clockwise);
  return Vector3d(m.x(), m.y(), v.z());
}

// Does the tool at gauge position g sit in material (height field)? For a flat end mill
// the bottom disk; for the probe the tip ball's lower part (reach r/2, 0.866 r below).
bool VirtualMachine::inMaterial(const Vector3d& g, double tolerance_mm) const {
  const Vector3d w = toWorkpiece(tipActual(g));
  const double r = tipRadius();
  const bool ball = tool_ == m_.probe.tool;
  const double reach = ball ? 0.5 * r : std::max(0.0, r - 0.2);
  const double bottom = ball ? w.z() - 0.866 * r : w.z();
  if (bottom + 1e-6 >= stock_.max().z()) return false;  // above the stock: no cell can be higher
  return stock_.topUnder(w.head<2>(), reach) > bottom + tolerance_mm;
}

// Obstacles (adapter, washers, clamps) must not be touched. The tool is a vertical
// cylinder of its radius (the probe: of its ball's radius) from its bottom upward; it
// touches an obstacle where its axis comes closer than the two radii while its bottom is
// below the obstacle's top. Exact for a straight move in the part frame: the stretch of the
// move within reach (a disk interval) and the lowest bottom there (linear in the move).
void VirtualMachine::checkObstacles(const Vector3d& w0, const Vector3d& w1, const std::string& what) const {
  if (!w_ || w_->obstacles.empty()) return;
  const double r = tipRadius(), below = bottomBelowTip();
  for (const auto& o : w_->obstacles) {
    const double reach = o.radius_mm + r - 1e-9;
    const Eigen::Vector2d u = w0.head<2>(), v = (w1 - w0).head<2>(), d = u - o.centre_mm;
    double lo = 0, hi = 1;
    const double A = v.squaredNorm(), B = v.dot(d), C = d.squaredNorm() - reach * reach;
    if (A < 1e-18) {
      if (C >= 0) continue;
    } else {
      const double disc = B * B - A * C;
      if (disc <= 0) continue;
      lo = std::max(0.0, (-B - std::sqrt(disc)) / A);
      hi = std::min(1.0, (-B + std::sqrt(disc)) / A);
      if (lo > hi) continue;
    }
    const double z_lo = w0.z() + lo * (w1.z() - w0.z()), z_hi = w0.z() + hi * (w1.z() - w0.z());
    const double s = z_lo <= z_hi ? lo : hi;
    if (std::min(z_lo, z_hi) - below < o.z_max_mm - 1e-9) {
      const Vector3d at = w0 + s * (w1 - w0);
      throw SafetyError(what + " would touch the " + o.name + " (an obstacle) at X " + formatNumber(at.x(), 3) + " Y " +
                        formatNumber(at.y(), 3) + " Z " + formatNumber(at.z(), 3) + " (part frame)");
    }
  }
}

// The same while C turns: the tool circles about the axis in the part frame.
void VirtualMachine::checkObstaclesArc(const Eigen::Vector2d& axis, double rho, double lo, double span, double z_tip,
                                       const std::string& what) const {
  if (!w_ || w_->obstacles.empty()) return;
  const double r = tipRadius(), below = bottomBelowTip();
  for (const auto& o : w_->obstacles)
    if (z_tip - below < o.z_max_mm - 1e-9 && arcDistance(o.centre_mm, axis, rho, lo, span) < o.radius_mm + r - 1e-9)
      throw SafetyError(what + " turns the table so that the tool would touch the " + o.name +
                        " (an obstacle): tool at radius " + formatNumber(rho, 3) + " mm from the C axis, Z " +
                        formatNumber(z_tip, 3) + " (part frame)");
}

// Turning the table under a still tool: allowed above the stock, and below its top when
// the tool stays clear of all material it could meet: its edge outside the largest radius
// (about the C axis) of material higher than the tool's bottom, plus a clearance of 0.5 mm
// (the height field's cells are 0.25 mm). The test waits at r = 130 mm, z = -12.1 mm while
// the table turns ~1500 times; the radius is cached until a cut changes the stock.
void VirtualMachine::checkTurn(const MachinePosition& to, const std::string& what) const {
  const Vector3d w = toWorkpiece(tipActual(pos_.xyz_mm));
  const double r = tipRadius(), bottom = w.z() - bottomBelowTip();
  const Eigen::Vector2d axis = cAxisInPart();
  const double rho = (w.head<2>() - axis).norm();
  if (bottom < stock_.max().z() + 1e-9) {
    const double material = stock_.maxMaterialRadius(axis, bottom);
    if (!(rho - r > material + kTurnClearance_mm))
      throw SafetyError(what + " turns the table with the tool below the top of the stock and within reach of its "
                        "material (tool edge " + formatNumber(rho - r, 3) + " mm from the C axis; material up to " +
                        formatNumber(material, 3) + " mm, plus " + formatNumber(kTurnClearance_mm) + " mm clearance)");
  }
  const TurnArc arc = turnArc(w, axis, to.c_deg - pos_.c_deg);
  checkObstaclesArc(axis, rho, arc.ccw.lo, arc.ccw.span, w.z(), what);
}

VirtualMachine::TurnArc VirtualMachine::turnArc(const Vector3d& w, const Eigen::Vector2d& axis, double dc_deg) const {
  TurnArc a;
  a.start = std::atan2(w.y() - axis.y(), w.x() - axis.x());
  a.sweep = -cSense() * degToRad(dc_deg);
  a.ccw = ccwArc(a.start, a.sweep);
  return a;
}

void VirtualMachine::checkWorkpiecePath(const MachinePosition& to, const std::string& what) const {
  const Vector3d a = pos_.xyz_mm, b = to.xyz_mm;
  if (to.c_deg != pos_.c_deg && a != b) checkTogetherWithC(to, what);
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.5)));
  // Straight up from where the tool stands: it rests on the floor the last feed move cut and,
  // where the axes' Z errors vary along X/Y, sits a fraction of a micrometre in the floor
  // that neighbouring passes cut: the start tolerates 2 um of it (a tool 0.3 mm too long
  // after a tool change is still caught); rising, the same footprint only leaves material.
  const bool straight_up = b.z() > a.z() && b.head<2>() == a.head<2>() && to.c_deg == pos_.c_deg;
  for (int k = 0; k <= n; ++k) {
    const Vector3d g = a + (b - a) * (static_cast<double>(k) / n);
    const Vector3d tip = tipActual(g);
    if (tip.z() - (tool_ == m_.probe.tool ? tipRadius() : 0.0) < m_.table_surface_z_mm - 1e-9)
      throw SafetyError(what + " would hit the table at tip Z " + formatNumber(tip.z(), 4) + " mm");
    if (inMaterial(g, straight_up && k == 0 ? 2e-3 : 1e-6)) {
      const Vector3d w = toWorkpiece(tip);
      throw SafetyError(what + " would move through the workpiece's material at X " + formatNumber(w.x(), 3) +
                        " Y " + formatNumber(w.y(), 3) + " Z " + formatNumber(w.z(), 3) + " (workpiece frame)");
    }
  }
  if (!w_->obstacles.empty() && a != b) checkObstacles(toWorkpiece(tipActual(a)), toWorkpiece(tipActual(b)), what);
  if (to.c_deg != pos_.c_deg) checkTurn(to, what);
}

// X/Y/Z moving together with C: in the part frame the tool follows a curve (the line
// turned by the changing C), which the path checks (the straight line at the start's C,
// then the turn at the start's X/Y/Z) do not follow. Above the top of the part and of every
// obstacle nothing can be met, so it is allowed there; below it, refused as not modelled
// (the planner never moves them together: it turns C alone, or above the part).
void VirtualMachine::checkTogetherWithC(const MachinePosition& to, const std::string& what) const {
  double top = stock_.max().z();
  for (const auto& o : w_->obstacles) top = std::max(top, o.z_max_mm);
  const double bottom = std::min(toWorkpiece(tipActual(pos_.xyz_mm)).z(), toWorkpiece(tipActual(to.xyz_mm)).z()) -
                        bottomBelowTip();
  if (bottom < top + 1e-9)
    throw SafetyError(what + " moves X/Y/Z and C together below the top of the part: not modelled (the tool's bottom "
                      "reaches Z " + formatNumber(bottom, 3) + ", the part and its obstacles Z " + formatNumber(top, 3) +
                      ", part frame); turn C alone, or move above the top");
}

// Seed 000 Eq. 3.16 with I1 = I2 = I (the printed E*I^2 is read as E*I, notes §4.8):
// deflection per newton of a cantilevered end mill, mm/N.
double VirtualMachine::toolCompliance(const parts::CuttingTool& t) {
  const double L1 = t.flute_length_mm, L2 = t.stickout_mm, E = t.youngs_modulus_N_per_mm2;
  const double I = kPi * std::pow(t.diameter_mm, 4) / 64.0;
  return (L1 * L1 * L1 / 3.0 + L1 * (L2 - L1) * (L2 + L1) / 6.0 + L2 * (L2 - L1) * (2 * L2 + L1) / 6.0) / (E * I);
}

// Compliance of tool and structure along a machine direction (unit, XY).
double VirtualMachine::compliance(const parts::CuttingTool& t, const Vector3d& away_m) const {
  double c = toolCompliance(t);
  const auto& k = tr_.stiffness_N_per_um;
  for (int i = 0; i < 2; ++i)
    if (k(i) > 0) c += away_m(i) * away_m(i) * 1e-3 / k(i);
  return c;
}

// The machine's state when a cut starts (truth.json relates the as-cut surfaces to it).
void VirtualMachine::recordCutState(const Vector3d& deflection_mm, const Vector3d* from,
                                    const Vector3d* to, double feed) {
  CutState s;
  s.deflection_um = deflection_mm * 1e3;
  if (from && to) {
    s.axes_start_um = axesErrorUm(*from);
    s.axes_end_um = axesErrorUm(*to);
  }
  s.feed_mm_per_min = feed;
  s.spindle_rpm = spindle_rpm_;
  s.time_s = t_;
  s.tool = tool_;
  s.location = locationErrors();
  s.tool_um = toolDriftUm();
  s.part_above_20C_K = workpieceAbove20K();
  s.scale_um_per_mm = scaleUmPerMm();
  s.lost_motion_um = lost_motion_um_;
  cut_states_.push_back(s);
}

// A cutting feed move: material removed along the real tool path; the mean cutting force
// from the removal rate (P = k_c Q, F_t = P / v_c); the radial force K_r F_t pushes the
// tool away from the material, which bends (Eq. 3.16) and the structure yields (F/k); the
// surface cut is the swept volume of the displaced path.
void VirtualMachine::cutMove(const MachinePosition& to, double F) {
  const parts::CuttingTool& t = *cutter();
  const double r = t.diameter_mm / 2;
  if (to.b_deg != pos_.b_deg || to.a_deg != pos_.a_deg || (to.c_deg != pos_.c_deg && to.xyz_mm != pos_.xyz_mm))
    throw InputError("", 0, "cutting with a rotary axis moving together with X/Y/Z (or A, B) is not modelled");
  if (to.c_deg != pos_.c_deg) return arcCut(to, F);
  const double len_cut = (to.xyz_mm - pos_.xyz_mm).norm();
  noteAxesMotion(to.xyz_mm, len_cut / F * 60.0);
  const Vector3d w0 = toWorkpiece(tipActual(pos_.xyz_mm)), w1 = toWorkpiece(tipActual(to.xyz_mm));
  const double table_z = m_.table_surface_z_mm - w_->frame_origin_mm.z();
  if (w0.z() < table_z - 1e-9 || w1.z() < table_z - 1e-9)
    throw SafetyError("feed move (G1/G2/G3) would cut into the table");
  checkObstacles(w0, w1, "feed move (G1/G2/G3)");
  const double len = (to.xyz_mm - pos_.xyz_mm).norm();
  const double dt = len / F * 60.0;
  // A chord of a ring around the part cannot reach the blank: nothing to remove (the hot
  // path of the test's moves around the part).
  const Removal rem = stock_.segmentReachesBlank(w0, w1, r) ? stock_.removeHeightField(w0, w1, r) : Removal{};
  Vector3d defl = Vector3d::Zero();
  double Ft = 0, Fn = 0;
  if (rem.volume_mm3 > 0 && dt > 0) {
    const double vc = kPi * t.diameter_mm * std::fabs(spindle_rpm_) / 60.0;  // mm/s
    Ft = w_->material.specific_cutting_force_N_per_mm2 * (rem.volume_mm3 / dt) / vc;
    // Lateral offset of the removed material from the path, in the workpiece frame.
    const Eigen::Vector2d a = w0.head<2>(), ab = w1.head<2>() - a;
    Eigen::Vector2d lateral = rem.centroid.head<2>() - a;
    if (ab.norm() > 1e-12) {
      const Eigen::Vector2d e = ab.normalized();
      lateral -= lateral.dot(e) * e;
    }
    if (lateral.norm() > 0.05 * r) {
      Fn = w_->material.radial_force_ratio * Ft;
      const Vector3d away_w(-lateral.x() / lateral.norm(), -lateral.y() / lateral.norm(), 0);
      const Vector3d away_m = workpieceDirToMachine(away_w);
      defl = away_w * (Fn * compliance(t, away_m));
      if (!tr_.structure_units.empty()) {
        // Seed 003's units turn and shift the tool under the force on it (machine frame ->
        // workpiece frame: the inverse of the turn by C).
        const Vector3d d = model::tcpDisplacement_mm(tr_.structure_units, Fn * away_m);
        defl += Vector3d(d.dot(workpieceDirToMachine(Vector3d::UnitX())), d.dot(workpieceDirToMachine(Vector3d::UnitY())), d.z());
      }
    }
  }
  // The cut is made warm; in the 20 °C frame the tool's radius shrinks with the part.
  const double r_w = r / (1.0 + partAlpha() * workpieceAbove20K());
  const int tag = static_cast<int>(cut_states_.size());
  const bool stored = stock_.recordCut(w0 + defl, w1 + defl, r_w, t_, tag);
  // A run of cutting moves that cannot touch the blank (a ring around the part, which the
  // controller follows as thousands of chords) is one entry in cuts.json; a single such
  // move keeps its full entry.
  const bool air = rem.volume_mm3 == 0 && !stored;
  if (air && air_run_motion_ == motions_ && !cuts_.empty()) {
    auto& e = cuts_.back();
    if (!e.contains("kind")) e = {{"time_s", e["time_s"]}, {"tool", e["tool"]}, {"kind", "air"}, {"moves", 1}};
    e["moves"] = e["moves"].get<long>() + 1;
    e["until_s"] = t_ + dt;
  } else {
    recordCutState(defl, &pos_.xyz_mm, &to.xyz_mm, F);
    const Vector3d drift = toolDriftUm();
    cuts_.push_back({{"time_s", t_}, {"tool", tool_},
                     {"p0_mm", {w0.x() + defl.x(), w0.y() + defl.y(), w0.z()}},
                     {"p1_mm", {w1.x() + defl.x(), w1.y() + defl.y(), w1.z()}},
                     {"radius_mm", r_w}, {"removed_mm3", rem.volume_mm3}, {"Ft_N", Ft}, {"Fn_N", Fn},
                     {"deflection_um", {defl.x() * 1e3, defl.y() * 1e3}},
                     {"tool_drift_um", {drift.x(), drift.y(), drift.z()}}});
    if (!tr_.structure_units.empty()) {  // a turned unit also lifts or lowers the tool
      cuts_.back()["p0_mm"][2] = w0.z() + defl.z();
      cuts_.back()["p1_mm"][2] = w1.z() + defl.z();
      cuts_.back()["deflection_um"] = {defl.x() * 1e3, defl.y() * 1e3, defl.z() * 1e3};
    }
    if (tr_.axes.any || tr_.EC0Y_urad != 0 || tr_.EB0Z_urad != 0 || tr_.EA0Z_urad != 0 || scaleUmPerMm() != Vector3d::Zero()) {
      const Vector3d a0 = axesErrorUm(pos_.xyz_mm), a1 = axesErrorUm(to.xyz_mm);
      cuts_.back()["axes_um"] = {{a0.x(), a0.y(), a0.z()}, {a1.x(), a1.y(), a1.z()}};
    }
  }
  const double t0 = t_;
  move(dt, F);
  traceRow("cut", to, F, t0);
  if (air) air_run_motion_ = motions_;
  pos_ = to;
}

// Cutting while C turns (pre-machining step 1, seed 004 L2006: "circular milled by turning
// the rotary table; no linear axis is moved"): in the part frame the still tool circles
// the C axis. Removal and force as for a line (force from the removal rate over the first
// turn, which removes all there is); the radial force pushes the tool away from the
// material: outward when the removed material lies inside the circle. A turn whose swept
// annulus cannot reach the material is no cut (the test's load turns the table a thousand
// times with the tool waiting outside the part): timed and checked only.
void VirtualMachine::arcCut(const MachinePosition& to, double F_deg_per_min) {
  const parts::CuttingTool& t = *cutter();
  const double r = t.diameter_mm / 2;
  const Vector3d q = tipActual(pos_.xyz_mm);
  const Vector3d w0 = toWorkpiece(q);
  const double table_z = m_.table_surface_z_mm - w_->frame_origin_mm.z();
  if (w0.z() < table_z - 1e-9) throw SafetyError("feed move (G1) would cut into the table");
  const Eigen::Vector2d axis = cAxisInPart();
  const double rho = (w0.head<2>() - axis).norm();
  const double dc = to.c_deg - pos_.c_deg;
  const TurnArc arc = turnArc(w0, axis, dc);
  const double start = arc.start, sweep = arc.sweep;
  checkObstaclesArc(axis, rho, arc.ccw.lo, arc.ccw.span, w0.z(), "feed move (G1)");
  const double dt = std::fabs(dc) / F_deg_per_min * 60.0;
  const double turns = std::fabs(sweep) / (2 * kPi);
  const double cut_sweep = std::clamp(sweep, -2 * kPi, 2 * kPi);
  const bool reaches = w0.z() < stock_.max().z() && rho - r <= stock_.maxMaterialRadius(axis, w0.z()) + kTurnClearance_mm;
  const double t0 = t_;
  if (reaches) {
    const Removal rem = stock_.removeHeightFieldArc(axis, rho, start, cut_sweep, w0.z(), r);
    double Ft = 0, Fn = 0, defl_mm = 0;  // radial, outward positive
    const double dt_cut = dt / std::max(1.0, turns);  // the first turn removes it all
    Vector3d away_m = Vector3d::Zero();
    if (rem.volume_mm3 > 0 && dt_cut > 0) {
      const double vc = kPi * t.diameter_mm * std::fabs(spindle_rpm_) / 60.0;  // mm/s
      Ft = w_->material.specific_cutting_force_N_per_mm2 * (rem.volume_mm3 / dt_cut) / vc;
      const double lateral = rem.mean_radius_mm - rho;  // > 0: the material lay outside the circle
      if (std::fabs(lateral) > 0.05 * r && rho > 1e-9) {
        Fn = w_->material.radial_force_ratio * Ft;
        const double sign = lateral > 0 ? -1.0 : 1.0;
        // Radial in the machine: from the axis to the still tool.
        const Eigen::Vector2d radial_m = (q.head<2>() - m_.c_axis_centre_mm).normalized();
        away_m = Vector3d(sign * radial_m.x(), sign * radial_m.y(), 0);
        defl_mm = sign * Fn * compliance(t, away_m);
        // Seed 003's units: the radial component of their displacement of the tip.
        if (!tr_.structure_units.empty())
          defl_mm += model::tcpDisplacement_mm(tr_.structure_units, Fn * away_m).dot(Vector3d(radial_m.x(), radial_m.y(), 0));
      }
    }
    const double r_w = r / (1.0 + partAlpha() * workpieceAbove20K());
    const int tag = static_cast<int>(cut_states_.size());
    recordCutState();
    stock_.recordArc(axis, rho + defl_mm, start, cut_sweep, w0.z(), r_w, t_, tag);
    const Vector3d drift = toolDriftUm();
    const Eigen::Vector2d e0(std::cos(start), std::sin(start));
    cuts_.push_back({{"time_s", t_}, {"tool", tool_}, {"kind", "arc"},
                     {"centre_mm", {axis.x(), axis.y()}}, {"path_radius_mm", rho + defl_mm}, {"z_mm", w0.z()},
                     {"start_deg", radToDeg(start)}, {"sweep_deg", radToDeg(cut_sweep)}, {"turns", turns},
                     {"radius_mm", r_w}, {"removed_mm3", rem.volume_mm3}, {"Ft_N", Ft}, {"Fn_N", Fn},
                     {"deflection_um", {e0.x() * defl_mm * 1e3, e0.y() * defl_mm * 1e3}},
                     {"radial_deflection_um", defl_mm * 1e3},
                     {"tool_drift_um", {drift.x(), drift.y(), drift.z()}}});
  }
  c_move_rpm_ = cMoveRpm(to, dt);
  move(dt, 0.0);
  c_move_rpm_ = 0;
  traceRow(reaches ? "cut" : "feed", to, F_deg_per_min, t0);
  pos_ = to;
}

}  // namespace probeloop::sim::detail
