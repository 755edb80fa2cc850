// The touch probe of the virtual machine: a probe move to the first contact with the sphere
// artifact or the workpiece, pre-travel (lobed, by direction) and trigger delay, the clock
// while the tip approaches, repeatability noise and quantisation of the latched position,
// and the truth behind each probe event. The class: sim/virtual_machine_detail.hpp.
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/error.hpp"
#include "core/units.hpp"
#include "model/effects.hpp"
#include "parts/machine_clock.hpp"
#include "sim/virtual_machine_detail.hpp"

namespace probeloop::sim::detail {

// A probe move (G38.2/G38.3, G31): to the first contact with the sphere artifact here, with
// the workpiece in probeWorkpiece.
gcode::ProbeOutcome VirtualMachine::probeMove(const MachinePosition& to, double F, gcode::ProbeMode mode) {
  checkTravel(to);
  checkAxisA(to);
  checkFeed(F);
  if (to.c_deg != pos_.c_deg || to.b_deg != pos_.b_deg || to.a_deg != pos_.a_deg)
    throw InputError("", 0, "a probe move with a rotary axis is not modelled");
  const Vector3d g0 = pos_.xyz_mm, g1 = to.xyz_mm;
  const double len = (g1 - g0).norm();
  if (len <= 0) throw InputError("", 0, "a probe move of zero length");
  noteAxesMotion(g1, parts::linearFeedSeconds(len, F));
  const Vector3d dir = (g1 - g0) / len;
  if (!a_) return probeWorkpiece(to, F, dir, len, mode);
  const Vector3d a = tipActual(g0), b = tipActual(g1);
  const Artifact art = artifact();
  // Stem and table first: a probe move may touch the sphere only.
  // LinuxCNC refuses to start a probe move with the probe tripped; Fanuc skips at once.
  if ((a - art.centre).norm() <= art.radius + tipRadius() && mode != gcode::ProbeMode::SkipToTarget)
    throw SafetyError("probe move starts with the probe already in contact (tripped)");
  const double s_contact = firstSphereContact(a, b, art);
  const double s_end = s_contact >= 0 ? s_contact : 1.0;
  checkStemAndTable(a, a + s_end * (b - a), art, "probe move");
  const double pre_um = pretravel(dir);
  const double extra_mm = pre_um * 1e-3 + F / 60.0 * tr_.probe.trigger_delay_s;
  const double s_trig = s_contact >= 0 ? s_contact + extra_mm / len : 2.0;
  if (s_contact < 0 || s_trig > 1.0) return noTrigger(to, len, F);
  // The clock runs while the tip approaches (~1 s): the tip meets the artifact where the
  // errors of the contact time put it, which matters for fast effects (a settling
  // transient of 10 min moves 0.15 % in that second). Move to the contact found with the
  // errors at the start, then find it again with the errors now: a nanometre correction,
  // forward or back along the line.
  const double approach_mm = s_contact * len;
  move(parts::linearFeedSeconds(approach_mm, F), F);
  pos_.xyz_mm = g0 + approach_mm * dir;
  const Artifact now = artifact();
  const double s_now = sphereEntryOnLine(tipActual(pos_.xyz_mm), tipActual(g1), now).value_or(0.0);
  const double travel_mm = s_now * (len - approach_mm) + extra_mm;
  if (approach_mm + travel_mm > len) return noTrigger(to, len - approach_mm, F);
  ProbeEvent ev = newEvent(dir, pre_um);
  fillTruth(ev, now);
  return latchTrigger(ev, dir, travel_mm, F);
}

// No trigger within the move: G38.2/G38.3 and G31 all end at the target.
gcode::ProbeOutcome VirtualMachine::noTrigger(const MachinePosition& to, double len, double F) {
  move(parts::linearFeedSeconds(len, F), F);
  pos_ = to;
  gcode::ProbeOutcome out;
  out.stop = to;
  return out;
}

ProbeEvent VirtualMachine::newEvent(const Vector3d& dir, double pretravel_um) const {
  ProbeEvent ev;
  ev.c_deg = pos_.c_deg;
  ev.approach = dir;
  ev.pretravel_um = pretravel_um;
  return ev;
}

// The controller latches the trigger: repeatability noise along the approach, the axes'
// resolution, the clock at the trigger, the event for the truth and the next log line.
gcode::ProbeOutcome VirtualMachine::latchTrigger(ProbeEvent ev, const Vector3d& dir, double travel_mm, double F) {
  ev.noise_um = tr_.probe.noise_um > 0 ? tr_.probe.noise_um * noise_normal_(noise_rng_) : 0.0;
  Vector3d latched = pos_.xyz_mm + travel_mm * dir + ev.noise_um * 1e-3 * dir;
  // The stylus is calibrated at the probing feed (as for its pre-travel): the lag of the axes
  // that move in the approach is in its effective radius; a still axis's held lag is not.
  for (int k = 0; k < 3; ++k)
    if (lost_motion_moving_[k]) latched(k) += lost_motion_um_(k) * 1e-3;
  if (tr_.probe.quantise) {
    const double q[3] = {m_.x.resolution_mm, m_.y.resolution_mm, m_.z.resolution_mm};
    for (int k = 0; k < 3; ++k) latched(k) = std::round(latched(k) / q[k]) * q[k];
  }
  move(parts::linearFeedSeconds(travel_mm, F), F);
  ev.time_s = t_;
  ev.reported_tip_mm = latched - Vector3d(0, 0, currentToolLength());
  events_.push_back(ev);
  pending_ = static_cast<long>(events_.size()) - 1;
  pos_.xyz_mm = latched;
  gcode::ProbeOutcome out;
  out.contact = true;
  out.stop = pos_;
  return out;
}

// The probe's pre-travel (um) along an approach direction: lobed in XY, its vertical value in Z.
double VirtualMachine::pretravel(const Vector3d& dir) const {
  const auto& p = tr_.probe;
  const double h = std::hypot(dir.x(), dir.y());
  const double phi = std::atan2(dir.y(), dir.x());
  const double lateral = p.pretravel_um + p.lobe_amplitude_um * std::cos(p.lobes * (phi - degToRad(p.lobe_phase_deg)));
  return h * lateral + std::fabs(dir.z()) * p.pretravel_vertical_um;
}

// Smallest s in [0,1] where the tip sphere touches the artifact sphere while moving in;
// -1 if it does not.
double VirtualMachine::firstSphereContact(const Vector3d& a, const Vector3d& b, const Artifact& art) const {
  const double Rt = art.radius + tipRadius();
  const Vector3d d = b - a, w = a - art.centre;
  const double A = d.squaredNorm(), B = d.dot(w), C = w.squaredNorm() - Rt * Rt;
  if (C <= 0) return 0.0;  // already in contact at the start
  const double disc = B * B - A * C;
  if (disc < 0 || A == 0) return -1.0;
  const double s = (-B - std::sqrt(disc)) / A;
  return s >= 0 && s <= 1 ? s : -1.0;
}

// Where the tip sphere enters the artifact sphere on the whole line through a and b
// (parameter s, negative = behind a); none if the line misses it.
std::optional<double> VirtualMachine::sphereEntryOnLine(const Vector3d& a, const Vector3d& b,
                                                        const Artifact& art) const {
  const double Rt = art.radius + tipRadius();
  const Vector3d d = b - a, w = a - art.centre;
  const double A = d.squaredNorm(), B = d.dot(w), C = w.squaredNorm() - Rt * Rt;
  const double disc = B * B - A * C;
  if (disc < 0 || A == 0) return std::nullopt;
  return (-B - std::sqrt(disc)) / A;
}

// The truth of a probe event on the sphere artifact.
void VirtualMachine::fillTruth(ProbeEvent& ev, const Artifact& art) const {
  ev.location = art.location;
  ev.tool_um = toolDriftUm();
  ev.atc_um = atc_um_;
  ev.settling_um = settlingUm();
  ev.artifact_dT_K = art.dT;
  // What a sphere campaign evaluation sees: table errors minus the tool's translation,
  // plus the artifact's own growth (radius from the axis and height).
  ev.apparent = art.location;
  const double alpha_um_per_m_K = partAlpha() * 1e6;
  ev.apparent[0] -= ev.tool_um.x();
  ev.apparent[1] -= ev.tool_um.y();
  ev.apparent[2] -= ev.tool_um.z();
  // The ball grows too; the known-radius fit reads that as a lift of the centre by the
  // radius change, because only the top point sees Z (docs/simulator.md). The same
  // alpha L dT as the model's `expansion` effect.
  ev.apparent[2] += model::expansion_um(alpha_um_per_m_K, a_->centreHeightAboveTable() + a_->sphereRadius(), art.dT);
  ev.apparent[3] += model::expansion_um(alpha_um_per_m_K, a_->radius_from_axis_mm, art.dT);
}

// A probe move on a workpiece: the tip ball meets the first material of the stock.
gcode::ProbeOutcome VirtualMachine::probeWorkpiece(const MachinePosition& to, double F, const Vector3d& dir, double len,
                                                   gcode::ProbeMode mode) {
  double s_contact = -1;
  if (w_) {
    const double r = tipRadius();
    const Vector3d a = toWorkpiece(tipActual(pos_.xyz_mm)), b = toWorkpiece(tipActual(to.xyz_mm));
    const Vector3d d = (b - a).normalized();
    // Distances in the workpiece frame (20 °C) -> machine travel.
    const double to_machine = len / (b - a).norm();
    // The ball touches a surface square to the approach when its centre is r from it, in the
    // workpiece frame (where the axes' errors stretch the path): (s - r) of real travel.
    if (const auto s = stock_.firstMaterial(a, d, (b - a).norm() + r / to_machine)) {
      s_contact = (*s - r) * to_machine;
      if (s_contact < 0) {
        if (mode != gcode::ProbeMode::SkipToTarget)
          throw SafetyError("probe move starts with the probe already in contact (tripped)");
        s_contact = 0;
      }
    }
    if (s_contact > len) s_contact = -1;
    // Nothing else in the way before the contact (height field).
    MachinePosition until = to;
    if (s_contact >= 0) until.xyz_mm = pos_.xyz_mm + dir * std::max(0.0, s_contact - 0.01);
    checkWorkpiecePath(until, "probe move");
  }
  const double pre_um = pretravel(dir);
  const double s_trig = s_contact >= 0 ? s_contact + pre_um * 1e-3 + F / 60.0 * tr_.probe.trigger_delay_s : 2 * len;
  if (s_contact < 0 || s_trig > len) return noTrigger(to, len, F);
  ProbeEvent ev = newEvent(dir, pre_um);
  ev.location = locationErrors();
  ev.tool_um = toolDriftUm();
  ev.axes_um = axesErrorUm(pos_.xyz_mm + dir * s_contact);
  for (int k = 0; k < 3; ++k)  // what the calibrated stylus takes out (latchTrigger)
    if (lost_motion_moving_[k]) (*ev.axes_um)(k) -= lost_motion_um_(k);
  ev.scale_um_per_mm = scaleUmPerMm();
  ev.atc_um = atc_um_;
  ev.settling_um = settlingUm();
  ev.artifact_dT_K = nodeRise(tr_.artifact.node);
  ev.apparent = ev.location;
  return latchTrigger(ev, dir, s_trig, F);
}

}  // namespace probeloop::sim::detail
