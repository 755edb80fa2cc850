#include "sim/rigid_campaign.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::sim {

using Eigen::Vector3d;
using geometry::LocationErrors;

LocationErrors interpolateKeyframes(const std::vector<LocationKeyframe>& keyframes, double t) {
  if (keyframes.empty()) return {};
  if (t <= keyframes.front().time_s) return keyframes.front().errors;
  if (t >= keyframes.back().time_s) return keyframes.back().errors;
  for (size_t i = 1; i < keyframes.size(); ++i) {
    if (t <= keyframes[i].time_s) {
      const auto& a = keyframes[i - 1];
      const auto& b = keyframes[i];
      const double w = (t - a.time_s) / (b.time_s - a.time_s);
      const auto va = a.errors.values(), vb = b.errors.values();
      std::array<double, 7> v;
      for (int j = 0; j < 7; ++j) v[j] = va[j] + w * (vb[j] - va[j]);
      return LocationErrors::fromValues(v);
    }
  }
  return keyframes.back().errors;
}

LocationErrors RigidTruth::at(double t) const { return interpolateKeyframes(keyframes, t); }

std::vector<LocationKeyframe> readLocationKeyframes(parts::YamlMap& parent, const std::string& key) {
  std::vector<LocationKeyframe> out;
  double last = -INFINITY;
  for (auto& k : parent.mapList(key)) {
    LocationKeyframe f;
    f.time_s = k.quantity("time", Dimension::Duration);
    if (!(f.time_s > last)) k.fail("time", "keyframe times must increase");
    last = f.time_s;
    std::array<double, 7> v;
    for (int j = 0; j < 7; ++j) {
      const std::string name = LocationErrors::names()[j];
      v[j] = k.quantityOr(name, j < 4 ? Dimension::Micrometre : Dimension::Microradian, 0.0);
    }
    f.errors = LocationErrors::fromValues(v);
    k.finish();
    out.push_back(f);
  }
  return out;
}

RigidTruth loadRigidTruth(const std::string& path) {
  parts::YamlMap root(parts::loadYamlFile(path), path, "");
  root.choice("kind", {"rigid_location_truth"});
  RigidTruth t;
  t.per_point = root.choice("sample", {"per_cycle", "per_point"}) == "per_point";
  t.probe_noise_um = root.quantity("probe_noise", Dimension::Micrometre);
  if (t.probe_noise_um < 0) root.fail("probe_noise", "must not be negative");
  t.quantise = root.boolean("quantise");
  t.keyframes = readLocationKeyframes(root, "location_errors");
  root.finish();
  return t;
}

namespace {

// Fanuc DPRNT with #x[44]: sign, digits, 4 decimals.
std::string dprnt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%10.4f", v);
  return b;
}
std::string f6(double v) { return formatNumber(v, 6); }

}  // namespace

SynthCampaign synthesiseSphereCampaign(const parts::PlanManifest& m, const RigidTruth& truth,
                                       std::uint64_t seed) {
  SynthCampaign out;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double Rt = m.sphere_radius_mm + m.tip_radius_mm;
  const double q = m.coordinate_resolution_mm;
  const LocationErrors e0 = truth.at(m.cycle_start_s.front());

  std::ostringstream lc, fa, csv, tj;
  csv << "# probeloop synth: rigid-body location errors on the C axis, seed " << seed << "\n";
  csv << "time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  fa << "%\n";
  nlohmann::ordered_json jt;
  jt["format"] = "probeloop-truth";
  jt["relative_to_cycle"] = 1;
  for (int cyc = 1; cyc <= m.cycles; ++cyc) {
    const double t0 = m.cycle_start_s[cyc - 1];
    for (size_t i = 0; i < m.points.size(); ++i) {
      const auto& p = m.points[i];
      const auto& s = m.spheres[p.position - 1];
      const double t = t0 + p.time_in_cycle_s;
      // Absolute errors at this time; cycle 1 is what the evaluation takes as reference,
      // so the truth is reported relative to it.
      const LocationErrors e = truth.at(truth.per_point ? t : t0);
      const Vector3d centre = geometry::displacedOnTable(s.nominal_centre_mm, m.c_axis_centre_mm, e);
      // The tip travels the planned line toward the surface and triggers at distance Rt.
      const Vector3d n = p.approach.normalized();
      const Vector3d start = p.contact_mm - 10.0 * n;
      const Vector3d w = start - centre;
      const double b = n.dot(w), c = w.squaredNorm() - Rt * Rt;
      const double disc = b * b - c;
      if (disc < 0 || -b - std::sqrt(disc) > 20.0)
        throw SafetyError("synth: cycle " + std::to_string(cyc) + " " + p.feature + " point " +
                          std::to_string(p.point) +
                          ": the probing line misses the displaced sphere; the truth is too large");
      Vector3d tip = start + (-b - std::sqrt(disc)) * n;
      tip += truth.probe_noise_um * 1e-3 * normal(rng) * n;
      if (truth.quantise)
        for (int a = 0; a < 3; ++a) tip(a) = std::round(tip(a) / q) * q;
      lc << "PT " << f6(cyc) << " " << p.position << " " << p.point << " " << f6(tip.x()) << " "
         << f6(tip.y()) << " " << f6(tip.z()) << "\n";
      char cyc_field[16];
      std::snprintf(cyc_field, sizeof cyc_field, "%5d", cyc);  // #100[40]
      fa << "PT" << cyc_field << " " << p.position << " " << p.point << " "
         << dprnt(tip.x()) << " " << dprnt(tip.y()) << " " << dprnt(tip.z()) << "\n";
      csv << formatNumber(t, 3) << "," << cyc << "," << formatNumber(s.c_deg) << "," << p.feature
          << "," << p.point << "," << f6(tip.x()) << "," << f6(tip.y()) << "," << f6(tip.z())
          << "," << formatNumber(n.x(), 6) << "," << formatNumber(n.y(), 6) << ","
          << formatNumber(n.z(), 6) << "\n";
    }
    const LocationErrors e = truth.at(t0);
    std::array<double, 7> rel;
    for (int j = 0; j < 7; ++j) rel[j] = e.values()[j] - e0.values()[j];
    out.truth_per_cycle.push_back(LocationErrors::fromValues(rel));
    nlohmann::ordered_json jc{{"cycle", cyc}, {"time_s", t0}};
    for (int j = 0; j < 7; ++j) jc[LocationErrors::names()[j]] = rel[j];
    jt["cycles"].push_back(jc);
  }
  fa << "%\n";
  out.linuxcnc_log = lc.str();
  out.fanuc_dprnt = fa.str();
  out.points_csv = csv.str();
  out.truth_json = jt.dump(1) + "\n";
  return out;
}

}  // namespace probeloop::sim
