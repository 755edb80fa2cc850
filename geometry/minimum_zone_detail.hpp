// Internal to the minimum-zone fits (minimum_zone.hpp is the public contract): what
// minimum_zone.cpp shares with minimum_zone_cgal.cpp, so that CGAL's headers are compiled only
// where they are used (most of this library's compile time is CGAL's):
// - minimum_zone.cpp: the frame, the models, the SLP stage, the starts, the results and the
//   public entry points; no CGAL header;
// - minimum_zone_cgal.cpp: the linearised LP solved exactly (CGAL's QP solver, Gmpzf) and the
//   exact CGAL parts: the minimum annulus (Min_annulus_d), the smallest enclosing circle
//   (Min_circle_2) and sphere (Min_sphere_of_spheres_d), the largest inscribed circle
//   (Delaunay) and the convex hull with the minimum-width strip. One unit: split into one
//   unit per part, they took 1.6 times the compile time (each pays for CGAL's kernel again).
// Every function works in the centroid frame (Frame). Nothing outside geometry/ includes
// this header.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "geometry/minimum_zone.hpp"

namespace probeloop::geometry::mz {

using Eigen::Vector2d;
using Eigen::Vector3d;
using Eigen::VectorXd;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// A number for a message (precision significant digits).
std::string fmt(double v, int precision = 6);

// The input moved to its centroid, with the scale that sets every tolerance.
struct Frame {
  Vector3d origin = Vector3d::Zero();
  Points3 q;            // centred points (2D kinds: z = 0)
  double size = 1.0;    // S: largest |q_i|
  double tol = 0.0;     // SLP convergence tolerance on the objective, mm
  double support = 0.0; // support-point tolerance, mm
  double noise = 0.0;   // rounding level of a residual, mm
};

// What the linearised problem optimises: the zone width (hi - lo), the outer radius (hi) or
// the inner radius (lo, maximised).
enum class Goal { Zone, Outer, Inner };

// Indices of the k largest and/or k smallest residuals (all of them for small n).
void addExtremes(const VectorXd& r, Goal g, int k, std::vector<int>& out);
// Sorted, without repeats.
void dedupe(std::vector<int>& v);

// ------------------------------------------------------------------ the linearised LP
// (minimum_zone_cgal.cpp)

struct LpStep {
  VectorXd delta;
  double model = 0.0;          // objective of the linearised problem at delta
  std::vector<int> upper;      // binding at hi (zone, outer)
  std::vector<int> lower;      // binding at lo (zone, inner)
};

// Exact solution (on the double data) of the linearised problem over all points inside
// the box |delta_j| <= box, by constraint generation starting from `active`.
LpStep solveLinearised(const VectorXd& r, const RowMatrix& J, Goal goal, double box,
                       std::vector<int> active, double noise);

// ------------------------------------------------------------------ exact CGAL parts

// Min_annulus_d (exact, Gmpzf) centre of the centred points, on a growing subset (D = 2, 3;
// minimum_zone_cgal.cpp).
template <int D>
Eigen::Matrix<double, D, 1> annulusCentre(const Frame& f);

// Smallest enclosing circle (Min_circle_2, exact constructions) and sphere
// (Min_sphere_of_spheres_d, Gmpq with the square-root extension; minimum_zone_cgal.cpp).
Vector2d minCircleCentre(const Frame& f);
Vector3d minSphereCentre(const Frame& f);

// Largest empty circle surrounded by the points (Delaunay; minimum_zone_cgal.cpp);
// GeometryError when the points do not surround one.
Vector2d maxInscribedCircleCentre(const Frame& f);

// Unit direction of the hull edge of the minimum-width strip of the xy points (rotating
// calipers over the exact convex hull; minimum_zone_cgal.cpp).
Vector2d minWidthDirection(const Points3& q);

}  // namespace probeloop::geometry::mz
