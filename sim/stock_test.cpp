// The exact stock (sim/material_removal.hpp): cylindrical blank, holes, arcs swept by a tool
// while C turns, the ramp split and which cut bounds a surface. Every expected number is
// derived here from the geometry (radii of circles, chords, the end disk of an arc).
#include <gtest/gtest.h>

#include <cmath>

#include "core/units.hpp"
#include "sim/material_removal.hpp"

namespace probeloop::sim {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kExact = 1e-9;  // mm: line queries are exact to floating point

// Where a ray from far outside toward the axis (angle th, height z) first meets material:
// the radius of the surface it finds.
double radiusAt(const Stock& s, double th, double z, double from_r = 200) {
  const Vector3d dir(-std::cos(th), -std::sin(th), 0);
  const Vector3d from(from_r * std::cos(th), from_r * std::sin(th), z);
  const auto hit = s.firstMaterial(from, dir, from_r);
  return hit ? from_r - *hit : -1;
}

TEST(Stock, CylindricalBlankIsTheInscribedCylinder) {
  const Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  for (double th : {0.0, 0.3, 1.0, 2.5, -2.0}) EXPECT_NEAR(radiusAt(s, th, -10), 50, kExact) << th;
  // A chord at y = 30 enters at x = -sqrt(50^2 - 30^2) = -40.
  const auto chord = s.firstMaterial(Vector3d(-100, 30, -1), Vector3d(1, 0, 0), 200);
  ASSERT_TRUE(chord);
  EXPECT_NEAR(-100 + *chord, -40, kExact);
  // The box's corner is not material: a vertical line at (45, 45) (radius 63.6) finds nothing.
  EXPECT_FALSE(s.firstMaterial(Vector3d(45, 45, 10), Vector3d(0, 0, -1), 100));
  // From above inside the circle: the top at z 0.
  EXPECT_NEAR(*s.firstMaterial(Vector3d(10, 10, 10), Vector3d(0, 0, -1), 100), 10, kExact);
  // Height field: no material in the corner, the top inside; the largest material radius is
  // the blank's within a cell (centre within the circle, + half a cell diagonal).
  EXPECT_EQ(s.topUnder(Vector2d(48, 48), 0.2), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.topUnder(Vector2d(0, 0), 1), 0);
  const double rmax = s.maxMaterialRadius(Vector2d::Zero(), -1);
  EXPECT_LE(rmax, 50 + std::hypot(0.25, 0.25) / 2 + 1e-9);
  EXPECT_GE(rmax, 50 - 0.25);
  EXPECT_EQ(s.maxMaterialRadius(Vector2d::Zero(), 0.5), -std::numeric_limits<double>::infinity());
}

TEST(Stock, HolesAreMaterialThatIsNotThere) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  s.addHole(Vector2d(20, 0), 4, -31, 1);     // through
  s.addHole(Vector2d(-20, 0), 4, -31, -10);  // blind, from below, 20 mm deep
  // Down the through hole: nothing; from the hole's axis toward +X the wall is 4 mm away.
  EXPECT_FALSE(s.firstMaterial(Vector3d(20, 0, 5), Vector3d(0, 0, -1), 50));
  EXPECT_NEAR(*s.firstMaterial(Vector3d(20, 0, -5), Vector3d(1, 0, 0), 40), 4, kExact);
  // A ray from the axis toward +X at z -5: material from the start (s = 0).
  EXPECT_NEAR(*s.firstMaterial(Vector3d(0, 0, -5), Vector3d(1, 0, 0), 40), 0, kExact);
  // The blind hole: from above the top is whole; from below the line enters at its bottom z -10.
  EXPECT_NEAR(*s.firstMaterial(Vector3d(-20, 0, 5), Vector3d(0, 0, -1), 50), 5, kExact);
  EXPECT_NEAR(*s.firstMaterial(Vector3d(-20, 0, -40), Vector3d(0, 0, 1), 50), 30, kExact);
  // Height field: the through hole shows at the top, the blind one does not.
  EXPECT_EQ(s.topUnder(Vector2d(20, 0), 2), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.topUnder(Vector2d(-20, 0), 2), 0);
}

