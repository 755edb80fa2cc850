#include "geometry/tip_compensation.hpp"

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace probeloop::geometry {

MaterialSide materialSideFromApproach(const Element& e, const Points3& points,
                                      const Points3& approach) {
  if (points.size() != approach.size())
    throw GeometryError("tip compensation needs one approach direction per point; got " +
                        std::to_string(approach.size()) + " for " + std::to_string(points.size()));
  if (points.empty()) throw GeometryError("tip compensation needs at least one point");
  std::optional<MaterialSide> side;
  size_t first = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double len = approach[i].norm();
    if (!(len > 0.0) || !std::isfinite(len))
      throw GeometryError("point " + std::to_string(i + 1) +
                          ": approach direction is zero or not finite");
    // Travel toward the surface points into the material: against the outward normal means
    // the material is on the negative side.
    const double c = approach[i].dot(outwardNormal(e, points[i])) / len;
    if (std::abs(c) < 0.1)
      throw GeometryError("point " + std::to_string(i + 1) +
                          ": approach direction runs along the surface (cos = " +
                          std::to_string(c) + "), so the material side is undefined; "
                          "probe along the surface normal or give the side");
    const MaterialSide s = c < 0.0 ? MaterialSide::Inside : MaterialSide::Outside;
    if (!side) {
      side = s;
      first = i;
    } else if (*side != s) {
      throw GeometryError("points " + std::to_string(first + 1) + " and " +
                          std::to_string(i + 1) +
                          " were probed from opposite sides of the " +
                          std::string(elementName(e.kind)) +
                          ": a surface is probed from one side; split the points into features");
    }
  }
  return *side;
}

MaterialSide materialSideFromApproach(const Element& e, const Eigen::Vector3d& approach) {
  return materialSideFromApproach(e, Points3{e.position_mm}, Points3{approach});
}

Element compensateTipRadius(const Element& e, double r, MaterialSide side) {
  if (!(r >= 0.0) || !std::isfinite(r))
    throw GeometryError("tip radius must be a finite number >= 0 mm");
  Element out = e;
  // The material surface lies r away from the tip-centre surface, on the material side.
  const double toward_material = side == MaterialSide::Inside ? -r : r;
  switch (e.kind) {
    case ElementKind::Line3D:
      throw GeometryError(
          "tip compensation is not defined for line3d: a line in space has no surface side; "
          "fit line2d in the probing plane or compensate the points");
    case ElementKind::Plane:
      out.position_mm += toward_material * e.direction;
      break;
    case ElementKind::Line2D:
      out.position_mm += toward_material * Eigen::Vector3d(-e.direction.y(), e.direction.x(), 0.0);
      break;
    case ElementKind::Circle2D:
    case ElementKind::Circle3D:
    case ElementKind::Sphere:
    case ElementKind::Cylinder:
      out.radius_mm += toward_material;
      if (!(out.radius_mm > 0.0))
        throw GeometryError("tip radius " + std::to_string(r) + " mm is not smaller than the " +
                            "fitted radius " + std::to_string(e.radius_mm) +
                            " mm of the tip-centre element: check the material side");
      break;
    case ElementKind::Cone:
      // An offset of the surface by t along its normal moves the generator radially by
      // t / cos(a) (a = half apex angle); the apex angle is unchanged.
      out.radius_mm += toward_material / std::cos(e.half_angle_rad);
      break;
  }
  return out;
}

}  // namespace probeloop::geometry
