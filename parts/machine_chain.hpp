// The machine description as a kinematic chain (geometry/kinematic_chain.hpp; issue 33):
// the workpiece branch from the frame through the workpiece-side linear axes, the tilting
// axis (A or B, when the machine has one and its axis line is located) and the C table; the
// tool branch through the tool-side linear axes to the stylus tip. Which linear axes carry
// the workpiece comes from the ISO 10791-1 code (Machine::workpiece_side); a workpiece-side
// axis moves the table by -q so that +X still moves the tool +X relative to the workpiece.
// Rotary directions follow Machine::RotaryAxis::positive_is_clockwise (C' turns about -Z).
//
// Location errors: C's are seed 004's, the table square to its axis and carrying its error
// (LocationConvention::BodyOnAxis), in the machine frame at A = B = 0; the tilting axis's are
// those of its line (ISO 230-7, AxisLine): at A = B = 0 they move nothing but its zero.
//
// Coordinates are tip coordinates (the probe's length offset active): at all-zero errors
// machineCoordinatesOf(point) of a table point at C = B = 0 is that point.
//
// `c_reference_z_mm`: the height of C's location errors' reference point on its axis line:
// EX0C and EY0C hold there and EA0C, EB0C pivot there. The sphere cycle uses the sphere
// centre's height, as seed 004 does (docs/conventions.md); 0 means the table surface.
#pragma once
#include <optional>

#include "geometry/kinematic_chain.hpp"
#include "parts/machine.hpp"

namespace probeloop::parts {

// InputError (file of the machine) when a tilting axis is present but not located and
// `need_tilt` is set.
geometry::KinematicChain machineChain(const Machine& m, std::optional<double> c_reference_z_mm = std::nullopt,
                                      bool need_tilt = false);

// "A", "B" or "" for the machine's tilting axis.
std::string tiltAxisName(const Machine& m);

}  // namespace probeloop::parts
