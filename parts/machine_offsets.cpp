#include "parts/machine_offsets.hpp"

#include "core/error.hpp"
#include "core/csv.hpp"

namespace probeloop::parts {

geometry::AxisOffsets MachineOffsetFrame::offsetsAt(const geometry::LocationErrors& e, const Eigen::Vector3d& tip_mm,
                                                    double b_deg) const {
  if (b_deg != 0 && !b_located)
    throw InputError(machine_file, 0, "b_axis: the offsets at B " + formatNumber(b_deg) +
                                          " deg need the B axis's line (centre_x, centre_z)");
  return geometry::compensationOffsets(e, tip_mm, b_deg, frame);
}

MachineOffsetFrame machineOffsetFrame(const Machine& m, double pivot_z_mm, double reference_radius_mm) {
  MachineOffsetFrame f;
  f.machine_file = m.file;
  f.frame.table.axis_centre_xy_mm = m.c_axis_centre_mm;
  f.frame.table.pivot_z_mm = pivot_z_mm;
  f.frame.table.reference_radius_mm = reference_radius_mm;
  if (m.b.present && m.b_axis_centre_xz_mm) {
    f.b_located = true;
    f.frame.b_axis_xz_mm = *m.b_axis_centre_xz_mm;
    // As parts/machine_chain.cpp turns B: about -Y when +B is clockwise seen from +Y.
    f.frame.b_sense = m.b.positive_is_clockwise ? -1.0 : 1.0;
  }
  return f;
}

}  // namespace probeloop::parts
