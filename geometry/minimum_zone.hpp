// Chebyshev (minimum-zone) form fits and the inscribed / circumscribed elements.
//
// Contract:
// - fitMinimumZone: line2d (straightness), line3d (straightness in space: smallest
//   cylinder), plane (flatness), circle2d (roundness), sphere (sphericity), cylinder
//   (cylindricity). The reported element is the zone's mid element (for circle/sphere/
//   cylinder the mean of the inner and outer radius); form_mm is the zone width
//   (max - min residual; for line3d the cylinder diameter); support_points are the points
//   on the zone boundaries.
// - fitMaximumInscribed / fitMinimumCircumscribed: circle2d, sphere, cylinder. The element
//   touches support_points; every point lies outside (MI) or inside (MC) within 1e-9 mm.
// - Exact CGAL algorithms where they fit (Min_circle_2, Min_sphere_d, Min_annulus_d,
//   Width_3 with exact number types); elsewhere sequential linearised Chebyshev from the
//   least-squares start, checked by the alternation property (k parameters: at least k+1
//   points on the zone boundaries).
// - Same degeneracy errors as least squares (GeometryError with what to fix); a kind the
//   method does not define throws GeometryError naming the kinds it supports.
#pragma once
#include "geometry/elements.hpp"

namespace probeloop::geometry {

FitResult fitMinimumZone(ElementKind kind, const Points3& points);
FitResult fitMaximumInscribed(ElementKind kind, const Points3& points);
FitResult fitMinimumCircumscribed(ElementKind kind, const Points3& points);

}  // namespace probeloop::geometry
