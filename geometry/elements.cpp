#include "geometry/elements.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.hpp"

namespace probeloop::geometry {
namespace {

struct KindInfo {
  ElementKind kind;
  std::string_view name;
  int minimum_points;
};
constexpr std::array<KindInfo, 8> kKinds{{{ElementKind::Line2D, "line2d", 2},
                                          {ElementKind::Line3D, "line3d", 2},
                                          {ElementKind::Plane, "plane", 3},
                                          {ElementKind::Circle2D, "circle2d", 3},
                                          {ElementKind::Circle3D, "circle3d", 3},
                                          {ElementKind::Sphere, "sphere", 4},
                                          {ElementKind::Cylinder, "cylinder", 5},
                                          {ElementKind::Cone, "cone", 6}}};

constexpr std::array<std::pair<FitMethod, std::string_view>, 4> kMethods{
    {{FitMethod::LeastSquares, "ls"},
     {FitMethod::MinimumZone, "mz"},
     {FitMethod::MaximumInscribed, "mi"},
     {FitMethod::MinimumCircumscribed, "mc"}}};

// Component of v perpendicular to the unit vector d.
Eigen::Vector3d perpendicular(const Eigen::Vector3d& v, const Eigen::Vector3d& d) {
  return v - d * d.dot(v);
}

Eigen::Vector3d unitOr(const Eigen::Vector3d& v, const Eigen::Vector3d& fallback) {
  const double n = v.norm();
  return n > 0.0 ? Eigen::Vector3d(v / n) : fallback;
}

// Any unit vector perpendicular to the unit vector d.
Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& d) {
  const Eigen::Vector3d a =
      std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return perpendicular(a, d).normalized();
}

}  // namespace

std::string_view elementName(ElementKind kind) {
  for (const auto& k : kKinds)
    if (k.kind == kind) return k.name;
  return "unknown";
}

std::optional<ElementKind> parseElementKind(std::string_view name) {
  for (const auto& k : kKinds)
    if (k.name == name) return k.kind;
  return std::nullopt;
}

int minimumPoints(ElementKind kind) {
  for (const auto& k : kKinds)
    if (k.kind == kind) return k.minimum_points;
  return 0;
}

std::string_view methodName(FitMethod method) {
  for (const auto& m : kMethods)
    if (m.first == method) return m.second;
  return "unknown";
}

std::optional<FitMethod> parseFitMethod(std::string_view name) {
  for (const auto& m : kMethods)
    if (m.second == name) return m.first;
  return std::nullopt;
}

double signedDistance(const Element& e, const Eigen::Vector3d& p) {
  const Eigen::Vector3d v = p - e.position_mm;
  switch (e.kind) {
    case ElementKind::Line2D: {
      const Eigen::Vector2d d = e.direction.head<2>();
      const Eigen::Vector2d w = v.head<2>();
      return d.x() * w.y() - d.y() * w.x();  // left of the direction is positive
    }
    case ElementKind::Line3D:
      return perpendicular(v, e.direction).norm();
    case ElementKind::Plane:
      return e.direction.dot(v);
    case ElementKind::Circle2D:
      return v.head<2>().norm() - e.radius_mm;
    case ElementKind::Circle3D:
      return perpendicular(v, e.direction).norm() - e.radius_mm;
    case ElementKind::Sphere:
      return v.norm() - e.radius_mm;
    case ElementKind::Cylinder:
      return perpendicular(v, e.direction).norm() - e.radius_mm;
    case ElementKind::Cone: {
      // In the half-plane through the axis: the generator line passes (0, r0) with slope
      // tan(a) toward +direction; the distance from (s, rho) is (rho - r0 - s tan a) cos a.
      const double s = e.direction.dot(v);
      const double rho = perpendicular(v, e.direction).norm();
      const double a = e.half_angle_rad;
      return (rho - e.radius_mm) * std::cos(a) - s * std::sin(a);
    }
  }
  return 0.0;
}

Eigen::Vector3d outwardNormal(const Element& e, const Eigen::Vector3d& p) {
  const Eigen::Vector3d v = p - e.position_mm;
  switch (e.kind) {
    case ElementKind::Line2D:
      return Eigen::Vector3d(-e.direction.y(), e.direction.x(), 0.0).normalized();
    case ElementKind::Line3D:
      return unitOr(perpendicular(v, e.direction), anyPerpendicular(e.direction));
    case ElementKind::Plane:
      return e.direction;
    case ElementKind::Circle2D:
      return unitOr(Eigen::Vector3d(v.x(), v.y(), 0.0), Eigen::Vector3d::UnitX());
    case ElementKind::Circle3D:
      return unitOr(perpendicular(v, e.direction), anyPerpendicular(e.direction));
    case ElementKind::Sphere:
      return unitOr(v, Eigen::Vector3d::UnitZ());
    case ElementKind::Cylinder:
      return unitOr(perpendicular(v, e.direction), anyPerpendicular(e.direction));
    case ElementKind::Cone: {
      const Eigen::Vector3d radial = unitOr(perpendicular(v, e.direction), anyPerpendicular(e.direction));
      const double a = e.half_angle_rad;
      return (radial * std::cos(a) - e.direction * std::sin(a)).normalized();
    }
  }
  return Eigen::Vector3d::UnitZ();
}

void fillResiduals(FitResult& r, const Points3& points, int free_parameters) {
  const size_t n = points.size();
  r.residuals_mm.resize(n);
  double ssr = 0.0;
  double lo = 0.0;
  double hi = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double d = signedDistance(r.element, points[i]);
    r.residuals_mm[i] = d;
    ssr += d * d;
    if (i == 0 || d < lo) lo = d;
    if (i == 0 || d > hi) hi = d;
  }
  r.ssr_mm2 = ssr;
  r.rms_mm = n > 0 ? std::sqrt(ssr / static_cast<double>(n)) : 0.0;
  r.form_mm = r.element.kind == ElementKind::Line3D ? 2.0 * hi : hi - lo;
  r.dof = static_cast<int>(n) - free_parameters;
  r.residual_variance_mm2 = r.dof > 0 ? ssr / r.dof : 0.0;
}

}  // namespace probeloop::geometry
