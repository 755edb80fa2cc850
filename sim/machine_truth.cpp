#include "sim/machine_truth.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::sim {

using parts::YamlMap;

bool ErrorVector::any() const {
  for (double v : location)
    if (v != 0) return true;
  for (double v : tool_um)
    if (v != 0) return true;
  for (double v : scale_um_per_mm)
    if (v != 0) return true;
  for (double v : tilt_location)
    if (v != 0) return true;
  return false;
}

int ThermalTruth::nodeIndex(const std::string& name) const {
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (nodes[i].name == name) return static_cast<int>(i);
  return -1;
}

double EnvironmentProfile::at(double t) const {
  constexpr double day = 86400.0;
  double T = mean_C + drift_K_per_s * t +
             daily_amplitude_K * std::cos(2 * kPi * (start_clock_s + t - peak_clock_s) / day);
  for (const auto& e : events) {
    const double u = t - e.at_s;
    if (u <= 0) continue;
    double f;  // fraction of the change in force
    if (u < e.ramp_s) f = u / e.ramp_s;
    else if (u < e.ramp_s + e.hold_s) f = 1;
    else if (e.recover_s > 0 && u < e.ramp_s + e.hold_s + e.recover_s) f = 1 - (u - e.ramp_s - e.hold_s) / e.recover_s;
    else f = e.recover_s > 0 || e.hold_s > 0 ? 0 : 1;  // no hold/recover given: a lasting step
    T += f * e.change_K;
  }
  return T;
}

geometry::LocationErrors MachineTruth::keyframeAt(double t) const { return interpolateKeyframes(keyframes, t); }

