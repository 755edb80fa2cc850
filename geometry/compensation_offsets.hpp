// The error -> axis-offset transformation of seed 004 Eqs. 6.3-6.5 (notes seed004.md §2.4),
// derived here for the table-side C axis at B = 0, first order in the errors (rigid body).
//
// Convention (stated and tested, the thesis leaves the sign open, notes §2.4 [AMBIGUOUS]):
// the offset is ADDED to the commanded X/Y/Z, and equals the displacement the location
// errors give the table point under the tool tip, so the tool follows the displaced
// workpiece: a probe of a table point then reports its nominal position (the residual
// error is the error minus its prediction). With e the errors of geometry/location_errors.hpp
// (EC0C positive = table turned clockwise seen from +Z), r = tip - (axis centre, pivot height):
//   X = EX0C + ER0T r_x/(d/2) + EB0C r_z + EC0C r_y
//   Y = EY0C + ER0T r_y/(d/2) - EA0C r_z - EC0C r_x
//   Z = EZ0T + EA0C r_y - EB0C r_x
// (angles in urad times mm give nm). Against the printed equations at B = 0:
// - the EC0C terms carry the opposite sign: our EC0C has Eq. 5.10's sign (E_C0C of the text),
//   and under it the printed -E_C0C Y (6.3) and +E_C0C X (6.4) move the tool away from the
//   turned table point. Either Ch. 6 counts C the other way or the print slipped; the rigid
//   body decides, and the test below pins the difference;
// - ER0T scales with the radius as printed (the table's expansion: ER0T is measured at d/2);
// - Eq. 6.4 prints +E_A0C Z; a right-hand rotation about +X moves a point above the pivot
//   towards -Y, and Eq. 6.5's +E_A0C Y (which the derivation confirms) is the same rotation,
//   so the printed +E_A0C Z cannot hold with it: the derivation's -E_A0C r_z is used;
// - the printed Z has its origin at the NC zero (Fig. 6.11): the tilt's pivot is where the
//   location errors were measured, which for the sphere cycle is the sphere centre's height,
//   so r_z = Z - pivot_z.
// B != 0 (the B/C trunnion of seed 004, issue 33 item 3): the C axis's errors were measured at
// B = 0 and hold in the trunnion's frame, so they turn with it. The first-order propagation
// through the chain frame -> B -> C: take the tip back to where the table point under it sits
// at B = 0, displace it there as above, turn the displacement by B. The kinematic chain gives
// the same to first order (geometry/chain_offsets.hpp, tested at every B); the printed
// equations, term by term: docs/kinematic-offsets.md.
#pragma once
#include <Eigen/Dense>

#include "geometry/location_errors.hpp"

namespace probeloop::geometry {

struct AxisOffsets {
  double x_um = 0, y_um = 0, z_um = 0;
};

struct OffsetFrame {
  Eigen::Vector2d axis_centre_xy_mm = Eigen::Vector2d::Zero();
  double pivot_z_mm = 0;            // height at which the location errors hold
  double reference_radius_mm = 0;   // d/2: the radius at which ER0T was measured (> 0)
};

AxisOffsets compensationOffsets(const LocationErrors& e, const Eigen::Vector3d& tip_mm, const OffsetFrame& f);

// A C table on a B trunnion (parts/machine_chain.hpp; parts/machines/nmv5000.yaml).
struct TrunnionFrame {
  OffsetFrame table;                                         // the C axis at B = 0
  Eigen::Vector2d b_axis_xz_mm = Eigen::Vector2d::Zero();   // B's axis line (parallel to Y) at B = 0
  // +1: +B turns the table right-handedly about +Y; -1: about -Y (B' on the workpiece side,
  // clockwise seen from +Y: parts::RotaryAxis::positive_is_clockwise).
  double b_sense = -1;
};

// At B = 0 exactly the B = 0 function above (the same bytes); tip_mm: commanded tip, machine
// coordinates; b_deg: the B axis's commanded position.
AxisOffsets compensationOffsets(const LocationErrors& e, const Eigen::Vector3d& tip_mm, double b_deg,
                                const TrunnionFrame& f);

// The printed Eqs. 6.3-6.5 at B = 0 verbatim (E_C0C of the text = EC0C here), X Y Z from the
// NC origin: kept to show, in a test, where the derivation departs from the print.
AxisOffsets printedOffsetsB0(const LocationErrors& e, double x_mm, double y_mm, double z_mm, double half_d_mm);
// Eqs. 6.3-6.5 verbatim at any B^ (deg; the print does not say which way B^ turns the table:
// docs/kinematic-offsets.md), E_C0C of the text = EC0C here, X^ Y^ Z^ from the print's origin.
AxisOffsets printedOffsets(const LocationErrors& e, double x_mm, double y_mm, double z_mm, double b_hat_deg,
                           double half_d_mm);

}  // namespace probeloop::geometry
