// Feature actuals (evaluate/feature_actuals.hpp) matched to a plan's nominal features, for the
// pieces measured once as a whole (thermal test piece, stepped workpiece): by id when a row's id
// is a manifest feature id, otherwise by nominal geometry, as CMM software assigns (the file must
// then be in the part frame, as for points: evaluate/ttp_ingest.hpp assignByNominalGeometry).
//
// Geometry rules (docs/formats.md#feature-actuals-csv), for a row of a foreign id:
// - plane row -> plane feature: normals within 1 deg (either sense: a fitted plane's normal
//   has no material side unless the software adds one), the row's location within 0.5 mm of the
//   nominal plane and inside its extent + 1 mm (CMM software reports a plane at the centroid of
//   its points, which lies on the face);
// - circle or cylinder row -> cylinder feature: axes within 1 deg (either sense), the location
//   within 0.5 mm of the nominal axis, the diameter (when given) within 1 mm of the nominal;
// - sphere row -> sphere feature: centre within 0.5 mm, diameter (when given) within 1 mm.
// Candidates rank by their distance from the nominal surface within its extent (so of two
// coplanar strips the one the location lies on wins); two whose distances differ by less than
// 0.05 mm are ambiguous: InputError naming
// the row's line and both features. A row that fits no feature is listed in `unmatched` with the
// nearest feature and its distance (a CMM file often holds more than the plan: an alignment
// feature, a reference sphere); when no row fits, InputError: the file is probably in another
// frame. Rows of kind point or line, or without measured geometry, are counted, not used.
//
// Contract: InputError with the file and line for a row whose id names a feature of another
// kind (a plane row named CYL) or whose geometry breaks the rules above against the feature it
// names (mislabelled, or not in the part frame: the features routes place the plan's points on
// it), for one feature given twice (both lines), and for rows of more than one measurement run
// (the piece is measured once: give one run).
#pragma once
#include <string>
#include <vector>

#include "evaluate/feature_actuals.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

struct MatchedFeature {
  FeatureActual actual;
  const parts::ManifestFeature* feature = nullptr;  // into the manifest
  bool by_id = false;                               // false: by nominal geometry
};

struct UnmatchedFeature {
  FeatureActual actual;
  std::string nearest;  // the nearest feature of the same kind ("" when the plan has none)
  double distance_mm = 0;  // from its nominal surface within its extent (plane), axis (cylinder), centre (sphere)
  std::string why;         // the rules it fails against the nearest ("normal off by 2.1 deg (at most 1)", ...)
};

struct FeatureMatch {
  std::vector<MatchedFeature> matched;  // in file order
  std::vector<UnmatchedFeature> unmatched;
  int other_kinds = 0;  // point or line rows
  std::string assigned_by;  // "labels", "nominal geometry" or "labels and nominal geometry"
  const MatchedFeature* find(const std::string& manifest_id) const;  // nullptr if absent
};

FeatureMatch matchFeatureActuals(const std::vector<FeatureActual>& rows, const parts::PlanManifest& m);

}  // namespace probeloop::evaluate
