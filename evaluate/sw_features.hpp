// The stepped workpiece (seed 000) evaluated when the CMM file holds only the fitted planes, not
// the points (issue 34 item 3; docs/stepped-workpiece.md#evaluating-from-features). The probe log
// stays points (on-machine probing always gives points).
//
// Route: the file's rows (feature-actuals CSV, or a QIF 3.0 Results / DMIS output without
// points, evaluate/feature_actuals.hpp) are matched to the plan's planes by id or nominal
// geometry (evaluate/feature_match.hpp); the plan's CMM points (cmm_points.csv beside the
// manifest) of each plane are placed on the stated plane (evaluate/feature_points.hpp), and the
// point route's own fits and formulas run on them (steppedGeometry's swPlanes and
// swGeometryFromPlanes): an LS fit of the placed points is the stated plane, so every width,
// depth, tilt, slope and Oz is the file's planes evaluated as the point route evaluates its fits.
//
// Budget: where the point route uses a plane's residual s (SwPlane::rms_um, u_slope) this route
// uses a per-point sigma, the largest of what the file and the plan state: the CMM's
// MPE(L)/sqrt 3 (the manifest's), the stated form over d2(n) sqrt((n-3)/n) (sigmaFromForm), and a
// stated standard uncertainty of the location along the normal times sqrt(n); n the file's point
// count, else the plan's. The slopes' u come from the planned layout scaled by point_scale. What
// is lost against the point route (the fitting criterion taken as least squares, the real point
// layout and residuals, outliers, the line of each point) goes into the notes.
//
// Contract: InputError naming file:line for what the matching refuses (a row of another kind
// named by a plane's id, a plane given twice, several runs, nothing matching: another frame);
// InputError naming the file and the feature for a plane the plan needs that is not in the file
// (the point route refuses a plane without points alike); a row that fits no plane is listed in
// from_features.unmatched (and on stdout, in evaluation.json and report.md), never dropped
// silently. The CMM plan must be readable beside the manifest: InputError naming it otherwise.
#pragma once
#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "evaluate/feature_actuals.hpp"
#include "evaluate/stepped_workpiece.hpp"

namespace probeloop::evaluate {

using PlannedCmmPoints = std::map<std::string, std::vector<Eigen::Vector3d>>;  // manifest id -> part frame

// The CMM plan's points per feature: CSV feature,point,x_mm,y_mm,z_mm (nx,ny,nz not needed).
PlannedCmmPoints plannedCmmPointsCsv(const std::string& text, const std::string& file);
// The stepped workpiece's plan (stepped_workpiece.cmm_plan, beside the manifest).
PlannedCmmPoints swPlannedCmmPoints(const parts::PlanManifest& m);

struct SwStatedCmm {
  SwSourceGeometry geometry;  // route "cmm"
  SwFromFeatures from;
  std::string criterion_note;              // what the file says of its fitting criterion (fittingCriterionNote)
  std::vector<std::string> scatter_notes;  // statedScatterNotes: more points than planned, no form or u
};
SwStatedCmm swCmmFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows,
                              const PlannedCmmPoints& planned, const std::string& file, const std::string& format);

// The whole evaluation: the CMM side from the rows, the probe side from its points, the notes
// that say what is lost.
SwEvaluation evaluateSteppedWorkpieceFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows,
                                                  const PlannedCmmPoints& planned, const std::string& file,
                                                  const std::string& format, const TtpPoints& probe);

// report.md's section and the stdout lines about the stated features.
std::string swFromFeaturesReport(const SwFromFeatures& f);
std::string swFromFeaturesStdout(const SwFromFeatures& f);

}  // namespace probeloop::evaluate
