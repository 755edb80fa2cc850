#include "interop/measured_geometry.hpp"

#include "core/error.hpp"
#include "geometry/least_squares.hpp"

namespace probeloop::interop {

bool fitMeasuredGeometry(CmmFeature& f) {
  geometry::ElementKind kind;
  switch (f.kind) {
    case CmmFeatureKind::Plane: kind = geometry::ElementKind::Plane; break;
    case CmmFeatureKind::Sphere: kind = geometry::ElementKind::Sphere; break;
    case CmmFeatureKind::Cylinder: kind = geometry::ElementKind::Cylinder; break;
    default: return false;
  }
  geometry::Points3 pts;
  for (const auto& p : f.points) pts.push_back(p.p_mm);
  try {
    geometry::LeastSquaresOptions o;
    if (f.kind != CmmFeatureKind::Plane && f.nominal.given && std::isfinite(f.nominal.diameter_mm)) {
      geometry::Element e;
      e.kind = kind;
      e.position_mm = f.nominal.location_mm;
      e.direction = f.nominal.direction.norm() > 0 ? f.nominal.direction : Eigen::Vector3d::UnitZ();
      e.radius_mm = f.nominal.diameter_mm / 2;
      o.start = e;
    }
    geometry::FitResult fit;
    try {
      fit = geometry::fitLeastSquares(kind, pts, o);
    } catch (const GeometryError&) {
      if (kind != geometry::ElementKind::Cylinder) throw;
      fit = geometry::fitLeastSquares(geometry::ElementKind::Circle3D, pts);
    }
    auto& g = f.measured;
    g.given = true;
    g.location_mm = fit.element.position_mm;
    g.direction = fit.element.direction;
    if (f.nominal.direction.norm() > 0 && g.direction.dot(f.nominal.direction) < 0) g.direction = -g.direction;
    g.diameter_mm = kind == geometry::ElementKind::Plane ? NAN : 2 * fit.element.radius_mm;
    g.form_mm = fit.form_mm;
    g.algorithm = "LEASTSQUARES";
    return true;
  } catch (const GeometryError&) {
    return false;
  }
}

}  // namespace probeloop::interop
