// The checking machine the interpreter runs against (safety_checker.hpp): probe branches
// (protection), travel, the collision and positioning rules of a linear move, the probing
// move's contact and what comes before it, the material the programs' own cuts remove.
// Rotary and tilting moves: safety_rotary.cpp.
#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "verify/safety_checker.hpp"

namespace probeloop::verify::detail {

void Checker::atProbe(const gcode::ProbeOutcome& nominal, const RunWith& run_with) {
  if (!branched_lines_.insert(line_).second) return;
  gcode::ProbeOutcome other = nominal;
  if (nominal.contact) {
    other.contact = false;
    other.stop = probe_to_;
  } else {
    other.contact = true;
    other.stop = probe_from_;
    // Half-way; 0.5 a + 0.5 b stays finite where b - a would overflow.
    other.stop.xyz_mm = 0.5 * probe_from_.xyz_mm + 0.5 * probe_to_.xyz_mm;
  }
  const State saved = state();
  Unprotected u{line_, probes_ - 1, nominal.contact, "", tip(nominal.stop)};
  bool stopped = false;
  replay_ = true;
  pos_ = other.stop;
  try {
    run_with(other);
    u.went_on = "the program's end";
  } catch (const Interrupted& i) {
    u.went_on = i.event;
  } catch (const SafetyError&) {
    stopped = true;
  } catch (...) {
    replay_ = false;
    restore(saved);
    throw;
  }
  replay_ = false;
  restore(saved);
  if (!stopped) unprotected_.push_back(std::move(u));
}

const gcode::MachinePosition& Checker::requireFinite(const gcode::MachinePosition& to) {
  if (!to.xyz_mm.allFinite() || !std::isfinite(to.a_deg) || !std::isfinite(to.b_deg) || !std::isfinite(to.c_deg))
    throw InputError("", 0, "a move to a coordinate that is not a finite number: the program cannot be checked");
  return to;
}

gcode::ProbeOutcome Checker::probe(const gcode::MachinePosition& to, double, gcode::ProbeMode) {
  requireFinite(to);
  event("a probe move");
  const auto r = probeNominal(to);
  ++probes_;
  probe_from_ = pos_;
  probe_to_ = to;
  pos_ = r.stop;
  return r;
}

void Checker::spindle(double rpm) {
  event(rpm != 0 ? "the spindle starting" : "the spindle stopping");
  rpm_ = rpm;
  if (replay_ || rpm == 0) return;
  if (tool_ == m_.probe.tool)
    add("spindle-with-probe", (rpm > 0 ? "M3" : "M4") + std::string(" S") + fmt(std::fabs(rpm), 0) +
                                  " with the probe (T" + std::to_string(tool_) + ") in the spindle",
        tip(pos_), "no spindle rotation with a touch probe");
}

void Checker::add(const std::string& rule, const std::string& what, const Vector3d& where, const std::string& limit) {
  if (replay_) return;
  if (!seen_.insert({file, line_, rule}).second) return;  // loops repeat a finding: once per line
  findings.push_back({file, line_, rule, what, where, limit});
}
void Checker::addAt(int line, const std::string& rule, const std::string& what, const Vector3d& where,
                    const std::string& limit) {
  if (!seen_.insert({file, line, rule}).second) return;
  findings.push_back({file, line, rule, what, where, limit});
}

// --- geometry of a pose ---

Vector3d Checker::tableFrame(const Vector3d& p, double c_deg) const {
  if (!m_.c.present) return p;
  const Vector2d xy = m_.c_axis_centre_mm +
                      parts::unturnedByTable(p.head<2>() - m_.c_axis_centre_mm, c_deg, m_.c.positive_is_clockwise);
  return Vector3d(xy.x(), xy.y(), p.z());
}

Hit Checker::distance(const Tool& tool, const Vector3d& t, Parts which, bool cutting, double cap) const {
  Hit best;
  auto take = [&](double d, const std::string& part, const std::string& solid) {
    if (d < best.d) best = {d, part, solid};
  };
  for (std::size_t k = 0; k < tool.parts.size(); ++k) {
    const ToolPart& p = tool.parts[k];
    if (which == Parts::TipOnly && !(p.ball)) continue;
    if (which == Parts::ExceptTip && p.ball) continue;
    if (p.ball) {
      for (const auto& s : scene_.spheres) take((t - s.c).norm() - p.r - s.r, p.name, s.name);
      for (const auto& c : scene_.cyls) take(pointCyl(t, c.c, c.r, c.z0, c.z1) - p.r, p.name, c.name);
      take(t.z() - p.r - scene_.table_z, p.name, "the table");
      take(scene_.material.distBall(t, p.r, cap, o_.tolerance_mm), p.name, scene_.material_name);
    } else {
      const Vector2d xy = t.head<2>();
      const double z0 = t.z() + p.dz0, z1 = t.z() + p.dz1;
      for (const auto& s : scene_.spheres) take(pointCyl(s.c, xy, p.r, z0, z1) - s.r, p.name, s.name);
      for (const auto& c : scene_.cyls) take(cylCyl(xy, p.r, z0, z1, c), p.name, c.name);
      take(z0 - scene_.table_z, p.name, "the table");
      if (!(cutting && p.cuts))
        take(scene_.material.distCyl(xy, p.r, z0, z1, cap, o_.tolerance_mm), p.name, scene_.material_name);
    }
  }
  return best;
}

Hit Checker::poseDistance(const Tool& tool, const Motion& mo, double s, Parts which, bool cutting, double cap) const {
  if (!tilted(mo)) return distance(tool, at(mo, s), which, cutting, cap);
  return tiltedDistance(tool, mo.a + s * (mo.b - mo.a), mo.c0 + s * (mo.c1 - mo.c0), mo.q0 + s * (mo.q1 - mo.q0), which,
                        cutting);
}

double Checker::speed(const Motion& mo, const Tool& tool) const {
  if (tilted(mo))
    // Machine frame: the tool moves straight, every body point turns about C and the tilting
    // axis, at most reach_c_ and reach_tilt_ from them.
    return (mo.b - mo.a).norm() + std::fabs(mo.c1 - mo.c0) * kPi / 180 * reach_c_ +
           std::fabs(mo.q1 - mo.q0) * kPi / 180 * reach_tilt_;
  const double rho = std::max((mo.a.head<2>() - m_.c_axis_centre_mm).norm(), (mo.b.head<2>() - m_.c_axis_centre_mm).norm());
  return (mo.b - mo.a).norm() + std::fabs(mo.c1 - mo.c0) * kPi / 180 * (rho + (mo.b - mo.a).norm() + tool.maxRadius());
}

Checker::Sweep Checker::sweep(const Tool& tool, const Motion& mo, Parts which, bool cutting, double cap, double min_step,
                              double margin) const {
  Sweep r;
  const double v = speed(mo, tool);
  double s = 0;
  for (;;) {
    const Hit h = poseDistance(tool, mo, s, which, cutting, cap);
    const double d = std::min(h.d, cap);
    if (s == 0) r.d_start = d;
    if (d < r.d_min) {
      r.d_min = d;
      r.s_min = s;
    }
    if (h.d <= margin + 1e-9) {
      r.hit = true;
      r.s_hit = s;
      r.h = h;
      return r;
    }
    if (s >= 1 || v < 1e-12) return r;
    s = std::min(1.0, s + std::max(d - margin, min_step) / v);
  }
}

void Checker::checkTravel(const gcode::MachinePosition& to) {
  const parts::LinearAxis* ax[3] = {&m_.x, &m_.y, &m_.z};
  const char* names = "XYZ";
  for (int i = 0; i < 3; ++i)
    if (to.xyz_mm(i) < ax[i]->min_mm - 1e-6 || to.xyz_mm(i) > ax[i]->max_mm + 1e-6)
      add("travel",
          std::string(1, names[i]) + " = " + fmt(to.xyz_mm(i)) + " mm (gauge line) is outside the " + names[i] + " travel",
          tip(to), std::string(1, names[i]) + " travel [" + fmt(ax[i]->min_mm) + ", " + fmt(ax[i]->max_mm) + "] mm of " + m_.file);
  auto rotary = [&](const parts::RotaryAxis& a, double v, double was, const char* n) {
    if (!a.present) {
      if (std::fabs(v - was) > 1e-9 || std::fabs(v) > 1e-9)
        add("travel", std::string(n) + " = " + fmt(v) + " deg: the machine has no " + n + " axis", tip(to),
            std::string("no ") + n + " axis in " + m_.file);
      return;
    }
    if (!a.continuous && (v < a.min_deg - 1e-6 || v > a.max_deg + 1e-6))
      add("travel", std::string(n) + " = " + fmt(v) + " deg is outside the " + n + " travel", tip(to),
          std::string(n) + " travel [" + fmt(a.min_deg) + ", " + fmt(a.max_deg) + "] deg of " + m_.file);
  };
  rotary(m_.a, to.a_deg, pos_.a_deg, "A");
  rotary(m_.b, to.b_deg, pos_.b_deg, "B");
  rotary(m_.c, to.c_deg, pos_.c_deg, "C");
}

void Checker::move(const gcode::MachinePosition& to, bool is_feed, double) {
  event(is_feed ? "a feed move" : "a rapid move");
  if (replay_) {
    pos_ = to;
    return;
  }
  checkTravel(to);
  const Tool& tool = toolOf(tool_);
  Motion mo = motionTo(to);
  const bool rotary = std::fabs(to.c_deg - pos_.c_deg) > 1e-9;
  const bool tilt = std::fabs(to.b_deg - pos_.b_deg) > 1e-9 || std::fabs(to.a_deg - pos_.a_deg) > 1e-9;
  const bool cutting = is_feed && tool.cutter && rpm_ != 0;
  if ((rotary || tilt) && tilted(mo)) {
    // The table tilts, or turns while tilted: the swept bodies against the tool.
    if (!tool.parts.empty()) checkSwing(tool, mo);
    pos_ = to;
    return;
  }
  // A table turning many times under a still tool sweeps the same ring: one turn.
  if (rotary && (mo.b - mo.a).norm() < 1e-9 && std::fabs(mo.c1 - mo.c0) > 360)
    mo.c1 = mo.c0 + (mo.c1 > mo.c0 ? 360.0 : -360.0);
  const double plane =
      tilted(mo) ? std::max(tiltedTop(mo.c0, mo.q0), tiltedTop(mo.c1, mo.q1)) + scene_.clearance : scene_.clearancePlane();
  const double low = std::min(mo.a.z(), mo.b.z()) + tool.lowest();

  if (!tool.parts.empty()) {
    // The same full turn at the same place on the same material: checked once.
    const bool turn = rotary && (mo.b - mo.a).norm() < 1e-9 && std::fabs(mo.c1 - mo.c0) >= 360 - 1e-9;
    const auto key = std::make_tuple(mo.a.x(), mo.a.y(), mo.a.z(), tool_, scene_.material.version(), cutting ? 1.0 : 0.0, 0.0);
    if (!turn || turned_.insert(key).second) {
      const Sweep s = sweep(tool, mo, Parts::All, cutting, 5.0, 0.05);
      const std::string tilted_to =
          tilted(mo) ? " (the table tilted to " + std::string(1, tilt_.name) + " " + fmt(mo.q0) + " deg)" : "";
      if (s.hit)
        add("collision",
            moveName(is_feed) + (cutting ? " (cutting)" : "") + tilted_to + ": the " + s.h.part + " " +
                (tool.probe ? "of the probe" : "of T" + std::to_string(tool_)) + " meets " + s.h.solid,
            mo.a + s.s_hit * (mo.b - mo.a), "clear of " + s.h.solid + (s.h.solid == scene_.material_name ? " (height field, " + fmt(o_.cell_mm, 2) + " mm cells, tolerance " + fmt(o_.tolerance_mm, 2) + " mm)" : ""));
      if (tool.probe && low < plane - 1e-3) {
        const double cap = std::max(scene_.clearance, 5.0);
        const Sweep a = sweep(tool, mo, Parts::All, false, cap, 0.25);
        const double tol = scene_.material.empty() ? 0.01 : o_.cell_mm;
        if (!a.hit && a.d_min < a.d_start - tol && a.d_min < cap)
          add("positioning-unprotected",
              moveName(is_feed) + " with the probe below the clearance plane closes in on the part from " + fmt(a.d_start) +
                  " mm to " + fmt(a.d_min) + " mm without protection (G38.3 / G31 with a check)",
              mo.a + a.s_min * (mo.b - mo.a),
              "below Z " + fmt(plane) + " (tip's lowest point) the probe approaches only in protected moves");
      }
    }
    // Cutting on a tilted table is not modelled: the material stays as it was.
    if (cutting && !tilted(mo)) removeMaterial(tool, mo);
  }
  if ((rotary || tilt) && !cutting && low < plane - 1e-3) checkTurn(to, tool, mo, tilt);
  pos_ = to;
}

void Checker::removeMaterial(const Tool& tool, const Motion& mo) {
  const ToolPart* cutter = nullptr;
  for (const auto& p : tool.parts)
    if (p.cuts) cutter = &p;
  if (!cutter || scene_.material.empty()) return;
  const double v = speed(mo, tool);
  const bool straight = std::fabs(mo.c1 - mo.c0) < 1e-9;
  const int n = straight ? std::max(1, static_cast<int>(std::ceil(std::fabs(mo.b.z() - mo.a.z()) / (o_.cell_mm / 2))))
                         : std::max(1, static_cast<int>(std::ceil(v / (o_.cell_mm / 2))));
  Vector3d p0 = at(mo, 0);
  for (int k = 1; k <= n; ++k) {
    const Vector3d p1 = at(mo, static_cast<double>(k) / n);
    scene_.material.cut(p0.head<2>(), p1.head<2>(), cutter->r, std::max(p0.z(), p1.z()));
    p0 = p1;
  }
}

gcode::ProbeOutcome Checker::probeNominal(const gcode::MachinePosition& to) {
  checkTravel(to);
  gcode::ProbeOutcome r;
  r.stop = to;
  const Tool& tool = toolOf(tool_);
  const Motion mo = motionTo(to);
  if (tool.parts.empty()) return r;
  const Sweep t = tool.probe ? sweep(tool, mo, Parts::TipOnly, false, 5.0, 0.002) : Sweep{};
  Motion before = mo;
  if (t.hit) {
    r.contact = true;
    // The probe latches at the contact; the stop is taken 0.02 mm back along the move (the
    // advancement may step up to 0.002 mm into the body), so a retreat starts clear.
    const double len = (mo.b - mo.a).norm();
    const double s_stop = len > 0 ? std::max(0.0, t.s_hit - 0.02 / len) : 0.0;
    r.stop.xyz_mm = pos_.xyz_mm + s_stop * (to.xyz_mm - pos_.xyz_mm);
    r.stop.c_deg = pos_.c_deg + s_stop * (to.c_deg - pos_.c_deg);
    before.b = mo.a + t.s_hit * (mo.b - mo.a);
    before.c1 = r.stop.c_deg;
    const double past = (1 - t.s_hit) * (mo.b - mo.a).norm();
    if (past > m_.probe.max_overtravel_mm + 1e-6)
      add("probe-unbounded",
          "probing move goes on " + fmt(past) + " mm past the contact with " + t.h.solid + " (at " + xyz(mo.a + t.s_hit * (mo.b - mo.a)) + ")",
          mo.b, "probe.max_overtravel " + fmt(m_.probe.max_overtravel_mm) + " mm of " + m_.file);
  }
  const Sweep o = sweep(tool, before, tool.probe ? Parts::ExceptTip : Parts::All, false, 5.0, 0.01);
  if (o.hit)
    add("collision",
        "probe move: the " + o.h.part + " meets " + o.h.solid + (tool.probe ? " before the stylus tip touches anything" : ""),
        mo.a + o.s_hit * (before.b - mo.a), "only the stylus tip may touch");
  return r;
}

}  // namespace probeloop::verify::detail