namespace {

// Keys of an error vector with a suffix: "EX0C_um" + suffix ("" or "_per_K").
ErrorVector readErrorVector(YamlMap& m, const std::string& suffix) {
  ErrorVector e;
  for (int j = 0; j < 7; ++j)
    e.location[j] = m.numberOr(std::string(geometry::LocationErrors::names()[j]) + suffix, 0.0);
  const char* tool[] = {"tool_X_um", "tool_Y_um", "tool_Z_um"};
  for (int a = 0; a < 3; ++a) e.tool_um[a] = m.numberOr(std::string(tool[a]) + suffix, 0.0);
  const char* scale[] = {"EXX_um_per_mm", "EYY_um_per_mm", "EZZ_um_per_mm"};
  for (int a = 0; a < 3; ++a) e.scale_um_per_mm[a] = m.numberOr(std::string(scale[a]) + suffix, 0.0);
  const char* comp[6] = {"X", "Y", "Z", "A", "B", "C"};
  for (int k = 0; k < 6; ++k) {
    const std::string unit = k < 3 ? "_um" : "_urad";
    const std::string b = std::string("E") + comp[k] + "0B" + unit + suffix, a = std::string("E") + comp[k] + "0A" + unit + suffix;
    if (m.has(b) && m.has(a)) m.fail(a, "the tilting axis is B or A, not both (" + b + " is given)");
    e.tilt_location[static_cast<std::size_t>(k)] = m.numberOr(b, 0.0) + m.numberOr(a, 0.0);
  }
  return e;
}


void loadThermal(YamlMap t, ThermalTruth& th) {
  th.present = true;
  th.max_step_s = t.quantityOr("max_step", Dimension::Duration, 60);
  if (!(th.max_step_s > 0)) t.fail("max_step", "must be positive");
  if (auto e = t.mapIfPresent("environment")) {
    auto& env = th.environment;
    env.mean_C = e->numberOr("mean_C", 20);
    env.daily_amplitude_K = e->numberOr("daily_amplitude_K", 0);
    env.peak_clock_s = e->quantityOr("peak_clock", Dimension::Duration, 15 * 3600.0);
    env.start_clock_s = e->quantityOr("start_clock", Dimension::Duration, 0);
    env.drift_K_per_s = e->numberOr("drift_K_per_day", 0) / 86400.0;
    if (e->has("events"))
      for (auto& v : e->mapList("events")) {
        EnvironmentEvent ev;
        ev.at_s = v.quantity("at", Dimension::Duration);
        ev.change_K = v.number("change_K");
        ev.ramp_s = v.quantityOr("ramp", Dimension::Duration, 0);
        ev.hold_s = v.quantityOr("hold", Dimension::Duration, 0);
        ev.recover_s = v.quantityOr("recover", Dimension::Duration, 0);
        if (ev.ramp_s < 0 || ev.hold_s < 0 || ev.recover_s < 0) v.fail("ramp", "durations must not be negative");
        v.finish();
        env.events.push_back(ev);
      }
    e->finish();
  }
  auto nodes = t.mapList("nodes");
  for (auto& n : nodes) {
    ThermalNodeSpec s;
    s.name = n.string("name");
    if (s.name == "environment") n.fail("name", "'environment' is reserved for the surroundings");
    if (th.nodeIndex(s.name) >= 0) n.fail("name", "node '" + s.name + "' is defined twice");
    s.capacity_J_per_K = n.number("capacity_J_per_K");
    if (!(s.capacity_J_per_K > 0)) n.fail("capacity_J_per_K", "must be positive");
    s.to_environment_W_per_K = n.numberOr("to_environment_W_per_K", 0);
    if (s.to_environment_W_per_K < 0) n.fail("to_environment_W_per_K", "must not be negative");
    th.nodes.push_back(s);
    if (auto d = n.mapIfPresent("displacement_per_K")) {
      th.per_node_K.push_back(readErrorVector(*d, "_per_K"));
      d->finish();
    } else {
      th.per_node_K.push_back({});
    }
    n.finish();
  }
  auto node = [&](YamlMap& m, const std::string& key, bool env_ok) {
    const std::string name = m.string(key);
    if (env_ok && name == "environment") return -1;
    const int i = th.nodeIndex(name);
    if (i < 0) m.fail(key, "no thermal node named '" + name + "'");
    return i;
  };
  if (t.has("links"))
    for (auto& l : t.mapList("links")) {
      ThermalLinkSpec s;
      s.a = node(l, "from", false);
      s.b = node(l, "to", false);
      if (s.a == s.b) l.fail("to", "a link joins two different nodes");
      s.conductance_W_per_K = l.number("conductance_W_per_K");
      if (!(s.conductance_W_per_K > 0)) l.fail("conductance_W_per_K", "must be positive");
      l.finish();
      th.links.push_back(s);
    }
  if (t.has("sources"))
    for (auto& s : t.mapList("sources")) {
      HeatSourceSpec h;
      h.node = node(s, "node", false);
      const auto in = s.choice("input", {"c_axis_speed", "spindle_speed", "axis_speed", "mwf", "constant"});
      if (in == "c_axis_speed" || in == "spindle_speed") {
        h.input = in == "c_axis_speed" ? HeatInput::CAxisRpm : HeatInput::SpindleRpm;
        h.gain = s.number("W_per_rpm");
      } else if (in == "axis_speed") {
        h.input = HeatInput::AxisSpeed;  // friction in guides and screws while X/Y/Z move
        h.gain = s.number("W_per_m_per_min");
      } else {
        h.input = in == "mwf" ? HeatInput::Mwf : HeatInput::Constant;
        h.gain = s.number("W");
      }
      s.finish();
      th.sources.push_back(h);
    }
  if (t.has("sensors"))
    for (auto& s : t.mapList("sensors")) {
      SensorSpec k;
      k.column = s.string("column");
      if (k.column.size() < 3 || (k.column.substr(k.column.size() - 2) != "_C"))
        s.fail("column", "a temperature column name ends in _C (e.g. T_env_C)");
      k.node = node(s, "node", true);
      k.noise_K = s.numberOr("noise_K", 0);
      if (k.noise_K < 0) s.fail("noise_K", "must not be negative");
      if (s.has("offset_K")) {
        if (s.string("offset_K") != "random") k.offset_K = s.number("offset_K");
      } else {
        k.offset_K = 0.0;
      }
      s.finish();
      th.sensors.push_back(k);
    }
  // Validate the network now, with the file and line of `nodes`.
  try {
    ThermalNetwork(th.nodes, th.links, 20.0);
  } catch (const InputError& e) {
    t.fail("nodes", e.what());
  }
  t.finish();
}

int axisIndex(const std::string& a) { return a == "x" ? 0 : a == "y" ? 1 : 2; }

// A seed 003 structural unit (model/structural_stiffness.hpp) in the machine frame.
model::StructuralUnit readStructuralUnit(YamlMap& u) {
  model::StructuralUnit s;
  s.name = u.stringOr("name", "unit");
  const auto k = u.numberList("k_N_per_mm");
  if (k.size() != 3) u.fail("k_N_per_mm", "expected [k_x, k_y, k_z] in N/mm (seed 003 Table 4)");
  for (int i = 0; i < 3; ++i) {
    if (!(k[i] >= 0)) u.fail("k_N_per_mm", "must not be negative (0: the unit takes no force in that direction)");
    s.k_N_per_mm(i) = k[i];
  }
  if (u.has("shear")) {
    const YAML::Node list = u.raw("shear");
    if (!list.IsSequence()) u.fail("shear", "expected a list of directions, e.g. [x, y]");
    for (const auto& item : list) {
      const std::string a = item.IsScalar() ? item.as<std::string>() : "";
      if (a != "x" && a != "y" && a != "z") u.fail("shear", "expected x, y or z, got '" + a + "'");
      if (!(s.k_N_per_mm(axisIndex(a)) > 0)) u.fail("shear", "direction " + a + " needs a stiffness > 0 in k_N_per_mm");
      s.shear[axisIndex(a)] = true;
    }
  }
  if (u.has("moments"))
    for (auto& m : u.mapList("moments")) {
      model::MomentPath p;
      p.force_axis = axisIndex(m.choice("force", {"x", "y", "z"}));
      const std::string lever = m.choice("lever", {"+x", "-x", "+y", "-y", "+z", "-z"});
      if (axisIndex(lever.substr(1)) == p.force_axis) m.fail("lever", "must be perpendicular to the force (no moment otherwise)");
      p.lever = (lever[0] == '-' ? -1.0 : 1.0) * Eigen::Vector3d::Unit(axisIndex(lever.substr(1)));
      p.R_mm = m.positiveQuantity("R", Dimension::Length);
      p.S_mm = m.positiveQuantity("spacing", Dimension::Length);
      if (!(s.k_N_per_mm(p.force_axis) > 0)) m.fail("force", "the unit's stiffness in this direction must be > 0");
      p.eq = "seed 003 eq. 29";
      m.finish();
      s.moments.push_back(p);
    }
  if (u.has("arm_mm")) {
    const auto a = u.numberList("arm_mm");
    if (a.size() != 3) u.fail("arm_mm", "expected [x, y, z] in mm (the unit's pivot -> the tool tip)");
    s.arm_mm = Eigen::Vector3d(a[0], a[1], a[2]);
  }
  u.finish();
  return s;
}

}  // namespace

