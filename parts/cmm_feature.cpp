#include "parts/cmm_feature.hpp"

#include <stdexcept>

namespace probeloop::parts {

interop::CmmFeature cmmFeatureOf(const NominalFeature& n) {
  interop::CmmFeature f;
  f.name = n.id;
  f.nominal.given = true;
  f.nominal.location_mm = n.point_mm;
  f.nominal.direction = n.direction;
  if (n.kind == "plane") {
    f.kind = interop::CmmFeatureKind::Plane;
  } else if (n.kind == "cylinder") {
    f.kind = interop::CmmFeatureKind::Cylinder;
    f.nominal.diameter_mm = 2 * n.radius_mm;
  } else if (n.kind == "sphere") {
    f.kind = interop::CmmFeatureKind::Sphere;
    f.nominal.diameter_mm = 2 * n.radius_mm;
  } else {
    throw std::logic_error("CMM document: feature " + n.id + " of kind " + n.kind);
  }
  return f;
}

void setInternalFromPoints(interop::CmmFeature& f) {
  if (f.kind != interop::CmmFeatureKind::Cylinder || f.points.empty() || f.points.front().normal.norm() == 0) return;
  const auto& p = f.points.front();
  const Eigen::Vector3d a = p.p_mm - f.nominal.location_mm;
  const Eigen::Vector3d radial = a - a.dot(f.nominal.direction) * f.nominal.direction;
  f.internal = radial.dot(p.normal) < 0;
}

}  // namespace probeloop::parts
