// glTF 2.0 scene of a sphere-artifact campaign (for viewing in any glTF viewer).
//
// Contract: returns the text of a self-contained .gltf (JSON, buffers embedded as base64
// data URIs), deterministic for the same input, that the Khronos glTF validator accepts
// with zero errors. Content, all in metres (glTF's unit) from the manifest's mm:
// - the table: a disc at manifest.table_surface_z_mm around the C axis, radius
//   radius_from_axis_mm + 2 * sphere_radius_mm;
// - the C axis: a line along +Z through c_axis_centre_mm;
// - one sphere mesh per manifest sphere (position), at its nominal centre;
// - the probe points: the nominal contact points of manifest.points (points primitive);
// - per cycle and position, an error vector: a line from the nominal centre to
//   nominal + exaggeration * (centre of that cycle - centre of the reference cycle).
// Node names say what they are ("table", "C axis", "sphere S1", "probe points",
// "error vectors cycle 3 (x10000)").
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

#include "parts/plan_manifest.hpp"

namespace probeloop::report {

struct CycleCentres {
  int cycle = 0;
  // One entry per manifest.spheres, same order; nullopt where the position is missing.
  std::vector<std::optional<Eigen::Vector3d>> centre_mm;
};

std::string campaignSceneGltf(const parts::PlanManifest& manifest,
                              const std::vector<CycleCentres>& cycles, int reference_cycle,
                              double exaggeration);

}  // namespace probeloop::report
