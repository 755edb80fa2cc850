// The rotary calibration on the chain against sphere centres made by an independent model:
// seed 004's exact rigid-body action of C's errors (geometry/location_errors.hpp) followed by
// the trunnion's turn about its own, displaced and tilted, B line, written out here with
// Eigen's rotations. The plan is the shipped B/C example on the shipped NMV 5000.
#include "evaluate/rotary_calibration.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"
#include "planner/sphere_cycle.hpp"

namespace probeloop::evaluate {
namespace {

using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;

struct Truth {
  geometry::LocationErrors c;
  double EX0B_um = 0, EZ0B_um = 0, EA0B_urad = 0, EC0B_urad = 0;
  Vector3d placement_mm = Vector3d::Zero();
};

parts::PlanManifest plan() {
  const std::string src = PROBELOOP_SOURCE_DIR;
  const auto artifact = parts::loadSphereArtifact(src + "/examples/rotary/sphere_artifact_bc.yaml");
  const auto machine = parts::loadMachine(src + "/parts/machines/nmv5000.yaml");
  return planner::planSphereCycle(artifact, machine).manifest;
}

// Where the sphere of manifest sphere s really is under the truth t.
Vector3d centreUnder(const parts::PlanManifest& m, const parts::ManifestSphere& s, const Truth& t) {
  // Level: the nominal at this C plus the placement turned with the table (C' turns
  // clockwise), then C's location errors about the pivot at the sphere's height.
  const double a0 = (s.angle_deg + s.c_deg) * kPi / 180;  // C': angle = a0 - C
  const double R = m.radius_from_axis_mm, zc = m.table_surface_z_mm + m.sphere_centre_height_mm;
  const double th = a0 - s.c_deg * kPi / 180;
  const Eigen::Vector2d pl = Eigen::Rotation2Dd(-s.c_deg * kPi / 180) * t.placement_mm.head<2>();
  const Vector3d level(m.c_axis_centre_mm.x() + R * std::cos(th) + pl.x(), m.c_axis_centre_mm.y() + R * std::sin(th) + pl.y(),
                       zc + t.placement_mm.z());
  const Vector3d on_table = geometry::displacedOnTable(level, m.c_axis_centre_mm, t.c);
  // Then B' (turning about -Y) about its real line (ISO 230-7): through (x_B, z_B) moved by
  // EX0B, EZ0B, its direction -Y turned by EA0B about +X and EC0B about +Z.
  const Vector3d through = Vector3d(m.tilt_axis->centre_mm.x(), 0, m.tilt_axis->centre_mm.y()) +
                           Vector3d(t.EX0B_um, 0, t.EZ0B_um) * 1e-3;
  const Vector3d axis = (Eigen::AngleAxisd(t.EA0B_urad * 1e-6, Vector3d::UnitX()) *
                         Eigen::AngleAxisd(t.EC0B_urad * 1e-6, Vector3d::UnitZ())) * Vector3d(0, -1, 0);
  return through + Eigen::AngleAxisd(s.tilt_deg * kPi / 180, axis.normalized()) * (on_table - through);
}

CampaignEvaluation measured(const parts::PlanManifest& m, const std::vector<Truth>& cycles) {
  CampaignEvaluation e;
  for (std::size_t i = 0; i < cycles.size(); ++i) {
    CycleEvaluation c;
    c.cycle = static_cast<int>(i + 1);
    for (const auto& s : m.spheres) {
      SphereMeasurement sm;
      sm.position = s.position;
      sm.known_radius.centre_mm = centreUnder(m, s, cycles[i]);
      for (auto& b : sm.centre_budgets) b.u_c = 0.2;
      c.spheres.push_back(sm);
    }
    e.cycles.push_back(c);
  }
  e.reference_cycle = 1;
  return e;
}

double valueOf(const std::vector<uncertainty::Budget>& bs, const std::string& q) {
  for (const auto& b : bs)
    if (b.quantity == q) return b.value;
  ADD_FAILURE() << "no " << q;
  return NAN;
}

TEST(RotaryCalibration, RecoversTheLocationErrorsOfBAndCFromExactCentres) {
  const auto m = plan();
  ASSERT_TRUE(m.tilt_axis);
  Truth t1;
  t1.c = {4.0, -3.0, 0, 0, 12, -8, 0};
  t1.EX0B_um = 6, t1.EZ0B_um = -5, t1.EA0B_urad = 15, t1.EC0B_urad = -10;
  t1.placement_mm = Vector3d(0.12, -0.08, 0.04);
  Truth t2 = t1;  // a thermal drift of both axes
  t2.c = {5.5, -1.0, 3.0, 2.0, 20, -2, 9};
  t2.EX0B_um = 8, t2.EZ0B_um = -2, t2.EA0B_urad = 19, t2.EC0B_urad = -4;
  const auto r = calibrateRotaryAxes(m, measured(m, {t1, t2}));
  ASSERT_EQ(r.cycles.size(), 2u);
  const auto& a = r.cycles[0].absolute;
  // First order in errors of ~1e-5: the second order is below 1e-3 um (urad).
  EXPECT_NEAR(valueOf(a, "EX0C"), 4.0, 2e-3);
  EXPECT_NEAR(valueOf(a, "EY0C"), -3.0, 2e-3);
  EXPECT_NEAR(valueOf(a, "EA0C"), 12, 2e-3);
  EXPECT_NEAR(valueOf(a, "EB0C"), -8, 2e-3);
  EXPECT_NEAR(valueOf(a, "EX0B"), 6, 2e-3);
  EXPECT_NEAR(valueOf(a, "EZ0B"), -5, 2e-3);
  EXPECT_NEAR(valueOf(a, "EA0B"), 15, 2e-3);
  EXPECT_NEAR(valueOf(a, "EC0B"), -10, 2e-3);
  EXPECT_NEAR(r.cycles[0].placement[0].value, 120, 2e-3);
  EXPECT_NEAR(r.cycles[0].placement[2].value, 40, 2e-3);
  EXPECT_LT(r.cycles[0].residual_rms_um, 1e-3);
  const auto& d = r.cycles[1].relative;
  EXPECT_NEAR(valueOf(d, "EX0C"), 1.5, 2e-3);
  EXPECT_NEAR(valueOf(d, "EY0C"), 2.0, 2e-3);
  EXPECT_NEAR(valueOf(d, "EZ0T"), 3.0, 2e-3);
  EXPECT_NEAR(valueOf(d, "ER0T"), 2.0, 2e-3);
  EXPECT_NEAR(valueOf(d, "EA0C"), 8, 2e-3);
  EXPECT_NEAR(valueOf(d, "EB0C"), 6, 2e-3);
  EXPECT_NEAR(valueOf(d, "EC0C"), 9, 2e-3);
  EXPECT_NEAR(valueOf(d, "EX0B"), 2, 2e-3);
  EXPECT_NEAR(valueOf(d, "EZ0B"), 3, 2e-3);
  EXPECT_NEAR(valueOf(d, "EA0B"), 4, 2e-3);
  EXPECT_NEAR(valueOf(d, "EC0B"), 6, 2e-3);
  // Every value carries its budget: U from the centres' u through the least squares.
  for (const auto& b : d) EXPECT_GT(b.U, 0) << b.quantity;
}

TEST(RotaryCalibration, TheLevelPositionsAloneCannotSeeTheBAxis) {
  auto m = plan();
  std::vector<parts::ManifestSphere> level;
  for (const auto& s : m.spheres)
    if (s.tilt_deg == 0) level.push_back(s);
  m.spheres = level;
  const auto id = rotaryIdentifiability(m);
  EXPECT_FALSE(id.relative.all());
  for (std::size_t j = 0; j < id.relative.names.size(); ++j) {
    const std::string& n = id.relative.names[j];
    // B's line (ISO 230-7) moves nothing at B = 0: each of its four alone leaves the centres
    // unchanged; C's seven (seed 004's, at B = 0) stay identifiable.
    EXPECT_EQ(id.relative.identifiable[j], n.find("0B") == std::string::npos) << n;
  }
  EXPECT_EQ(id.relative.relations.size(), 4u);
  EXPECT_THROW(calibrateRotaryAxes(m, measured(m, {Truth{}, Truth{}})), GeometryError);
}

TEST(RotaryCalibration, AnAbsoluteCalibrationCannotTellCsZeroFromWhereTheSphereSits) {
  const auto id = rotaryIdentifiability(plan());
  EXPECT_TRUE(id.relative.all());
  for (std::size_t j = 0; j < id.absolute.names.size(); ++j) {
    const std::string& n = id.absolute.names[j];
    const bool confounded = n == "EC0C" || n == "EZ0T" || n == "ER0T" || n.rfind("placement", 0) == 0;
    EXPECT_EQ(id.absolute.identifiable[j], !confounded) << n;
  }
  // One relation each: C's zero with the sphere's placement across the radius, ...
  EXPECT_EQ(id.absolute.relations.size(), 3u);
  for (const auto& s : id.absolute.sentences()) EXPECT_NE(s.find("cannot be separated"), std::string::npos) << s;
}

}  // namespace
}  // namespace probeloop::evaluate
