// glTF 2.0 scene of a thermal test piece (seed 004 Ch. 7) with its measured deviations.
//
// Contract: returns the text of a self-contained .gltf (JSON, buffers embedded as base64),
// deterministic for the same inputs, that the Khronos glTF validator accepts with no error
// and no warning. Everything is in the part frame (docs/thermal-test-piece.md §1: origin on
// the C axis in the finished top face, +Z up), in metres; the root node turns it so that
// glTF viewers (+Y up) show +Z up. Content:
// - "datum TOP (finished top outline, Ø… mm)": the finished top's outline, a circle of the
//   TOP datum's half extent (the radius of the band that reaches the top: Ø199 mm on the
//   shipped piece, not the blank's Ø203) at its height; "datum FLANK_P", "datum FLANK_N":
//   the notch flanks as grey quads; "datum CYL (band Ø… mm)": the datum band as a grey
//   cylinder surface;
// - one quad per measured facet and Z path (a feature of the evaluation's "features" with a
//   manifest feature of the same id and role facet or z_path), at its nominal place: point
//   ± half_u·u ± half_v·v with v = direction × u; coloured by its change against its
//   reference (the same group's feature cut in the reference cycle): facets Δd = d − d_ref,
//   Z paths Δdepth = depth − depth_ref, in µm, on a diverging scale symmetric about 0 (blue
//   − … light grey 0 … red +) whose limit is the largest |change| rounded up to 1, 2 or 5 ×
//   10^k µm; a feature whose change is unknown (no value, no reference) is dark grey.
//   Names: "facet X1_3 (cycle 2): -4.1 um", "Z path Z7 (cycle 2): depth +3.2 um",
//   "facet X1_5 (reference, cycle 0)"; extras: feature, cycle, reference, change_um;
// - per quad with a non-zero change, a deviation vector: a line from the quad's centre to
//   centre + exaggeration × (surface displacement): facets +Δd along the outward normal,
//   Z paths −Δdepth along +Z (a deeper path is a lower floor). Named "deviation X1_3 (x1000)";
// - "colour scale: blue -L um ... grey 0 ... red +L um (change against the reference)": the
//   scale as a bar of 11 quads from -L (at -Y) to +L (at +Y) beside the piece on its +X side,
//   in the top face's plane; the scale (limit, colours, meaning), the exaggeration and the
//   reference cycle are also in the scene's and the asset's extras.
// Errors: a manifest of another kind, an evaluation of another kind, a feature of the
// evaluation that the manifest does not have (files that do not belong together) and a
// non-finite exaggeration are InputError.
#pragma once
#include <array>
#include <nlohmann/json.hpp>
#include <string>

#include "parts/plan_manifest.hpp"

namespace probeloop::report {

// The diverging scale used by the scene: change_um / limit_um clamped to [-1, 1], linear
// from the zero colour to the negative or positive end (linear RGB, alpha 1).
struct TtpColourScale {
  double limit_um = 1;
  static constexpr std::array<double, 3> kNegative{0.13, 0.30, 0.75};
  static constexpr std::array<double, 3> kZero{0.90, 0.90, 0.90};
  static constexpr std::array<double, 3> kPositive{0.80, 0.12, 0.10};
  std::array<double, 4> colour(double change_um) const;
};

// The limit for the largest |change|: the next 1, 2 or 5 × 10^k at or above it (1 when 0).
double ttpColourLimit(double max_abs_change_um);

std::string thermalTestPieceSceneGltf(const parts::PlanManifest& manifest, const nlohmann::json& evaluation,
                                      double exaggeration);

}  // namespace probeloop::report