// A tool of radius r on a full turn at rho about the axis: a cylinder of radius rho - r is
// left above the tool's bottom (the blank's radius 50 < rho + r = 58: the ring is cut
// through to the outside); below it the blank is whole.
TEST(Stock, AFullTurnLeavesACylinderOfRadiusRhoMinusR) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  const double rho = 53, r = 5, zb = -5;
  s.recordArc(Vector2d::Zero(), rho, 0.3, 2 * kPi, zb, r, 0, 7);
  EXPECT_EQ(s.sweptVolumes(), 4u);  // pieces of 90 deg
  for (int k = 0; k < 24; ++k) {
    const double th = 2 * kPi * k / 24;  // includes the pieces' junctions 0.3 + k pi/2 nearby and the axes
    EXPECT_NEAR(radiusAt(s, th, -2), rho - r, kExact) << th;
    EXPECT_NEAR(radiusAt(s, th, -7), 50, kExact) << th;
  }
  // Rays exactly through the junctions of the pieces (0.3 + k pi / 2): no gap between them.
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(radiusAt(s, 0.3 + k * kPi / 2, -2), rho - r, kExact) << k;
  // A chord at y = 20: enters at x = -sqrt(48^2 - 20^2).
  const auto c = s.firstMaterialHit(Vector3d(-100, 20, -1), Vector3d(1, 0, 0), 200);
  ASSERT_TRUE(c);
  EXPECT_NEAR(-100 + c->s, -std::sqrt(48.0 * 48 - 400), kExact);
  EXPECT_EQ(c->tag, 7);  // the arc bounds the material there
  // From above at radius 49 (in the groove): the groove's floor z -5.
  EXPECT_NEAR(*s.firstMaterial(Vector3d(49, 0, 5), Vector3d(0, 0, -1), 50), 10, kExact);
}

// A partial arc from 0 to 60 deg (counterclockwise), and one from 200 deg back to 140 deg
// (clockwise): inside the sector the surface is at rho - r, outside at the blank's radius;
// just beyond an end the end disk (radius r about the arc's end point) bounds it: along the
// ray at angle end + d, the disk spans t = rho cos d +- sqrt(r^2 - rho^2 sin^2 d).
TEST(Stock, APartialArcLeavesItsSector) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  const double rho = 52, r = 5, zb = -5;
  s.recordArc(Vector2d::Zero(), rho, 0, degToRad(60), zb, r, 0, 1);
  s.recordArc(Vector2d::Zero(), rho, degToRad(200), degToRad(-60), zb, r, 0, 2);
  EXPECT_NEAR(radiusAt(s, degToRad(30), -1), rho - r, kExact);
  EXPECT_NEAR(radiusAt(s, degToRad(170), -1), rho - r, kExact);
  EXPECT_NEAR(radiusAt(s, degToRad(100), -1), 50, kExact);
  EXPECT_NEAR(radiusAt(s, degToRad(-30), -1), 50, kExact);
  for (double end_deg : {60.0, 140.0}) {
    const double d = degToRad(3);
    const double th = degToRad(end_deg) + (end_deg == 60 ? d : -d);
    const double t_lo = rho * std::cos(d) - std::sqrt(r * r - rho * rho * std::sin(d) * std::sin(d));
    ASSERT_GT(rho * std::cos(d) + std::sqrt(r * r - rho * rho * std::sin(d) * std::sin(d)), 50);  // open to the outside
    EXPECT_NEAR(radiusAt(s, th, -1), t_lo, kExact) << end_deg;
  }
  // The tags say which arc made which surface.
  const auto h1 = s.firstMaterialHit(Vector3d(100 * std::cos(0.5), 100 * std::sin(0.5), -1),
                                     -Vector3d(std::cos(0.5), std::sin(0.5), 0), 100);
  const auto h2 = s.firstMaterialHit(Vector3d(100 * std::cos(3.0), 100 * std::sin(3.0), -1),
                                     -Vector3d(std::cos(3.0), std::sin(3.0), 0), 100);
  const auto h0 = s.firstMaterialHit(Vector3d(0, 100, -1), Vector3d(0, -1, 0), 100);
  ASSERT_TRUE(h1 && h2 && h0);
  EXPECT_EQ(h1->tag, 1);
  EXPECT_EQ(h2->tag, 2);
  EXPECT_EQ(h0->tag, -1);  // the blank
}

// A tool whose circle covers the centre (rho < r) removes the whole disk of radius rho + r.
TEST(Stock, AnArcAroundTheCentreRemovesTheDisk) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  s.recordArc(Vector2d::Zero(), 2, 0, kPi / 3, -5, 8, 0, 0);
  // Down the axis: the floor; at radius 5 in any direction: the floor (within 8 - 2 = 6 of
  // the centre every point is within r of the arc).
  for (double th : {0.0, 2.0, 4.0}) {
    const auto h = s.firstMaterial(Vector3d(5 * std::cos(th), 5 * std::sin(th), 5), Vector3d(0, 0, -1), 50);
    ASSERT_TRUE(h);
    EXPECT_NEAR(*h, 10, kExact) << th;
  }
}

