#include "geometry/location_errors.hpp"

#include <cmath>

namespace probeloop::geometry {

LocationErrors LocationErrors::fromValues(const std::array<double, kCount>& v) {
  return {v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
}

const std::array<const char*, LocationErrors::kCount>& LocationErrors::names() {
  static const std::array<const char*, kCount> n{"EX0C_um",   "EY0C_um",   "EZ0T_um",  "ER0T_um",
                                                 "EA0C_urad", "EB0C_urad", "EC0C_urad"};
  return n;
}

Eigen::Vector3d displacedOnTable(const Eigen::Vector3d& p, const Eigen::Vector2d& axis,
                                 const LocationErrors& e) {
  const Eigen::Vector3d pivot(axis.x(), axis.y(), p.z());
  Eigen::Vector3d r = p - pivot;
  const double radius = r.head<2>().norm();
  if (radius > 0) r.head<2>() *= (radius + e.ER0T_um * 1e-3) / radius;
  const Eigen::Matrix3d rot =
      (Eigen::AngleAxisd(e.EA0C_urad * 1e-6, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(e.EB0C_urad * 1e-6, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(-e.EC0C_urad * 1e-6, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  return pivot + Eigen::Vector3d(e.EX0C_um, e.EY0C_um, e.EZ0T_um) * 1e-3 + rot * r;
}

}  // namespace probeloop::geometry
