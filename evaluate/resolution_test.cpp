// Seed 004 Table 5.4, resolution column: 1 um coordinate step, d = 0.32 m.
#include <gtest/gtest.h>

#include "core/units.hpp"
#include "evaluate/sphere_campaign.hpp"

using namespace probeloop;

namespace {
// The thesis layout written out by hand (not by the planner): positions at -X, +Y, +X, -Y
// and the repeat of position 1.
parts::PlanManifest thesisManifest(double radius_mm) {
  parts::PlanManifest m;
  const double ang[5] = {180, 90, 0, 270, 180};
  for (int k = 0; k < 5; ++k) {
    parts::ManifestSphere s;
    s.position = k + 1;
    s.angle_deg = ang[k];
    s.nominal_centre_mm = {radius_mm * std::cos(degToRad(ang[k])), radius_mm * std::sin(degToRad(ang[k])), 75};
    s.formula_index = k < 4 ? k + 1 : 0;
    s.repeat_of = k == 4 ? 1 : 0;
    m.spheres.push_back(s);
  }
  m.radius_from_axis_mm = radius_mm;
  return m;
}
}  // namespace

TEST(Resolution, ReproducesSeed004Table54) {
  const auto r = evaluate::locationErrorResolution(thesisManifest(160.0), 0.001);
  ASSERT_TRUE(r.formulas.has_value());
  const double table54[7] = {0.25, 0.25, 0.25, 0.25, 3.125, 3.125, 1.5625};  // um, um/m
  for (int j = 0; j < 7; ++j) {
    EXPECT_NEAR((*r.formulas)[j], table54[j], 1e-9) << j;
    EXPECT_NEAR(r.least_squares[j], table54[j], 1e-9) << j;
  }
}

TEST(Resolution, ScalesWithTheSphereRadius) {
  // Angular resolution is 1 um / d: halving d/2 doubles it; linear ones do not change.
  const auto r = evaluate::locationErrorResolution(thesisManifest(80.0), 0.001);
  EXPECT_NEAR(r.least_squares[4], 6.25, 1e-9);
  EXPECT_NEAR(r.least_squares[0], 0.25, 1e-9);
}