// A horizontal program move becomes a tiny ramp in the part frame when the table is tilted
// (EB0C): 1 um over 200 mm is ceil(1e-3 / 1e-5) = 100 pieces, each within 0.01 um of the
// ramp; a steep ramp of 10 mm over 1 mm is capped at ceil(|d| / 0.05) pieces. The floor a
// flat end mill of radius r leaves under a descending ramp is where its bottom was lowest
// while its disk covered the point: the ramp's z at x + r (at most the end): the pieces
// leave it within one piece's height change, never below.
TEST(Stock, RampsAreSplitByHeightChange) {
  Stock s(Vector3d(-120, -20, -30), Vector3d(120, 20, 0), 0.25);
  const double r = 4;
  s.recordCut(Vector3d(-100, 0, -5), Vector3d(100, 0, -5.001), r, 0);
  EXPECT_EQ(s.sweptVolumes(), 100u);
  for (double x : {-90.0, -33.3, 0.0, 47.0, 99.0}) {
    const double floor_z = -5 - 0.001 * (std::min(x + r, 100.0) + 100) / 200;
    const auto h = s.firstMaterial(Vector3d(x, 0, 5), Vector3d(0, 0, -1), 50);
    ASSERT_TRUE(h);
    EXPECT_GE(5 - *h, floor_z - 1e-12) << x;
    EXPECT_LE(5 - *h - floor_z, 1e-5 + 1e-12) << x;
  }
  Stock steep(Vector3d(-120, -20, -30), Vector3d(120, 20, 0), 0.25);
  steep.recordCut(Vector3d(0, 0, -1), Vector3d(1, 0, -11), 4, 0);
  EXPECT_EQ(steep.sweptVolumes(), static_cast<std::size_t>(std::ceil(std::hypot(1.0, 10.0) / 0.05)));  // 201
  // A move in the air beside the blank is not stored: it cannot remove anything.
  steep.recordCut(Vector3d(-100, 40, -5), Vector3d(100, 40, -5), 4, 0);
  EXPECT_EQ(steep.sweptVolumes(), static_cast<std::size_t>(std::ceil(std::hypot(1.0, 10.0) / 0.05)));  // 201
}

// Whether a segment's swept region can reach the blank (the test that lets a move in the
// air skip the height field) around the Ø100 x 30 cylinder, tool radius 5: a chord at
// x = 130 (its box from x = 125) cannot, nor one with the tool's edge at x = 52 (2 mm beside
// the blank's square), a pass above the top (bottom at z 0.1), or one whose box overlaps the
// square's corner but not the circle (the box's point nearest the axis (40, 40) lies 56.6 mm
// from it): that one removes nothing and stores nothing. A pass at z -1 across the top
// reaches it and removes material.
TEST(Stock, ASegmentInTheAirCannotReachTheBlank) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  const double r = 5;
  EXPECT_FALSE(s.segmentReachesBlank(Vector3d(130, -10, -5), Vector3d(130, 10, -5), r));
  EXPECT_FALSE(s.segmentReachesBlank(Vector3d(52 + r, -10, -5), Vector3d(52 + r, 10, -5), r));
  EXPECT_FALSE(s.segmentReachesBlank(Vector3d(-60, 0, 0.1), Vector3d(60, 0, 0.1), r));
  EXPECT_FALSE(s.segmentReachesBlank(Vector3d(45, 60, -5), Vector3d(60, 45, -5), r));
  EXPECT_EQ(s.removeHeightField(Vector3d(45, 60, -5), Vector3d(60, 45, -5), r).volume_mm3, 0);
  EXPECT_FALSE(s.recordCut(Vector3d(45, 60, -5), Vector3d(60, 45, -5), r, 0));
  EXPECT_TRUE(s.segmentReachesBlank(Vector3d(-60, 0, -1), Vector3d(60, 0, -1), r));
  EXPECT_GT(s.removeHeightField(Vector3d(-60, 0, -1), Vector3d(60, 0, -1), r).volume_mm3, 0);
}

// The height field's removal on an arc: the ring's volume (pi (R^2 - (rho - r)^2) x depth)
// within the cells' resolution, and its mean radius between the ring's radii.
TEST(Stock, HeightFieldRemovalOfAnArc) {
  Stock s(Vector3d(-50, -50, -30), Vector3d(50, 50, 0), 0.25, true);
  const auto rem = s.removeHeightFieldArc(Vector2d::Zero(), 53, 0, 2 * kPi, -5, 5);
  const double ring = kPi * (50.0 * 50 - 48.0 * 48) * 5;
  EXPECT_NEAR(rem.volume_mm3, ring, 0.01 * ring);
  // Volume-weighted mean radius of the ring 48..50: (2/3)(50^3 - 48^3) / (50^2 - 48^2).
  EXPECT_NEAR(rem.mean_radius_mm, 2.0 / 3 * (50.0 * 50 * 50 - 48.0 * 48 * 48) / (50.0 * 50 - 48.0 * 48), 0.05);
}

}  // namespace
}  // namespace probeloop::sim
