// The stepped workpiece's geometry and separation from one part (evaluate/stepped_workpiece.hpp)
// on points placed exactly on planes whose widths, depths, tilts and squareness are known by
// construction (hand derivations in the comments); the truth recovery on the virtual machine is
// tests/integration/sw_separation.py.
#include "evaluate/stepped_workpiece.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace probeloop::evaluate {
namespace {

using Eigen::Vector3d;

parts::ManifestFeature feature(const std::string& id, const std::string& role, Vector3d p, Vector3d n, Vector3d u) {
  parts::ManifestFeature f;
  f.nominal.id = id;
  f.nominal.kind = "plane";
  f.nominal.role = role;
  f.nominal.point_mm = p;
  f.nominal.direction = n;
  f.nominal.u = u;
  f.nominal.half_u_mm = 10;
  f.nominal.half_v_mm = 4;
  return f;
}

// Two steps, 30 and 45 mm square, floors 9 and 19 mm deep, centred on (15, 15).
parts::PlanManifest twoSteps() {
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

TtpPoints pointsOn(const parts::PlanManifest& m, const Surfaces& s, const std::string& file) {
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

TEST(SteppedWorkpieceGeometry, WidthsDepthsTiltsAndSquarenessOfKnownPlanes) {
  const auto m = twoSteps();
  Surfaces s;
  s.grow_um = 2.5;     // each wall 2.5 um out: widths +5 um
  s.tilt = 40e-6;      // dx/dz (and dy/dz) of every wall
  s.o = 100e-6;        // Y walls y = c + o (x - 15): Oz = atan(o)
  s.s_x = 30e-6;       // floors and top dz/dx
  s.s_y = -20e-6;
  s.floor_um = 3.0;    // floors 3 um high: depths 3 um short
  const auto g = steppedGeometry(m, pointsOn(m, s, "cmm.csv"), "cmm");
  ASSERT_EQ(g.steps.size(), 2u);
  for (const auto& st : g.steps) {
    EXPECT_NEAR(st.width_x_error_um(), 5.0, 1e-6) << st.step;
    EXPECT_NEAR(st.width_y_error_um(), 5.0, 1e-6) << st.step;
    EXPECT_NEAR(st.depth_error_um(), -3.0, 1e-6) << st.step;
    EXPECT_NEAR(st.lean_x_urad, 40.0, 1e-3) << st.step;
    // the Y walls' dy/dz: tilt (the turn about Z does not incline them)
    EXPECT_NEAR(st.lean_y_urad, 40.0, 1e-3) << st.step;
    EXPECT_NEAR(st.floor_slope_x_urad, 30.0, 1e-3) << st.step;
    EXPECT_NEAR(st.floor_slope_y_urad, -20.0, 1e-3) << st.step;
    // outward normals (1, 0, .) and (-o, 1, .): the angle between them 90 deg + atan(o)
    EXPECT_NEAR(st.oz_urad, std::atan(100e-6) * 1e6, 0.05) << st.step;
    EXPECT_NEAR(st.u_wall_x_um, 0.0, 1e-6);  // exact planes: no residuals
  }
}

TEST(SteppedWorkpieceSeparation, PositionErrorIsCmmMinusProbeAndProcessTheRest) {
  auto m = twoSteps();
  // The CMM sees the walls 0.2 um per mm of size farther out than the probe (e_pos over the
  // probe's travel, size - 2 mm: the line through 0 has k = 0.2 * size / (size - 2) per step,
  // which differs between steps: the weighted k lies between 0.2 * 30/28 and 0.2 * 45/43);
  // the probe sees widths +4 um (30) and +6 um (45).
  Surfaces probe_s, cmm_s;
  const auto probe_pts = [&] {
    TtpPoints t = pointsOn(m, probe_s, "probe.log");
    // widths +4 / +6 um: move the walls 2 / 3 um out per step
    for (auto& p : t.points) {
      const double out = p.feature.rfind("S1_", 0) == 0 ? 2e-3 : p.feature.rfind("S2_", 0) == 0 ? 3e-3 : 0;
      if (p.feature.find("XP") != std::string::npos) p.p_mm.x() += out;
      if (p.feature.find("XN") != std::string::npos) p.p_mm.x() -= out;
    }
    return t;
  }();
  TtpPoints cmm_pts = probe_pts;
  cmm_pts.file = "cmm.csv";
  for (auto& p : cmm_pts.points) {
    const double size = p.feature.rfind("S1_", 0) == 0 ? 30 : 45;
    if (p.feature.find("XP") != std::string::npos) p.p_mm.x() += 0.1e-3 * size;
    if (p.feature.find("XN") != std::string::npos) p.p_mm.x() -= 0.1e-3 * size;
  }
  const auto e = evaluateSteppedWorkpiece(m, cmm_pts, probe_pts);
  ASSERT_EQ(e.steps.size(), 2u);
  EXPECT_NEAR(e.steps[0].e_pos_x_um.value, 6.0, 1e-6);  // 0.2 um/mm x 30 mm
  EXPECT_NEAR(e.steps[1].e_pos_x_um.value, 9.0, 1e-6);
  EXPECT_NEAR(e.steps[0].e_pos_y_um.value, 0.0, 1e-6);
  const double k = e.k_pos_x_um_per_mm.value;
  EXPECT_GT(k, 0.2 * 45 / 43 - 1e-9);
  EXPECT_LT(k, 0.2 * 30 / 28 + 1e-9);
  // e_proc = probe width error - k (tool d + stylus d) = 4 - 12 k, 6 - 12 k
  EXPECT_NEAR(e.steps[0].e_proc_x_um.value, 4.0 - 12 * k, 1e-6);
  EXPECT_NEAR(e.steps[1].e_proc_x_um.value, 6.0 - 12 * k, 1e-6);
  EXPECT_EQ(e.probe_repeat_pairs, 0);  // no repeats: the manifest's 2 sigma / 2
  EXPECT_DOUBLE_EQ(e.probe_repeatability_um, 1.0);
  EXPECT_GT(e.steps[1].e_pos_x_um.U, 0);
}

TEST(SteppedWorkpieceSeparation, RepeatabilityFromRepeatedPlannedPoints) {
  auto m = twoSteps();
  parts::ManifestPoint a;
  a.feature = "S1_XP";
  a.point = 1;
  a.contact_mm = {31, 15, -4};
  a.approach = -Vector3d::UnitX();
  parts::ManifestPoint b = a;
  b.point = 2;  // the same place again
  m.points = {a, b};
  TtpPoints t;
  t.points.push_back({"S1_XP", 1, 1, {30.0, 15, -4}});
  t.points.push_back({"S1_XP", 2, 2, {30.0 + 1.2e-3, 15, -4}});
  const auto r = probeRepeatability(m, t);
  EXPECT_EQ(r.pairs, 1);
  EXPECT_NEAR(r.s_um, 1.2 / std::sqrt(2.0), 1e-9);  // s of one point from one difference d: |d| / sqrt 2
}

TEST(SteppedWorkpieceSeparation, MissingFeaturesAndOtherKindsAreRefused) {
  auto m = twoSteps();
  TtpPoints t = pointsOn(m, {}, "cmm.csv");
  std::erase_if(t.points, [](const TtpPoint& p) { return p.feature == "S2_YN"; });
  try {
    steppedGeometry(m, t, "cmm");
    FAIL() << "accepted a step without its -Y wall";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cmm.csv: feature S2_YN: no points measured"), std::string::npos) << e.what();
  }
  m.kind = "thermal_test_piece";
  EXPECT_THROW(evaluateSteppedWorkpiece(m, t, t), InputError);
}

}  // namespace
}  // namespace probeloop::evaluate
