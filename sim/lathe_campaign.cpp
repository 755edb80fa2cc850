#include "sim/lathe_campaign.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.hpp"
#include "core/units.hpp"
#include "model/effects.hpp"
#include "parts/yaml_reader.hpp"
#include "sim/random_streams.hpp"

namespace probeloop::sim {

using Eigen::Vector3d;

namespace {

const char* kBodyNames[4] = {"z_carriage", "x_slide", "turret", "spindle"};  // the paper's 1..4

Vector3d vector3(parts::YamlMap& m, const std::string& key, const Vector3d& fallback) {
  if (!m.has(key)) return fallback;
  const auto v = m.numberList(key);
  if (v.size() != 3) m.fail(key, "expected [x, y, z] in mm (3 numbers), got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

LatheHeatSource readSource(parts::YamlMap& s) {
  LatheHeatSource h;
  h.input = s.string("input");
  const std::string body = s.choice("body", {kBodyNames[0], kBodyNames[1], kBodyNames[2], kBodyNames[3]});
  for (int b = 0; b < 4; ++b)
    if (body == kBodyNames[b]) h.body = b + 1;
  h.levels = s.numberList("levels");
  for (double l : h.levels)
    if (l < 0) s.fail("levels", "a load level is a speed's magnitude: >= 0");
  h.hold_s = s.positiveQuantity("hold", Dimension::Duration);
  h.K_per_unit = s.number("K_per_unit");
  h.tau_s = s.positiveQuantity("tau", Dimension::Duration);
  auto k = s.map("per_K");
  const char* t[3] = {"dx", "dy", "dz"};
  const char* r[3] = {"ex", "ey", "ez"};
  for (int i = 0; i < 3; ++i) {
    h.per_K.translation_mm(i) = k.quantityOr(t[i], Dimension::Micrometre, 0.0) * 1e-3;
    h.per_K.rotation_rad(i) = k.quantityOr(r[i], Dimension::Microradian, 0.0) * 1e-6;
  }
  k.finish();
  h.screw_um_per_m_K = s.numberOr("screw_um_per_m_K", 0.0);
  if (h.screw_um_per_m_K != 0 && h.body > 2)
    s.fail("screw_um_per_m_K", "a screw's scale error belongs to a linear axis (z_carriage or x_slide)");
  s.finish();
  return h;
}

double levelAt(const LatheHeatSource& h, const LatheTruth& t, double time_s, std::mt19937_64& rng,
               std::vector<double>& drawn) {
  if (time_s <= 0) return 0;  // cold and idle
  if (time_s < t.cold_start_s) return *std::max_element(h.levels.begin(), h.levels.end());
  const auto block = static_cast<std::size_t>((time_s - t.cold_start_s) / h.hold_s);
  std::uniform_int_distribution<std::size_t> pick(0, h.levels.size() - 1);
  while (drawn.size() <= block) drawn.push_back(h.levels[pick(rng)]);
  return drawn[block];
}

// The twist of each body at its thermal state and axis position.
geometry::LatheErrors errorsAt(const LatheTruth& t, const std::vector<double>& theta_K, double x_mm, double z_mm) {
  geometry::LatheErrors e;
  for (std::size_t i = 0; i < t.sources.size(); ++i) {
    const LatheHeatSource& h = t.sources[i];
    geometry::Twist& tw = e.body[static_cast<std::size_t>(h.body - 1)];
    tw.translation_mm += theta_K[i] * h.per_K.translation_mm;
    tw.rotation_rad += theta_K[i] * h.per_K.rotation_rad;
    // a screw warmed by theta stretches its axis: alpha theta q along the axis (um/m = 1e-6)
    if (h.body == 1) tw.translation_mm.z() += h.screw_um_per_m_K * 1e-6 * theta_K[i] * z_mm;
    if (h.body == 2) tw.translation_mm.x() += h.screw_um_per_m_K * 1e-6 * theta_K[i] * x_mm;
  }
  return e;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v == 0 ? 0.0 : v);  // no "-0.000"
  return b;
}

}  // namespace

LatheTruth loadLatheTruth(const std::string& path) {
  parts::YamlMap root(parts::loadYamlFile(path), path, "");
  root.choice("kind", {"lathe_truth"});
  LatheTruth t;
  t.file = path;
  if (auto g = root.mapIfPresent("geometry")) {
    for (int b = 0; b < 4; ++b) t.offsets.o[static_cast<std::size_t>(b)] = vector3(*g, kBodyNames[b], t.offsets.o[static_cast<std::size_t>(b)]);
    t.tool_tip_mm = vector3(*g, "tool_tip", t.tool_tip_mm);
    t.workpiece_point_mm = vector3(*g, "workpiece_point", t.workpiece_point_mm);
    // the lathe has no Y axis: the tool's centre height closes Y (eq. 24's second row)
    const double ty = t.offsets.o[3].y() + t.workpiece_point_mm.y() - t.offsets.o[0].y() - t.offsets.o[1].y() -
                      t.offsets.o[2].y();
    if (std::abs(t.tool_tip_mm.y() - ty) > 1e-9)
      g->fail("tool_tip", "Ty must put the tool at the workpiece point's height: b4 + Wy - b1 - b2 - b3 = " +
                              fmt("%.3f", ty) + " mm (seed 002 eq. 24)");
    g->finish();
  }
  if (auto c = root.mapIfPresent("campaign")) {
    t.duration_s = c->quantityOr("duration", Dimension::Duration, t.duration_s);
    t.cycle_s = c->quantityOr("cycle", Dimension::Duration, t.cycle_s);
    t.inputs_rate_s = c->quantityOr("inputs_rate", Dimension::Duration, t.inputs_rate_s);
    t.cold_start_s = c->quantityOr("cold_start", Dimension::Duration, t.cold_start_s);
    for (const char* k : {"duration", "cycle", "inputs_rate"})
      if (c->has(k) && c->quantity(k, Dimension::Duration) <= 0) c->fail(k, "must be positive");
    if (t.cold_start_s < 0) c->fail("cold_start", "a duration >= 0");
    const double r = t.cycle_s / t.inputs_rate_s;
    if (std::abs(r - std::round(r)) > 1e-9)
      c->fail("cycle", "a whole number of inputs_rate steps (parts are measured on the inputs' clock)");
    if (t.duration_s < 2 * t.cycle_s) c->fail("duration", "at least two cycles");
    c->finish();
  }
  if (auto m = root.mapIfPresent("measurement")) {
    t.diameter_noise_um = m->quantityOr("diameter_noise", Dimension::Micrometre, t.diameter_noise_um);
    t.face_noise_um = m->quantityOr("face_noise", Dimension::Micrometre, t.face_noise_um);
    if (t.diameter_noise_um <= 0) m->fail("diameter_noise", "a measurement has noise: > 0 (the errors' U comes from it)");
    if (t.face_noise_um <= 0) m->fail("face_noise", "a measurement has noise: > 0 (the errors' U comes from it)");
    m->finish();
  }
  for (auto& s : root.mapList("sources")) t.sources.push_back(readSource(s));
  root.finish();
  return t;
}

LatheCampaign simulateLatheCampaign(const LatheTruth& t, std::uint64_t seed) {
  const auto chain = geometry::latheChain(t.offsets, t.tool_tip_mm);
  const Vector3d& W = t.workpiece_point_mm;
  const Eigen::Vector2d xz = geometry::latheNominalXZ(t.offsets, t.tool_tip_mm, W);
  const std::size_t ns = t.sources.size();
  std::vector<std::mt19937_64> rng;
  std::vector<std::vector<double>> drawn(ns);
  for (std::size_t i = 0; i < ns; ++i) rng.emplace_back(streamSeed(seed, 20 + i));
  std::mt19937_64 noise_rng(streamSeed(seed, 19));
  std::normal_distribution<double> normal(0.0, 1.0);

  LatheCampaign out;
  std::string inputs = "# probeloop lathe: the seed 002 turning centre's loads sampled every " +
                       fmt("%.0f", t.inputs_rate_s) + " s (spindle speed, each axis's mean feed)\ntime_s";
  for (const auto& h : t.sources) inputs += "," + h.input;
  inputs += "\n";
  std::string errors = "# probeloop lathe: turned diameter and face position errors at W = (" + fmt("%.3f", W.x()) + ", " +
                       fmt("%.3f", W.y()) + ", " + fmt("%.3f", W.z()) +
                       ") mm, relative to cycle 1; U = expanded uncertainty (k = 2)\n"
                       "time_s,cycle,diameter_um,face_z_um,U_diameter_um,U_face_z_um\n";
  std::string truth = "# probeloop lathe: the truth per cycle; P = P_tool - P_work (seed 002 eqs. 27-30), exact through the chain\n"
                      "time_s,cycle";
  for (const auto& h : t.sources) truth += ",theta_" + std::string(kBodyNames[h.body - 1]) + "_K";
  truth += ",Px_um,Py_um,Pz_um,P_um,diameter_um,face_z_um\n";

  const auto steps = static_cast<long>(std::floor(t.duration_s / t.inputs_rate_s + 1e-9));
  const auto per_cycle = static_cast<long>(std::llround(t.cycle_s / t.inputs_rate_s));
  std::vector<double> theta(ns, 0.0), u(ns, 0.0);
  double d0 = 0, f0 = 0;
  const double U_d = 2 * std::sqrt(2.0) * t.diameter_noise_um, U_f = 2 * std::sqrt(2.0) * t.face_noise_um;
  for (long k = 0; k <= steps; ++k) {
    const double time = static_cast<double>(k) * t.inputs_rate_s;
    // the lag over the last step with the load logged at its start (zero-order hold, as the
    // model's regressor integrates it)
    if (k > 0)
      for (std::size_t i = 0; i < ns; ++i)
        theta[i] = model::lagStep(theta[i], t.sources[i].K_per_unit * u[i], t.inputs_rate_s, t.sources[i].tau_s);
    for (std::size_t i = 0; i < ns; ++i) u[i] = levelAt(t.sources[i], t, time, rng[i], drawn[i]);
    inputs += fmt("%.3f", time);
    for (double v : u) inputs += "," + fmt("%.3f", v);
    inputs += "\n";
    if (k % per_cycle != 0) continue;
    const auto e = errorsAt(t, theta, xz.x(), xz.y());
    const Vector3d P = geometry::latheVolumetricError(chain, xz.x(), xz.y(), e, W) * 1e3;
    const auto cut = geometry::latheCutErrors(chain, xz.x(), xz.y(), e, W);
    const double d = cut.diameter_mm * 1e3 + t.diameter_noise_um * normal(noise_rng);
    const double f = cut.face_z_mm * 1e3 + t.face_noise_um * normal(noise_rng);
    const int cycle = ++out.cycles;
    if (cycle == 1) d0 = d, f0 = f;
    errors += fmt("%.3f", time) + "," + std::to_string(cycle) + "," + fmt("%.4f", d - d0) + "," + fmt("%.4f", f - f0) +
              "," + fmt("%.4f", cycle == 1 ? 0 : U_d) + "," + fmt("%.4f", cycle == 1 ? 0 : U_f) + "\n";
    truth += fmt("%.3f", time) + "," + std::to_string(cycle);
    for (double th : theta) truth += "," + fmt("%.4f", th);
    truth += "," + fmt("%.4f", P.x()) + "," + fmt("%.4f", P.y()) + "," + fmt("%.4f", P.z()) + "," + fmt("%.4f", P.norm()) +
             "," + fmt("%.4f", cut.diameter_mm * 1e3) + "," + fmt("%.4f", cut.face_z_mm * 1e3) + "\n";
    out.max_resultant_um = std::max(out.max_resultant_um, P.norm());
  }
  // The cold start's steady state and what of it is still to come after cold_start_s.
  std::vector<double> warm(ns), after(ns);
  for (std::size_t i = 0; i < ns; ++i) {
    const auto& h = t.sources[i];
    const double top = *std::max_element(h.levels.begin(), h.levels.end());
    warm[i] = h.K_per_unit * top;
    after[i] = model::lagStep(0.0, warm[i], t.cold_start_s, h.tau_s);
  }
  const Vector3d Pw = geometry::latheVolumetricError(chain, xz.x(), xz.y(), errorsAt(t, warm, xz.x(), xz.y()), W);
  const Vector3d Pa = geometry::latheVolumetricError(chain, xz.x(), xz.y(), errorsAt(t, after, xz.x(), xz.y()), W);
  out.cold_start_resultant_um = Pw.norm() * 1e3;
  out.after_warm_up_resultant_um = (Pw - Pa).norm() * 1e3;
  out.inputs_csv = std::move(inputs);
  out.errors_csv = std::move(errors);
  out.truth_csv = std::move(truth);
  return out;
}

}  // namespace probeloop::sim
