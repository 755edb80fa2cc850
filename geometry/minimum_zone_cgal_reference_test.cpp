// CGAL's exact references for the minimum-zone tests (minimum_zone_test.cpp): the width of a
// point set (Width_3, homogeneous integers) and the centre of the annulus that minimises
// R^2 - r^2 (Min_annulus_d). Not compiled in the sanitizer build (geometry/CMakeLists.txt):
// instrumenting CGAL cost more than any unit of ours there and checks none of our code.
#include <CGAL/Cartesian.h>
#include <CGAL/Gmpz.h>
#include <CGAL/Gmpzf.h>
#include <CGAL/Homogeneous.h>
#include <CGAL/Min_annulus_d.h>
#include <CGAL/Min_sphere_annulus_d_traits_2.h>
#include <CGAL/Width_3.h>
#include <CGAL/Width_default_traits_3.h>

#include <cmath>
#include <vector>

#include "geometry/minimum_zone.hpp"

namespace probeloop::geometry::cgal_reference {

using Eigen::Vector2d;
using Eigen::Vector3d;

// Points in the centroid frame rounded to a 2^-40 mm (~1e-12 mm) grid.
double width(const Points3& p) {
  using K = CGAL::Homogeneous<CGAL::Gmpz>;
  Vector3d m = Vector3d::Zero();
  for (const auto& v : p) m += v;
  m /= static_cast<double>(p.size());
  const double scale = std::ldexp(1.0, 40);
  std::vector<K::Point_3> pts;
  for (const auto& v : p) {
    const Vector3d s = (v - m) * scale;
    pts.emplace_back(CGAL::Gmpz(std::round(s.x())), CGAL::Gmpz(std::round(s.y())),
                     CGAL::Gmpz(std::round(s.z())), CGAL::Gmpz(1));
  }
  CGAL::Width_3<CGAL::Width_default_traits_3<K>> w(pts.begin(), pts.end());
  K::RT num, den;
  w.get_squared_width(num, den);
  return std::sqrt(CGAL::to_double(num) / CGAL::to_double(den)) / scale;
}

Vector2d annulusCentre(const Points3& p) {
  using K = CGAL::Cartesian<double>;
  using T = CGAL::Min_sphere_annulus_d_traits_2<K, CGAL::Gmpzf, double>;
  const Vector2d m = p[0].head<2>();
  std::vector<K::Point_2> pts;
  for (const auto& v : p) pts.emplace_back(v.x() - m.x(), v.y() - m.y());
  CGAL::Min_annulus_d<T> a(pts.begin(), pts.end());
  std::vector<double> h;
  for (auto it = a.center_coordinates_begin(); it != a.center_coordinates_end(); ++it)
    h.push_back(CGAL::to_double(*it));
  return Vector2d(h[0] / h[2], h[1] / h[2]);
}

}  // namespace probeloop::geometry::cgal_reference
