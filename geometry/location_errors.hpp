// Location errors of a C axis with the table's functional surface (ISO 230-7 + Gebhardt;
// seed 004 Table 5.2) and their exact rigid-body action on a point of the table.
//
// Sign conventions (docs/conventions.md, with drawing), all in the machine frame:
// - EX0C, EY0C, EZ0T: translation of the C axis / table surface, um, at the height of the
//   sphere centre (a tilt pivots about the axis at that height);
// - ER0T: radial growth of the table at the sphere radius d/2, um (outward positive);
// - EA0C, EB0C: right-hand rotations of the C axis about +X and +Y, urad (= um/m);
// - EC0C: zero-position error, urad; positive = the table found turned clockwise seen from
//   +Z, which is +C on a workpiece-side C' axis. This is the sign of seed 004 Eq. 5.10
//   with positions 1-4 at -X, +Y, +X, -Y.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <string>

namespace probeloop::geometry {

struct LocationErrors {
  double EX0C_um = 0, EY0C_um = 0, EZ0T_um = 0, ER0T_um = 0;
  double EA0C_urad = 0, EB0C_urad = 0, EC0C_urad = 0;

  static constexpr int kCount = 7;
  std::array<double, kCount> values() const {
    return {EX0C_um, EY0C_um, EZ0T_um, ER0T_um, EA0C_urad, EB0C_urad, EC0C_urad};
  }
  static LocationErrors fromValues(const std::array<double, kCount>& v);
  static const std::array<const char*, kCount>& names();  // "EX0C_um", ..., "EC0C_urad"
};

// Where a point that sits nominally at `nominal_mm` on the table is found when the C axis
// (centre `axis_centre_xy_mm`, pivot at the point's own height) carries the errors `e`:
// radial growth scales the in-plane radius, the rotation Rx(EA) Ry(EB) Rz(-EC) acts about
// the pivot, then the translation. Exact (not linearised), so tests of the linear
// estimators see the true second-order terms.
Eigen::Vector3d displacedOnTable(const Eigen::Vector3d& nominal_mm,
                                 const Eigen::Vector2d& axis_centre_xy_mm,
                                 const LocationErrors& e);

}  // namespace probeloop::geometry
