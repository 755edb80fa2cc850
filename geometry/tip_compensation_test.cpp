#include "geometry/tip_compensation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace {
Element sphere(const Vector3d& c, double r) {
  Element e;
  e.kind = ElementKind::Sphere;
  e.position_mm = c;
  e.radius_mm = r;
  return e;
}
}  // namespace

TEST(TipCompensation, BallProbedFromOutsideShrinksByTipRadius) {
  const Vector3d c(400, -200, 90);
  const Element tips = sphere(c, 12.5 + 1.5);  // tip centres of a 1.5 mm tip on a 12.5 mm ball
  Points3 p{c + Vector3d(14, 0, 0), c + Vector3d(0, 14, 0), c + Vector3d(0, 0, 14)};
  Points3 approach{Vector3d(-1, 0, 0), Vector3d(0, -1, 0), Vector3d(0, 0, -1)};
  const MaterialSide side = materialSideFromApproach(tips, p, approach);
  EXPECT_EQ(side, MaterialSide::Inside);
  const Element ball = compensateTipRadius(tips, 1.5, side);
  EXPECT_DOUBLE_EQ(ball.radius_mm, 12.5);
  EXPECT_EQ(ball.position_mm, c);
}

TEST(TipCompensation, BoreProbedFromInsideGrowsByTipRadius) {
  Element tips;
  tips.kind = ElementKind::Cylinder;
  tips.position_mm = Vector3d(0, 0, 0);
  tips.direction = Vector3d(0, 0, 1);
  tips.radius_mm = 20.0 - 2.0;
  Points3 p{Vector3d(18, 0, -5), Vector3d(0, -18, 3)};
  Points3 approach{Vector3d(1, 0, 0), Vector3d(0.2, -1, 0)};  // outward, slightly oblique
  const MaterialSide side = materialSideFromApproach(tips, p, approach);
  EXPECT_EQ(side, MaterialSide::Outside);
  EXPECT_DOUBLE_EQ(compensateTipRadius(tips, 2.0, side).radius_mm, 20.0);
}

TEST(TipCompensation, PlaneMovesIntoTheMaterial) {
  Element tips;  // top face z = 5 probed from above with a 3 mm tip: centres at z = 8
  tips.kind = ElementKind::Plane;
  tips.position_mm = Vector3d(10, 20, 8);
  tips.direction = Vector3d(0, 0, 1);
  const MaterialSide side = materialSideFromApproach(tips, Vector3d(0, 0, -1));
  EXPECT_EQ(side, MaterialSide::Inside);
  EXPECT_NEAR(compensateTipRadius(tips, 3.0, side).position_mm.z(), 5.0, 1e-15);
  // The same face probed from below (a ceiling) moves the other way.
  EXPECT_NEAR(compensateTipRadius(tips, 3.0, materialSideFromApproach(tips, Vector3d(0, 0, 1)))
                  .position_mm.z(),
              11.0, 1e-15);
}

TEST(TipCompensation, ConeSurfacePointsLieOnTheCompensatedCone) {
  // Independent construction: points on a known material cone, tip centres offset along the
  // surface normal by the tip radius; the tip-centre cone is built from the same offset.
  Element material;
  material.kind = ElementKind::Cone;
  material.position_mm = Vector3d(100, 50, -30);
  material.direction = Vector3d(1, 2, 2).normalized();
  material.radius_mm = 15.0;
  material.half_angle_rad = 20.0 * M_PI / 180.0;
  const double t = 2.5;
  Element tips = material;
  tips.radius_mm = material.radius_mm + t / std::cos(material.half_angle_rad);
  const Vector3d u = material.direction.unitOrthogonal();
  const Vector3d w = material.direction.cross(u);
  for (int i = 0; i < 12; ++i) {
    const double phi = i * 0.5, s = -10.0 + 2.0 * i;
    const Vector3d radial = std::cos(phi) * u + std::sin(phi) * w;
    const Vector3d on = material.position_mm + s * material.direction +
                        (material.radius_mm + s * std::tan(material.half_angle_rad)) * radial;
    const Vector3d normal = outwardNormal(material, on);
    const Vector3d tip = on + t * normal;
    EXPECT_NEAR(signedDistance(tips, tip), 0.0, 1e-12);
    const Element back = compensateTipRadius(tips, t, materialSideFromApproach(tips, {tip}, {-normal}));
    EXPECT_NEAR(signedDistance(back, on), 0.0, 1e-12);
  }
}

TEST(TipCompensation, MixedSidesAreRefusedNamingThePoints) {
  const Element tips = sphere(Vector3d::Zero(), 10);
  Points3 p{Vector3d(10, 0, 0), Vector3d(0, 10, 0)};
  Points3 approach{Vector3d(-1, 0, 0), Vector3d(0, 1, 0)};
  try {
    materialSideFromApproach(tips, p, approach);
    FAIL() << "mixed sides accepted";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("points 1 and 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("opposite sides"), std::string::npos) << e.what();
  }
}

TEST(TipCompensation, ApproachAlongTheSurfaceIsRefused) {
  const Element tips = sphere(Vector3d::Zero(), 10);
  EXPECT_THROW(materialSideFromApproach(tips, {Vector3d(10, 0, 0)}, {Vector3d(0, 1, 0)}),
               GeometryError);
  EXPECT_THROW(materialSideFromApproach(tips, {Vector3d(10, 0, 0)}, {Vector3d(0, 0, 0)}),
               GeometryError);
}

TEST(TipCompensation, TipLargerThanTheElementAndLine3dAreExplained) {
  EXPECT_THROW(compensateTipRadius(sphere(Vector3d::Zero(), 1.0), 2.0, MaterialSide::Inside),
               GeometryError);
  Element line;
  line.kind = ElementKind::Line3D;
  EXPECT_THROW(compensateTipRadius(line, 1.0, MaterialSide::Inside), GeometryError);
  EXPECT_THROW(compensateTipRadius(sphere(Vector3d::Zero(), 5.0), -1.0, MaterialSide::Inside),
               GeometryError);
}
