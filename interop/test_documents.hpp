// A plan both format tests write and read (test support, not part of the library): a ball, a
// plane and a bore in one part frame, each with its points and their outward normals.
#pragma once
#include <gtest/gtest.h>

#include <cmath>

#include "interop/cmm_document.hpp"

namespace probeloop::interop::testing {

// SPH1: a 25 mm ball at (150, 50, 12.5), 5 points on its upper half (the top one at z 25);
// X1_3: the plane z = 10 with 4 points; BORE1: a 20 mm bore on the axis (100, 50, z), 6 points
// at z -5 and -15 (its outward normals point to the axis).
inline CmmDocument ballPlaneBore() {
  CmmDocument d;
  d.part_name = "test";
  CmmFeature s;
  s.name = "SPH1";
  s.kind = CmmFeatureKind::Sphere;
  s.nominal = {true, {150, 50, 12.5}, {0, 0, 0}, 25, NAN};
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 1).normalized(), Eigen::Vector3d(0, 1, 1).normalized(),
                                   Eigen::Vector3d(-1, 0, 1).normalized(), Eigen::Vector3d(0, -1, 1).normalized()})
    s.points.push_back({s.nominal.location_mm + 12.5 * n, n});
  d.features.push_back(s);
  CmmFeature p;
  p.name = "X1_3";
  p.kind = CmmFeatureKind::Plane;
  p.nominal = {true, {50, 25, 10}, {0, 0, 1}, NAN, NAN};
  for (double x : {40.0, 60.0})
    for (double y : {15.0, 35.0}) p.points.push_back({{x, y, 10}, {0, 0, 1}});
  d.features.push_back(p);
  CmmFeature c;
  c.name = "BORE1";
  c.kind = CmmFeatureKind::Cylinder;
  c.internal = true;
  c.nominal = {true, {100, 50, -10}, {0, 0, 1}, 20, NAN};
  for (int k = 0; k < 6; ++k) {
    const double a = k * M_PI / 3;
    const Eigen::Vector3d r(std::cos(a), std::sin(a), 0);
    c.points.push_back({Eigen::Vector3d(100, 50, k % 2 ? -5 : -15) + 10 * r, -r});
  }
  d.features.push_back(c);
  return d;
}

// A plan read back against the one written: names, kinds, bores, nominal locations and
// diameters, every point (lengths are written to 1 nm) and its normal (within normal_tol).
inline void expectSamePlan(const CmmDocument& written, const CmmDocument& read, double normal_tol) {
  ASSERT_EQ(read.features.size(), written.features.size());
  for (std::size_t i = 0; i < written.features.size(); ++i) {
    const auto& x = written.features[i];
    const auto& y = read.features[i];
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.kind, x.kind);
    EXPECT_EQ(y.internal, x.internal);
    EXPECT_LT((y.nominal.location_mm - x.nominal.location_mm).norm(), 1e-6);
    if (x.kind != CmmFeatureKind::Plane) {
      EXPECT_NEAR(y.nominal.diameter_mm, x.nominal.diameter_mm, 1e-9);
    }
    ASSERT_EQ(y.points.size(), x.points.size());
    for (std::size_t k = 0; k < x.points.size(); ++k) {
      EXPECT_LT((y.points[k].p_mm - x.points[k].p_mm).norm(), 1e-6);
      EXPECT_LT((y.points[k].normal - x.points[k].normal).norm(), normal_tol);
    }
  }
}

}  // namespace probeloop::interop::testing
