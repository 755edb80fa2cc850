// Probe-tip radius compensation: from the element through the stylus-tip centres to the
// element of the material surface.
//
// Contract:
// - The points a probe reports are tip centres; they lie on a surface offset from the
//   material by the tip radius r, on the side the probe came from. For every element that
//   has a surface the compensated element is the offset of the fitted one by r toward the
//   material: a ball or shaft (material inside) shrinks by r, a bore grows by r, a plane
//   moves by r along its normal into the material, a cone's radius changes by r / cos(a)
//   (the offset is normal to the surface). Offsetting the element is exact for LS, MZ, MI
//   and MC fits of offset surfaces; residuals and form are unchanged.
// - The material side comes from the probe approach directions (direction of travel
//   toward the surface, which points into the material) or from the nominal. Mixed sides
//   are an error: a surface is probed from one side.
// - line3d has no surface side: compensation is refused with an explanation.
#pragma once
#include <optional>

#include "geometry/elements.hpp"

namespace probeloop::geometry {

// Where the material lies relative to the element's signed distance: Inside = on the
// negative side (ball, shaft, boss; for a plane: behind its normal), Outside = positive
// side (bore, hole; for a plane: in front of its normal).
enum class MaterialSide { Inside, Outside };

// The side the approach directions point to. Every approach must agree (|cos| > 0.1 to the
// outward normal at its point); otherwise GeometryError names the first disagreeing point.
MaterialSide materialSideFromApproach(const Element& element, const Points3& points,
                                      const Points3& approach_directions);

// The side a single nominal approach direction points to (planes and 2D lines, where the
// side is the same at every point).
MaterialSide materialSideFromApproach(const Element& element, const Eigen::Vector3d& approach);

// The element of the material surface. tip_radius_mm >= 0.
Element compensateTipRadius(const Element& tip_centre_element, double tip_radius_mm,
                            MaterialSide side);

}  // namespace probeloop::geometry
