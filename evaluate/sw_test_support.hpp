// Test-only (evaluate's stepped-workpiece tests): a two-step manifest and points placed exactly on
// planes whose widths, depths, tilts and squareness are known by construction.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

#include "evaluate/ttp_ingest.hpp"
#include "evaluate/feature_test_support.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate::sw_test {

using Eigen::Vector3d;

inline parts::ManifestFeature feature(const std::string& id, const std::string& role, Vector3d p, Vector3d n, Vector3d u) {
  return feature_test::nominalPlane(id, p, n, u, 10, 4, role);
}

// Two steps, 30 and 45 mm square, floors 9 and 19 mm deep, centred on (15, 15).
inline parts::PlanManifest twoSteps() {
  parts::PlanManifest m;
  m.file = "plan.json";
  m.kind = "stepped_workpiece";
  m.tip_radius_mm = 1.0;
  m.probe_repeatability_2sigma_um = 2.0;
  m.material_alpha_um_per_m_K = 23.4;
  m.sw.experiment = "W8";
  m.sw.sizes_mm = {30, 45};
  m.sw.tool_diameter_mm = 10;
  m.sw.cmm.mpe_constant_um = 1.5;
  m.sw.cmm.mpe_length_mm = 333;
  m.sw.cmm.temperature_half_width_K = 0.5;
  m.features.push_back(feature("TOP", "datum_top", {15, 15, 0}, Vector3d::UnitZ(), Vector3d::UnitX()));
  const double depth[2] = {9, 19}, top[2] = {0, -9};
  for (int k = 1; k <= 2; ++k) {
    const double h = m.sw.sizes_mm[k - 1] / 2, zc = 0.5 * (top[k - 1] - depth[k - 1]);
    const std::string s = "S" + std::to_string(k) + "_";
    m.features.push_back(feature(s + "XP", "wall", {15 + h, 15, zc}, Vector3d::UnitX(), Vector3d::UnitY()));
    m.features.push_back(feature(s + "XN", "wall", {15 - h, 15, zc}, -Vector3d::UnitX(), -Vector3d::UnitY()));
    m.features.push_back(feature(s + "YP", "wall", {15, 15 + h, zc}, Vector3d::UnitY(), -Vector3d::UnitX()));
    m.features.push_back(feature(s + "YN", "wall", {15, 15 - h, zc}, -Vector3d::UnitY(), Vector3d::UnitX()));
    m.features.push_back(feature(s + "F", "floor", {15, 15, -depth[k - 1]}, Vector3d::UnitZ(), Vector3d::UnitX()));
  }
  return m;
}

// The surfaces: every width `grow_um` larger than nominal per wall, walls leaning dx/dz = tilt,
// the Y walls turned by atan(o) about Z, floors and top sloped s_x, s_y; the floors lie
// `floor_um` higher than nominal.
struct Surfaces {
  double grow_um = 0, tilt = 0, o = 0, s_x = 0, s_y = 0, floor_um = 0;
};

inline TtpPoints pointsOn(const parts::PlanManifest& m, const Surfaces& s, const std::string& file) {
  TtpPoints t;
  t.file = file;
  auto add = [&](const std::string& f, Vector3d p) { t.points.push_back({f, static_cast<int>(t.points.size()) + 1, 1, p}); };
  auto z_of = [&](double x, double y, double z0) { return z0 + s.s_x * (x - 15) + s.s_y * (y - 15); };
  for (double x : {8.0, 15.0, 22.0})
    for (double y : {8.0, 15.0, 22.0}) add("TOP", {x, y, z_of(x, y, 0)});
  const double depth[2] = {9, 19}, top[2] = {0, -9};
  for (int k = 1; k <= 2; ++k) {
    const double h = m.sw.sizes_mm[k - 1] / 2 + s.grow_um * 1e-3, zc = 0.5 * (top[k - 1] - depth[k - 1]);
    const std::string id = "S" + std::to_string(k) + "_";
    for (double v : {-8.0, 0.0, 8.0})
      for (double dz : {-3.0, 3.0}) {
        add(id + "XP", {15 + h + s.tilt * dz, 15 + v, zc + dz});
        add(id + "XN", {15 - h + s.tilt * dz, 15 + v, zc + dz});
        add(id + "YP", {15 + v, 15 + h + s.o * v + s.tilt * dz, zc + dz});
        add(id + "YN", {15 + v, 15 - h + s.o * v + s.tilt * dz, zc + dz});
      }
    // the floor ring beside the step (outside the step, inside the next)
    const double r = m.sw.sizes_mm[k - 1] / 2 + 3;
    for (const auto& [x, y] : std::vector<std::pair<double, double>>{{15 + r, 15}, {15 - r, 15}, {15, 15 + r}, {15, 15 - r}, {15 + r, 15 + r}})
      add(id + "F", {x, y, z_of(x, y, -depth[k - 1] + s.floor_um * 1e-3)});
  }
  return t;
}

}  // namespace probeloop::evaluate::sw_test
