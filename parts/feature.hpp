// A nominal feature of a test piece in its part frame: what the planner plans points on, the
// CMM measures, the evaluation assigns points to and fits, and the scene draws. Every id
// survives into every file (manifest, CMM plan and export, logs via the manifest, reports).
//
// Planes: point = centre of the face, direction = outward unit normal (away from the
// material), u = a unit direction in the face, half_u / half_v its half extents (v = n x u).
// Cylinders: point = on the axis at mid-height, direction = unit axis, radius, half_v = half
// the height. Spheres: point = centre, radius. Lengths in mm, angles in degrees.
#pragma once
#include <Eigen/Dense>
#include <string>

namespace probeloop::parts {

struct NominalFeature {
  std::string id;
  std::string kind;   // plane | cylinder | sphere
  std::string role;   // what it is for, by kind: datum_top, datum_flank, datum_circle, z_path, facet, sphere
  std::string group;  // a family of features evaluated together (X1, Z, datum, ...)
  int index = 0;      // number within its group (1-based); 0 for datums
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();
  double half_u_mm = 0, half_v_mm = 0, radius_mm = 0;
  double angle_deg = 0;  // facets: direction of the outward normal from +X

  Eigen::Vector3d v() const { return direction.cross(u); }
};

// Which features give which error, by which formula, from which source (a test piece's
// evaluation as data; written into the plan manifest and the evaluation report).
struct EvaluationRule {
  std::string output;    // EX_um, EX0C_um, ...
  std::string formula;   // in words and symbols
  std::string source;    // "seed 004 Eq. 7.1 (sign corrected, notes §11 item 10)"
  std::string features;  // which features it reads
};

}  // namespace probeloop::parts
