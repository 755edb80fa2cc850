// Least-squares fits of every element (contract in least_squares.hpp and elements.hpp).
// The families live in ls_lines_planes.cpp (closed form), ls_circle.cpp, ls_sphere.cpp and
// ls_axis.cpp (cylinder, cone); the shared checks and the Gauss-Newton / Levenberg-
// Marquardt engine in ls_detail.hpp and ls_checks.cpp.
#include "geometry/least_squares.hpp"

#include "geometry/ls_detail.hpp"

namespace probeloop::geometry {

FitResult fitLeastSquares(ElementKind kind, const Points3& points, const LeastSquaresOptions& options) {
  using namespace ls;
  checkOptions(kind, options);
  checkCount(kind, points);
  const Moments m = computeMoments(kind, points);
  const Axes ax = principalAxes(m);
  checkNotCoincident(kind, ax, points.size());
  if (points.size() <= options.duplicate_search_max_points) checkDuplicates(kind, points);
  switch (kind) {
    case ElementKind::Line2D: return fitLine2D(points, m, options);
    case ElementKind::Line3D: return fitLine3D(points, m, ax, options);
    case ElementKind::Plane: return fitPlane(points, m, ax, options);
    case ElementKind::Circle2D: return fitCircle2D(points, m, options);
    case ElementKind::Circle3D: return fitCircle3D(points, m, ax, options);
    case ElementKind::Sphere: return fitSphereLs(points, m, ax, options);
    case ElementKind::Cylinder: return fitCylinder(points, m, ax, options);
    case ElementKind::Cone: return fitCone(points, m, ax, options);
  }
  fail("least-squares fit of an unknown element kind");
}

}  // namespace probeloop::geometry
