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

AxisOffsets compensationOffsets(const LocationErrors& e, const Eigen::Vector3d& tip_mm, double b_deg,
                                const TrunnionFrame& f) {
  if (b_deg == 0) return compensationOffsets(e, tip_mm, f.table);
  if (!std::isfinite(b_deg) || !(f.b_sense == 1 || f.b_sense == -1))
    throw InputError("", 0, "compensation offsets: B must be a number and its sense +1 or -1");
  const double kDeg = 3.14159265358979323846 / 180.0;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(f.b_sense * b_deg * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d b_line(f.b_axis_xz_mm.x(), 0.0, f.b_axis_xz_mm.y());
  // Where the table point under the tip is at B = 0 (the frame the errors hold in) ...
  const Eigen::Vector3d at_b0 = b_line + R.transpose() * (tip_mm - b_line);
  const AxisOffsets d = compensationOffsets(e, at_b0, f.table);
  // ... and its displacement turned by B into the machine frame.
  const Eigen::Vector3d v = R * Eigen::Vector3d(d.x_um, d.y_um, d.z_um);
  return {v.x(), v.y(), v.z()};
}

AxisOffsets printedOffsets(const LocationErrors& e, double x, double y, double z, double b_hat_deg, double half_d) {
  const double nm = 1e-3, b = b_hat_deg * 3.14159265358979323846 / 180.0, c = std::cos(b), s = std::sin(b);
  const double EX = e.EX0C_um, EY = e.EY0C_um, EZ = e.EZ0T_um, ER = e.ER0T_um;
  const double EA = e.EA0C_urad * nm, EB = e.EB0C_urad * nm, EC = e.EC0C_urad * nm;  // um per mm
  AxisOffsets o;
  o.x_um = EB * z + (EX + ER * x / half_d - EC * y) * c + (EZ + EA * y) * s;        // seed 004 Eq. 6.3
  o.y_um = EY + ER * y / half_d + (EA * z + EC * x) * c - (EA * x + EC * z) * s;    // seed 004 Eq. 6.4
  o.z_um = -EB * x + (EZ + EA * y) * c + (-EX + ER * z / half_d + EC * y) * s;      // seed 004 Eq. 6.5
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
