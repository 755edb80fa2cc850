// Reference data generator for least-squares fitting software, the NIST method
// (ISO 10360-6 Annex, ASME B89.4.10): points are built so that the least-squares solution is
// known by construction. Start from a reference element, take foot points on it, and add
// deviations along the surface normals that are orthogonal to the columns of the Jacobian
// at the reference element (J^T e = 0). The reference element is then a stationary point of
// the sum of squares, and with small deviations the minimum.
//
// Contract: deterministic for a seed; covers every ElementKind and the hard cases (far
// from the origin, short arcs, small caps, 4-point spheres, partial cylinders and cones).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/elements.hpp"

namespace probeloop::geometry {

struct ReferenceDataSet {
  std::string name;           // e.g. "sphere_cap_10deg_far"
  Element reference;          // the least-squares solution by construction
  Points3 points;
  double reference_ssr_mm2;   // sum of squared orthogonal residuals at `reference`
  bool well_conditioned;      // false for the hard cases (targets 0.1 um / 0.1 urad)
};

// The project's reference suite: for each kind, well-conditioned and hard sets.
std::vector<ReferenceDataSet> referenceSuite(std::uint64_t seed = 20261122);

// One data set: n foot points spread over `span` of the element (arc angle for circles,
// cap half angle for spheres, angle of the sector for cylinders and cones; length along
// lines, axes and planes is given by `extent_mm`), deviations of RMS `noise_mm`.
ReferenceDataSet makeReferenceData(const Element& reference, int n, double span_rad,
                                   double extent_mm, double noise_mm, std::uint64_t seed);

}  // namespace probeloop::geometry
