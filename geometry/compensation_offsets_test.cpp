#include "geometry/compensation_offsets.hpp"

#include <gtest/gtest.h>

#include <random>

#include "core/error.hpp"

namespace probeloop::geometry {
namespace {

// The exact rigid displacement of a table point under the location errors, built here
// independently: rotation Rx(EA) Ry(EB) Rz(-EC) about the pivot (axis centre at pivot_z),
// radial growth proportional to the radius (ER0T at d/2), then the translation.
Eigen::Vector3d exactDisplacement(const LocationErrors& e, const Eigen::Vector3d& p, const OffsetFrame& f) {
  const Eigen::Vector3d pivot(f.axis_centre_xy_mm.x(), f.axis_centre_xy_mm.y(), f.pivot_z_mm);
  Eigen::Vector3d r = p - pivot;
  r.head<2>() *= 1 + e.ER0T_um * 1e-3 / f.reference_radius_mm;
  const Eigen::Matrix3d rot = (Eigen::AngleAxisd(e.EA0C_urad * 1e-6, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(e.EB0C_urad * 1e-6, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(-e.EC0C_urad * 1e-6, Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
  return (pivot + Eigen::Vector3d(e.EX0C_um, e.EY0C_um, e.EZ0T_um) * 1e-3 + rot * r - p) * 1e3;  // um
}

LocationErrors randomErrors(std::mt19937& g) {
  std::uniform_real_distribution<double> lin(-30, 30), ang(-60, 60);
  LocationErrors e;
  e.EX0C_um = lin(g), e.EY0C_um = lin(g), e.EZ0T_um = lin(g), e.ER0T_um = lin(g) / 3;
  e.EA0C_urad = ang(g), e.EB0C_urad = ang(g), e.EC0C_urad = ang(g);
  return e;
}

TEST(CompensationOffsets, EqualTheRigidDisplacementOfTheTablePointToFirstOrder) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> xy(-300, 300), z(-50, 400);
  const OffsetFrame f{Eigen::Vector2d(12.5, -4.0), 75.0, 160.0};
  for (int i = 0; i < 200; ++i) {
    const LocationErrors e = randomErrors(g);
    const Eigen::Vector3d p(xy(g), xy(g), z(g));
    const AxisOffsets o = compensationOffsets(e, p, f);
    const Eigen::Vector3d d = exactDisplacement(e, p, f);
    // Second-order terms: (60 urad)^2 x 500 mm = 1.8 nm; radial x angle 3.3 um/160 mm x 60 urad x 300 mm.
    EXPECT_NEAR(o.x_um, d.x(), 3e-3) << i;
    EXPECT_NEAR(o.y_um, d.y(), 3e-3) << i;
    EXPECT_NEAR(o.z_um, d.z(), 3e-3) << i;
  }
}

TEST(CompensationOffsets, AtTheSphereTheyAgreeWithTheSimulatorsDisplacement) {
  // geometry::displacedOnTable pivots at the point's own height and grows the radius by ER0T:
  // at the sphere (radius d/2, pivot height = its centre) both conventions coincide.
  std::mt19937 g(11);
  const OffsetFrame f{Eigen::Vector2d(0, 0), 75.0, 160.0};
  for (double c_deg : {0.0, 90.0, 180.0, 270.0, 33.0}) {
    const double a = c_deg * M_PI / 180;
    const Eigen::Vector3d p(-160 * std::cos(a), -160 * std::sin(a), 75.0);
    const LocationErrors e = randomErrors(g);
    const Eigen::Vector3d d = (displacedOnTable(p, f.axis_centre_xy_mm, e) - p) * 1e3;
    const AxisOffsets o = compensationOffsets(e, p, f);
    EXPECT_NEAR(o.x_um, d.x(), 2e-3);
    EXPECT_NEAR(o.y_um, d.y(), 2e-3);
    EXPECT_NEAR(o.z_um, d.z(), 2e-3);
  }
}

TEST(CompensationOffsets, DepartFromThePrintedEquationsInTheEC0CTermsAndEq64sEA0CZ) {
  // With the pivot at the NC zero and the axis at the origin, the derivation and the print
  // (E_C0C of the text = EC0C, Eq. 5.10's sign) agree in the EX, EY, EZ, ER and EB terms and in
  // Eq. 6.5's EA0C Y; they differ by exactly 2 EC0C Y (X), 2 EC0C X + 2 EA0C Z (Y).
  std::mt19937 g(3);
  const OffsetFrame f{Eigen::Vector2d(0, 0), 0.0, 160.0};
  for (int i = 0; i < 20; ++i) {
    const LocationErrors e = randomErrors(g);
    const Eigen::Vector3d p(100.0 + i, -50.0 + 3 * i, 20.0 * i);
    const AxisOffsets o = compensationOffsets(e, p, f);
    const AxisOffsets printed = printedOffsetsB0(e, p.x(), p.y(), p.z(), 160.0);
    EXPECT_NEAR(printed.x_um - o.x_um, -2 * e.EC0C_urad * p.y() * 1e-3, 1e-12);
    EXPECT_NEAR(printed.y_um - o.y_um, 2 * (e.EA0C_urad * p.z() + e.EC0C_urad * p.x()) * 1e-3, 1e-12);
    EXPECT_NEAR(o.z_um, printed.z_um, 1e-12);
  }
}

TEST(CompensationOffsets, RefuseANonPositiveReferenceRadius) {
  EXPECT_THROW(compensationOffsets(LocationErrors{}, Eigen::Vector3d::Zero(), OffsetFrame{}), InputError);
}

}  // namespace
}  // namespace probeloop::geometry
