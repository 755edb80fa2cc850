// The error -> axis-offset transformation taken from a kinematic chain (issue 33 item 3; the
// general form of seed 004 Eqs. 6.3-6.5, notes seed004.md §2.4): at a pose of the machine, the
// offset (um, ADDED to the commanded X Y Z, the convention of geometry/compensation_offsets.hpp)
// that brings the tool tip back onto the workpiece point it meets nominally there once the
// chain carries the errors, to first order in the errors.
//
// It is the sensitivity of machineCoordinatesOf (geometry/kinematic_chain.hpp, exact HTMs) to
// each parameter, by chainSensitivity's central differences: no linearisation by hand.
// ER0T is not a twist: it is a radial scale of the table about its C axis, (ER0T / (d/2)) times
// the point's distance from the axis, outward (docs/conventions.md); it is taken here by moving
// the workpiece point in the table's own frame.
//
// Contract: `pose.positions` holds every axis position, X Y Z the commanded (tip) ones; the
// table carrying the radial scale is the workpiece branch's last body (the C table of
// parts/machine_chain.hpp). GeometryError from machineCoordinatesOf when the pose is singular.
#pragma once
#include <Eigen/Dense>
#include <vector>

#include "geometry/kinematic_chain.hpp"

namespace probeloop::geometry {

// The workpiece point (workpiece-body frame) under the tool tip at the pose.
Eigen::Vector3d workpiecePointUnderTip(const KinematicChain& chain, const ChainState& pose);

// d(offset)/d(parameter): 3 rows (X Y Z offset, um), one column per parameter (per um or
// urad), then, when reference_radius_mm > 0, one column for the table's radial scale (per um
// of radial growth at the radius reference_radius_mm).
Eigen::MatrixXd chainOffsetSensitivity(const KinematicChain& chain, const ChainState& pose,
                                       const std::vector<ChainParameter>& params, double reference_radius_mm = 0);

// Seed 004's seven errors on the chain's C axis, as geometry/location_errors.hpp signs them:
// EX0C, EY0C, EZ0T (the C joint's location translation), EA0C, EB0C (its location rotation
// about +X, +Y of the parent frame: the trunnion's, so they turn with B) and EC0C (rotation
// about +Z with sign -1: positive = the table turned clockwise seen from +Z).
std::vector<ChainParameter> seed004Parameters(const KinematicChain& chain);

// The 3 x 7 offset coefficients in LocationErrors order (EX0C EY0C EZ0T ER0T EA0C EB0C EC0C),
// um per um or urad, from the chain; d/2 = reference_radius_mm (> 0).
Eigen::Matrix<double, 3, 7> seed004OffsetSensitivity(const KinematicChain& chain, const ChainState& pose,
                                                     double reference_radius_mm);

}  // namespace probeloop::geometry
