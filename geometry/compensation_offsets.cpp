#include "geometry/compensation_offsets.hpp"

#include <cmath>

#include "core/error.hpp"

namespace probeloop::geometry {

AxisOffsets compensationOffsets(const LocationErrors& e, const Eigen::Vector3d& tip_mm, const OffsetFrame& f) {
  if (!(f.reference_radius_mm > 0) || !std::isfinite(f.reference_radius_mm))
    throw InputError("", 0, "compensation offsets: the reference radius d/2 must be a positive length");
  const double rx = tip_mm.x() - f.axis_centre_xy_mm.x(), ry = tip_mm.y() - f.axis_centre_xy_mm.y();
  const double rz = tip_mm.z() - f.pivot_z_mm;
  const double nm = 1e-3;  // urad x mm = nm
  AxisOffsets o;
  o.x_um = e.EX0C_um + e.ER0T_um * rx / f.reference_radius_mm + (e.EB0C_urad * rz + e.EC0C_urad * ry) * nm;
  o.y_um = e.EY0C_um + e.ER0T_um * ry / f.reference_radius_mm + (-e.EA0C_urad * rz - e.EC0C_urad * rx) * nm;
  o.z_um = e.EZ0T_um + (e.EA0C_urad * ry - e.EB0C_urad * rx) * nm;
  return o;
}

AxisOffsets printedOffsetsB0(const LocationErrors& e, double x, double y, double z, double half_d) {
  const double nm = 1e-3, ec_text = e.EC0C_urad;
  AxisOffsets o;  // seed 004 Eqs. 6.3-6.5 with cos B = 1, sin B = 0
  o.x_um = e.EB0C_urad * z * nm + e.EX0C_um + e.ER0T_um * x / half_d - ec_text * y * nm;
  o.y_um = e.EY0C_um + e.ER0T_um * y / half_d + (e.EA0C_urad * z + ec_text * x) * nm;
  o.z_um = -e.EB0C_urad * x * nm + e.EZ0T_um + e.EA0C_urad * y * nm;
  return o;
}

}  // namespace probeloop::geometry
