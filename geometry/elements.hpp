// Geometric elements of the fitting suite and the result every fit returns.
//
// Contract (shared by least squares, minimum zone, inscribed/circumscribed fits, tip
// compensation, outlier elimination and `probeloop fit`):
// - Units: mm and radians. Points are 3D; the 2D elements (line2d, circle2d) use x and y
//   and ignore z.
// - One representation for every element, ISO 10360-6 style: a location, a direction, a
//   size. For axes (line, cylinder, cone) `position_mm` is the point of the axis nearest the
//   centroid of the fitted points, so two fits of the same data are comparable.
//     line2d    position = point on the line, direction = unit direction (z = 0)
//     line3d    position = point on the line, direction = unit direction
//     plane     position = foot of the centroid on the plane, direction = unit normal
//     circle2d  position = centre (z = 0), radius_mm
//     circle3d  position = centre, direction = unit normal of the circle's plane, radius_mm
//     sphere    position = centre, radius_mm
//     cylinder  position = point on the axis, direction = unit axis, radius_mm
//     cone      position = point on the axis, direction = unit axis pointing toward
//               increasing radius, radius_mm = radius at position_mm (perpendicular to the
//               axis), half_angle_rad = half the apex angle (0 < a < pi/2)
//   Directions are unit vectors with a canonical sign (largest-magnitude component
//   positive) except for the cone, whose direction is physical.
// - Residuals are signed orthogonal distances (`signedDistance`): positive outside the
//   circle, sphere, cylinder or cone (away from the centre or axis), positive on the side
//   the plane normal points to, positive to the left of a line2d (direction rotated +90 deg
//   about z). line3d residuals are unsigned distances from the line. circle3d residuals are
//   the radial deviation of the point's projection on the circle's plane (the out-of-plane
//   part is the plane's business).
// - form_mm: peak to valley of the residuals (max - min); for line3d, twice the largest
//   distance (diameter of the coaxial cylinder containing the points, ISO 12780).
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace probeloop::geometry {

using Points3 = std::vector<Eigen::Vector3d>;

enum class ElementKind { Line2D, Line3D, Plane, Circle2D, Circle3D, Sphere, Cylinder, Cone };

// "line2d", "line3d", "plane", "circle2d", "circle3d", "sphere", "cylinder", "cone".
std::string_view elementName(ElementKind kind);
std::optional<ElementKind> parseElementKind(std::string_view name);
// Minimum number of points a fit of this kind needs (2, 2, 3, 3, 3, 4, 5, 6).
int minimumPoints(ElementKind kind);

struct Element {
  ElementKind kind = ElementKind::Plane;
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  double radius_mm = 0.0;       // circle, sphere, cylinder; cone: radius at position_mm
  double half_angle_rad = 0.0;  // cone only
};

// Signed orthogonal distance of p from the element, sign as in the contract above.
double signedDistance(const Element& element, const Eigen::Vector3d& p);
// Unit outward surface normal at the foot of p (direction of increasing signedDistance);
// used for probe-tip compensation and reporting.
Eigen::Vector3d outwardNormal(const Element& element, const Eigen::Vector3d& p);

enum class FitMethod {
  LeastSquares,          // Gaussian: minimise the sum of squared orthogonal distances
  MinimumZone,           // Chebyshev: minimise the largest |deviation| (form zone width)
  MaximumInscribed,      // largest circle/sphere/cylinder with every point outside it
  MinimumCircumscribed,  // smallest circle/sphere/cylinder with every point inside it
};
std::string_view methodName(FitMethod method);  // "ls", "mz", "mi", "mc"
std::optional<FitMethod> parseFitMethod(std::string_view name);

struct FitResult {
  Element element;
  FitMethod method = FitMethod::LeastSquares;
  std::vector<double> residuals_mm;  // signedDistance of every input point, input order
  double ssr_mm2 = 0.0;              // sum of squared residuals
  double rms_mm = 0.0;               // sqrt(ssr / n)
  double form_mm = 0.0;              // see contract; for MZ fits this is the zone width
  int dof = 0;                       // n - number of free parameters
  double residual_variance_mm2 = 0.0;  // ssr / dof (0 when dof == 0)
  // Least squares only: (J^T J)^-1 propagated to the reported parameters, in the order of
  // parameter_names, e.g. {"x_mm","y_mm","z_mm","nx","ny","nz","r_mm"}. Multiply by a point
  // variance (type B) or by residual_variance_mm2 (type A) for the parameter covariance.
  // May be singular (directions are unit vectors; an axis point slides along the axis).
  std::vector<std::string> parameter_names;
  Eigen::MatrixXd covariance_unscaled;
  int iterations = 0;
  // Minimum-zone / inscribed / circumscribed fits: indices of the points that define the
  // solution (on the zone boundaries or touching the element), for the alternation check.
  std::vector<int> support_points;
};

// Residuals, ssr, rms, form, dof and residual variance of `element` on `points`, with
// `free_parameters` parameters estimated. Shared by every fitting method.
void fillResiduals(FitResult& result, const Points3& points, int free_parameters);

}  // namespace probeloop::geometry
