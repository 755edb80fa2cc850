// Test support for the features routes' unit tests (issue 34): a feature-actuals row as a CMM
// states it, and a nominal plane of a hand-made plan.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "evaluate/feature_actuals.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate::feature_test {

// One measurement run (cycle 1); the direction normalised as the CSV reader does.
inline FeatureActual statedFeature(int line, const std::string& id, const std::string& kind, const Eigen::Vector3d& p,
                                   const Eigen::Vector3d& n, double size_mm = NAN, double form_um = NAN, int n_points = 0,
                                   const std::string& file = "f.csv") {
  FeatureActual f;
  f.file = file;
  f.line = line;
  f.cycle = 1;
  f.id = id;
  f.kind = kind;
  f.location_mm = p;
  f.direction = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : n;
  f.size_mm = size_mm;
  f.form_um = form_um;
  f.n_points = n_points;
  return f;
}

// A plane of the plan: centre p, outward normal n, u in the face, half extents along u and n x u.
inline parts::ManifestFeature nominalPlane(const std::string& id, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                                           const Eigen::Vector3d& u, double half_u_mm, double half_v_mm, const std::string& role = "") {
  parts::ManifestFeature f;
  f.nominal.id = id;
  f.nominal.kind = "plane";
  f.nominal.role = role;
  f.nominal.point_mm = p;
  f.nominal.direction = n;
  f.nominal.u = u;
  f.nominal.half_u_mm = half_u_mm;
  f.nominal.half_v_mm = half_v_mm;
  return f;
}

}  // namespace probeloop::evaluate::feature_test
