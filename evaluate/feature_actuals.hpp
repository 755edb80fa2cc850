// Feature actuals: what a CMM package reports when it exports only the fitted features, not
// the points (docs/formats.md#feature-actuals-csv), and the sphere artifact's centres matched
// from them.
//
// CSV columns `cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points`, optional
// `u_x_um,u_y_um,u_z_um` (all three columns or none; per row all three fields or none: the
// stated standard uncertainty of the location), `time_s` (empty: not given) and `algorithm`
// (the fitting criterion, QIF's names: LEASTSQUARES, MINMAX, ...; empty: not stated); the separators and decimal marks of core/csv.hpp. kind is sphere, circle,
// cylinder, plane or point; x/y/z the centre (sphere, circle), a point on the axis (cylinder)
// or on the plane; i/j/k the axis or normal (empty or 0 for a sphere or point); size_mm the
// diameter (empty for a plane or point); form_um the form deviation (empty: not stated);
// n_points the number of points the CMM fitted: at least the element's fitted parameters
// (minimumPoints: plane 3, circle 3, sphere 4, cylinder 5, point 1), empty when not stated (0).
//
// Contract: InputError with file:line:field for a missing column, an unknown kind, a field that
// is not a number where one is needed, a count that is not a positive integer or is below the
// kind's minimumPoints (no fit of that kind has so few points), a negative
// size/form/u, a direction of zero length where one is needed, a coordinate or size beyond 1 km
// or a form or u beyond 1 m (not a measurement: it would overflow a budget). Nothing is guessed
// silently.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "evaluate/input_warnings.hpp"
#include "interop/cmm_document.hpp"
#include "parts/plan_manifest.hpp"

namespace probeloop::evaluate {

struct FeatureActual {
  std::string file;
  int line = 0;
  int cycle = 0;
  std::string id, kind;
  Eigen::Vector3d location_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // unit; zero for a sphere or point
  double size_mm = 0;                                   // diameter; NaN when not given
  double form_um = 0;                                   // NaN when not stated
  int n_points = 0;  // 0: not stated (QIF/DMIS features exported without their points)
  std::optional<Eigen::Vector3d> u_um;  // the CMM's stated standard uncertainty per coordinate
  std::optional<double> time_s;
  bool has_geometry = true;  // false: a QIF/DMIS feature with points but no measured geometry
  bool fitted_here = false;  // a sphere of points only: its centre fitted here (featureActualsFromCmm)
  double fitted_known_radius_mm = NAN;  // fitted_here with a known radius: that radius; NaN: free radius
  // How the CMM fitted it, as the file states it (QIF SubstituteFeatureAlgorithmEnum names,
  // e.g. LEASTSQUARES, MINMAX; the CSV's optional column `algorithm`); "" not stated.
  std::string algorithm;
};

// The fewest points that fix an element of the kind (its least-squares fit's parameters):
// plane 3, circle 3, sphere 4, cylinder 5; point (and any other) 1.
int minimumPoints(const std::string& kind);

// max_cycle > 0 refuses a cycle beyond it (the plan's cycles).
std::vector<FeatureActual> parseFeatureActuals(const std::string& text, const std::string& file, int max_cycle = 0);

// The measured features of a QIF 3.0 Results or DMIS output document (interop's readers) as
// feature actuals: the cycle is the document's measurement run (QIF: the MeasurementResults in
// order; DMIS output: 1), the id the feature's name, size and form as the file states them,
// n_points the points it carries (0: none exported). A sphere without measured geometry but with
// points (a QIF or DMIS export of points only; surface points) gets its centre here: the
// least-squares sphere of its points (form = the range of the residuals; fitted_here), of the
// known radius known_radius_mm when given (the point route's default: a free radius is shrunk by
// the probe's pre-travel and lifts the centre, docs/uncertainty.md; fitted_known_radius_mm says
// which), else of a free radius; with fewer than 4 points, or points that fix no sphere, it is
// refused with its line. Cycles beyond max_cycle (> 0) are refused.
std::vector<FeatureActual> featureActualsFromCmm(const interop::CmmDocument& d, int max_cycle = 0,
                                                 std::optional<double> known_radius_mm = std::nullopt);

// True when a CSV text's header holds the feature-actuals columns (for --format auto).
bool looksLikeFeatureActuals(const std::string& text);

// True when a QIF/DMIS document carries measured features but not one point: the feature route.
bool holdsOnlyFeatures(const interop::CmmDocument& d);

// The features a CMM file states when it holds no points, for the pieces measured once
// (thermal test piece, stepped workpiece): a feature-actuals CSV, or a QIF 3.0 Results / DMIS
// output whose features carry measured geometry and none of them points. nullopt: the file holds
// points (the point route reads it) or is neither. A QIF with several MeasurementResults is
// refused (the piece is measured once). warnings: the lenient reader's, "file:line: what"; strict
// refuses them instead.
struct StatedFeatureFile {
  std::string format;  // features | qif | dmis
  std::vector<FeatureActual> rows;
  std::vector<InputWarning> warnings;
};
std::optional<StatedFeatureFile> readStatedFeatures(const std::string& path, const std::string& text, bool strict);

// A sphere centre of the plan, from the file: the row, the position it was matched to and how.
struct StatedCentre {
  FeatureActual feature;
  int position = 0;
  bool by_id = false;  // id S<position>; false: by nearness to the nominal centre
};

struct SphereCentresFromFeatures {
  std::map<int, std::map<int, StatedCentre>> by_cycle;  // cycle -> position -> centre
  int other_kinds = 0;                                  // rows of other kinds, not used
};

// The sphere artifact's centres per cycle: a row whose id is a manifest id (S<k>) takes that
// position; any other sphere row takes the position whose nominal centre (at its planned C
// angle) lies within 5 mm of the row's centre. Positions at the same place (a repeat) are told
// apart by time_s (earlier row, earlier position); without it, or when a row is near two
// places, or a position is given twice in a cycle, InputError naming both rows. A diameter more
// than 1 mm from the planned sphere's is refused (another feature, not the artifact's sphere).
SphereCentresFromFeatures sphereCentresFromFeatures(const std::vector<FeatureActual>& rows, const parts::PlanManifest& m);

}  // namespace probeloop::evaluate