MachineTruth loadMachineTruth(const std::string& path) {
  YamlMap root(parts::loadYamlFile(path), path, "");
  root.choice("kind", {"machine_truth"});
  MachineTruth t;
  t.file = path;
  if (auto s = root.mapIfPresent("static")) {
    t.static_errors = readErrorVector(*s, "");
    s->finish();
  }
  if (root.has("location_keyframes")) t.keyframes = readLocationKeyframes(root, "location_keyframes");
  if (auto a = root.mapIfPresent("axes")) {
    const char axn[] = {'X', 'Y', 'Z'};
    const char* err[] = {"EX", "EY", "EZ", "EA", "EB", "EC"};
    for (int i = 0; i < 3; ++i) {
      auto m = a->mapIfPresent(std::string(1, axn[i]));
      if (!m) continue;
      for (int e = 0; e < 6; ++e) {
        const std::string key = std::string(err[e]) + axn[i] + (e < 3 ? "_um" : "_urad");
        if (m->has(key)) {
          // Bare numbers: coefficients as written (um/mm^k or urad/mm^k).
          t.axes.coeff[i][e] = m->quantityList(key, e < 3 ? Dimension::Micrometre : Dimension::Microradian);
          t.axes.any = true;
        } else {
          m->numberOr(key, 0);  // allowed key
        }
      }
      m->finish();
    }
    a->finish();
  }
  if (auto s = root.mapIfPresent("squareness")) {
    t.EC0Y_urad = s->numberOr("EC0Y_urad", 0);
    t.EB0Z_urad = s->numberOr("EB0Z_urad", 0);
    t.EA0Z_urad = s->numberOr("EA0Z_urad", 0);
    s->finish();
  }
  if (auto th = root.mapIfPresent("thermal")) loadThermal(*th, t.thermal);
  if (auto d = root.mapIfPresent("duty")) {
    if (auto c = d->mapIfPresent("c_axis")) {
      if (c->has("levels_rpm")) {
        t.duty.c_levels_rpm = c->quantityList("levels_rpm", Dimension::RotSpeed);
        t.duty.hold_s = c->quantity("hold", Dimension::Duration);
        if (!(t.duty.hold_s > 0)) c->fail("hold", "must be positive");
      }
      if (c->has("profile"))
        for (auto& p : c->mapList("profile")) {
          t.duty.c_profile.push_back({p.quantity("at", Dimension::Duration), p.quantity("speed", Dimension::RotSpeed)});
          p.finish();
        }
      if (!t.duty.c_levels_rpm.empty() && !t.duty.c_profile.empty())
        c->fail("profile", "give either levels_rpm + hold (random) or a profile, not both");
      c->finish();
    }
    if (d->has("mwf"))
      for (auto& p : d->mapList("mwf")) {
        t.duty.mwf_profile.push_back({p.quantity("at", Dimension::Duration), p.boolean("on")});
        p.finish();
      }
    if (auto c = d->mapIfPresent("tool_changes")) {
      t.duty.tool_changes_per_hour = c->number("per_hour");
      if (!(t.duty.tool_changes_per_hour > 0)) c->fail("per_hour", "must be positive (leave tool_changes out for none)");
      c->finish();
    }
    d->finish();
  }
  if (auto p = root.mapIfPresent("probe")) {
    auto& pr = t.probe;
    pr.pretravel_um = p->quantityOr("pretravel", Dimension::Micrometre, 0);
    pr.lobes = p->integerOr("lobes", 3);
    pr.lobe_amplitude_um = p->quantityOr("lobe_amplitude", Dimension::Micrometre, 0);
    pr.lobe_phase_deg = p->quantityOr("lobe_phase", Dimension::Angle, 0);
    pr.pretravel_vertical_um = p->quantityOr("pretravel_vertical", Dimension::Micrometre, 0);
    pr.trigger_delay_s = p->numberOr("trigger_delay_ms", 0) / 1000.0;
    pr.noise_um = p->quantityOr("noise", Dimension::Micrometre, 0);
    pr.quantise = p->booleanOr("quantise", false);
    if (pr.noise_um < 0) p->fail("noise", "must not be negative");
    if (pr.trigger_delay_s < 0) p->fail("trigger_delay_ms", "must not be negative");
    if (pr.lobes < 1) p->fail("lobes", "must be at least 1");
    p->finish();
  }
  if (auto c = root.mapIfPresent("tool_change")) {
    t.atc_repeatability_um = c->quantityOr("repeatability", Dimension::Micrometre, 0);
    if (t.atc_repeatability_um < 0) c->fail("repeatability", "must not be negative");
    if (auto s = c->mapIfPresent("settling")) {
      t.settling_tool_Z_um = s->quantity("tool_Z", Dimension::Micrometre);
      t.settling_tau_s = s->quantity("time_constant", Dimension::Duration);
      if (!(t.settling_tau_s > 0)) s->fail("time_constant", "must be positive");
      s->finish();
    }
    c->finish();
  }
  if (auto a = root.mapIfPresent("artifact")) {
    if (a->has("node")) {
      const std::string n = a->string("node");
      t.artifact.node = t.thermal.nodeIndex(n);
      if (t.artifact.node < 0) a->fail("node", "no thermal node named '" + n + "' (define thermal: before)");
      if (a->has("alpha_um_per_m_K")) t.artifact.alpha_per_K = a->number("alpha_um_per_m_K") * 1e-6;
      else a->numberOr("alpha_um_per_m_K", 0);  // allowed: a workpiece's material gives it
    }
    if (auto p = a->mapIfPresent("placement_error")) {
      t.artifact.placement_error_mm = Eigen::Vector3d(p->quantityOr("x", Dimension::Micrometre, 0),
                                                      p->quantityOr("y", Dimension::Micrometre, 0),
                                                      p->quantityOr("z", Dimension::Micrometre, 0)) * 1e-3;
      p->finish();
    }
    a->finish();
  }
  if (auto st = root.mapIfPresent("structure")) {
    const char* keys[] = {"stiffness_x_N_per_um", "stiffness_y_N_per_um", "stiffness_z_N_per_um"};
    for (int k = 0; k < 3; ++k) {
      t.stiffness_N_per_um(k) = st->numberOr(keys[k], 0);
      if (t.stiffness_N_per_um(k) < 0) st->fail(keys[k], "must not be negative (0 = rigid)");
    }
    const char* lost[] = {"lost_motion_x_um_per_m_per_min", "lost_motion_y_um_per_m_per_min",
                          "lost_motion_z_um_per_m_per_min"};
    for (int k = 0; k < 3; ++k) {
      t.lost_motion_um_per_m_per_min(k) = st->numberOr(lost[k], 0);
      if (!(t.lost_motion_um_per_m_per_min(k) >= 0)) st->fail(lost[k], "must not be negative (0 = none)");
    }
    if (st->has("units"))
      for (auto& u : st->mapList("units")) t.structure_units.push_back(readStructuralUnit(u));
    t.lost_motion_max_um = st->numberOr("lost_motion_max_um", 0);
    if (t.lost_motion_um_per_m_per_min != Eigen::Vector3d::Zero() && !(t.lost_motion_max_um > 0))
      st->fail("lost_motion_max_um", "must be given and positive with a lost motion (a rapid would otherwise wind a drive up without bound)");
    st->finish();
  }
  t.inputs_rate_s = root.quantityOr("inputs_rate", Dimension::Duration, 60);
  if (!(t.inputs_rate_s > 0)) root.fail("inputs_rate", "must be positive");
  root.finish();
  return t;
}

}  // namespace probeloop::sim
