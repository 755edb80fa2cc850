// The frame in which seed 004's offsets (geometry/compensation_offsets.hpp, Eqs. 6.3-6.5 as
// derived) are evaluated on a machine: the C axis, the height where its errors hold and the
// radius d/2 of ER0T; on a B/C trunnion also B's axis line and sense (issue 33 item 3), as
// parts/machine_chain.hpp builds the chain from the same description.
//
// Contract: without a B axis, or with B but its line unknown (no `b_axis` in the file), the
// B fields stay at zero and `b_located` is false: offsets at B = 0 only (offsetsAt refuses
// B != 0 then, with an InputError naming the machine file).
#pragma once
#include "geometry/compensation_offsets.hpp"
#include "parts/machine.hpp"

namespace probeloop::parts {

struct MachineOffsetFrame {
  std::string machine_file;
  geometry::TrunnionFrame frame;
  bool b_located = false;
  // The offsets at the commanded tip (machine coordinates) and B (deg).
  geometry::AxisOffsets offsetsAt(const geometry::LocationErrors& e, const Eigen::Vector3d& tip_mm, double b_deg) const;
};

// pivot_z_mm: machine Z of C's errors' reference point (the sphere centres'); d/2 > 0.
MachineOffsetFrame machineOffsetFrame(const Machine& m, double pivot_z_mm, double reference_radius_mm);

}  // namespace probeloop::parts
