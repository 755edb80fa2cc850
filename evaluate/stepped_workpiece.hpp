// Evaluating one stepped workpiece (seed 000, Yaqoob 2017 Ch. 5; docs/stepped-workpiece.md §6):
// its CMM export and its on-machine probe log -> the geometry of every step and the error
// components the thesis separates from one part, each with a GUM budget.
//
// Geometry (per source, CMM and probe): a least-squares plane per wall, floor and the top
// (geometry::fitElement); per step the face-to-face widths X and Y at the wall's mid-height
// (the planes evaluated at the step's centre line), the depth of its floor below the top (both
// planes at the floor's nominal centre, the same place for both routes), the walls' tilt dx/dz,
// dy/dz (the mean of the two walls: a tilted path tilts both the same way), the floor's slopes
// dz/dx, dz/dy and Oz, the squareness of the X walls to the Y walls (the angle between their
// normals minus 90 deg, positive when it is larger).
//
// Separation (both sources; seed 000 Sec. 3.3-3.6):
// - e_pos (L761: CMM - probe): per step and axis, CMM width - probe width; it belongs to the
//   distance the probe's centre travelled between the walls: the steps are bosses, the ball
//   touches each wall from outside, so size + stylus diameter (the thesis's "offset distance
//   ... incorporated", L769). Z: CMM depth - probe depth, over the depth. A straight line
//   through zero per axis, e_pos(L) = k L, weighted by each step's own uncertainty; the lines
//   common to all steps (the part's temperature, the MPE's length term) go into u(k) whole.
// - e_proc (L1629, a two-wall sum): probe width error - (e_pos over the tool centre's travel,
//   size + tool diameter, minus e_pos over the probe's, size + stylus diameter) - the thermal
//   position error, which one workpiece cannot separate: taken as 0 (stated in the output;
//   a W1 campaign gives it). Per wall: half (L1639).
// - e_splz (Sec. 3.5, L812): the floor's depth error from the probe: the spindle's growth
//   between the top's cut and the floor's (+ when the floor lies shallower, i.e. the tool tip
//   rose), with the cut times of the manifest.
// Budgets: probe repeatability (pooled over the repeated points, type A; else the manifest's
// 2 sigma, type B), the CMM's MPE (rectangular), the planes' fit residuals, the part's
// temperature (CMM: the manifest's +-half width; on the machine: +-1 K about 20 C, our
// assumption, rectangular), and for e_proc the line's u(k).
//
// Contract: InputError (file, line, feature) for what cannot be read or a feature with fewer
// than 3 points; GeometryError never escapes as a NaN: a degenerate plane is refused naming it.
#pragma once
#include <Eigen/Dense>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "evaluate/ttp_ingest.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

struct SwPlane {
  std::string id, role;
  int points = 0;
  Eigen::Vector3d point_mm = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();  // outward
  double rms_um = 0;
  // Standard uncertainty of the plane's slope d(q_a)/d(q_i) over each other axis i (rad; a =
  // the axis of the nominal normal): s of the residuals x sqrt of (M^-1)_ii, M the centred
  // second moments of the points' other two coordinates (type A, n - 3 dof).
  double u_slope[3] = {0, 0, 0};
  double slope_lever[3] = {0, 0, 0};  // sqrt((M^-1)_ii), 1/mm: u_slope per mm of one point's sigma
  bool slope_u_from_spec = false;  // the specification was larger than the residual s
  // Stated planes (sw_features): the dof of a form-based sigma, rangeDof(n) (0: points - 3).
  double form_dof = 0;
  bool stated = false;  // rms_um is then the per-point sigma chosen, not a residual
  double dof() const { return form_dof > 0 ? form_dof : static_cast<double>(points > 4 ? points - 3 : 1); }
};

struct SwStepGeometry {
  int step = 0;
  double size_mm = 0, depth_nominal_mm = 0;
  double width_x_mm = 0, width_y_mm = 0, depth_mm = 0;
  double u_wall_x_um = 0, u_wall_y_um = 0, u_depth_um = 0;  // from the fits' residuals
  double lean_x_urad = 0, lean_y_urad = 0;                  // tilt dx/dz (dy/dz) of the X (Y) walls, their mean
  double floor_slope_x_urad = 0, floor_slope_y_urad = 0;    // dz/dx, dz/dy of the floor
  double oz_urad = 0;
  double u_lean_x_urad = 0, u_lean_y_urad = 0, u_floor_slope_x_urad = 0, u_floor_slope_y_urad = 0, u_oz_urad = 0;
  // Expanded (95 %): k from Student's t at the fewest degrees of freedom (points - 3) of the
  // planes involved (a wall of 6 points has 3: k = 3.18), JCGM 100 G.3.
  double U_lean_x_urad = 0, U_lean_y_urad = 0, U_floor_slope_x_urad = 0, U_floor_slope_y_urad = 0, U_oz_urad = 0;
  double width_x_error_um() const { return (width_x_mm - size_mm) * 1e3; }
  double width_y_error_um() const { return (width_y_mm - size_mm) * 1e3; }
  double depth_error_um() const { return (depth_mm - depth_nominal_mm) * 1e3; }
};

struct SwSourceGeometry {
  std::string file, route;  // cmm | on_machine
  // Empty: the planes are fits of measured points. Else (evaluate/sw_features.hpp) the planes are
  // the file's stated features and this says where each plane's sigma came from.
  std::string stated_basis;
  std::vector<SwPlane> planes;
  std::vector<SwStepGeometry> steps;
};

struct SwStepSeparation {
  int step = 0;
  double feed_mm_per_min = 0, spindle_rpm = 0, temp_state_min = 0;
  // On the programs' clock (the simulator's inputs.csv clock): the step's cuts, and the mid-time
  // of its wall cuts (step 1's start + T), the time its widths belong to.
  double cut_start_s = 0, cut_end_s = 0, cut_mid_s = 0;
  double travel_probe_mm = 0, travel_tool_mm = 0;  // size + stylus d, size + tool d
  // The CMM's measurement of the width X, Y and the depth: its MPE at the length, its planes'
  // residuals, the part's temperature at the CMM (what a series of CMM errors carries).
  double u_cmm_um[3] = {0, 0, 0};
  uncertainty::Budget e_pos_x_um, e_pos_y_um, e_pos_z_um;
  uncertainty::Budget e_proc_x_um, e_proc_y_um;  // two-wall sums (L1639: half per wall)
  uncertainty::Budget e_splz_um;
  // Prediction for this experiment cut again (Ch. 6): the CMM width errors, e_pos over the
  // tool's travel + e_proc (+ e_pt, 0 from one part), i.e. probe width error + k (size + stylus
  // d); the CMM depth error, probe depth error + k_z depth. Independent contributions only.
  uncertainty::Budget predicted_width_x_um, predicted_width_y_um, predicted_depth_um;
};

// A compensated part against the part it was predicted from (`evaluate … --compare
// before/evaluation.json`): per step and feature the CMM error before and after, the fall, and
// the fall the compensation promised (the manifest's offsets: the two walls' sum for a width,
// the floor's for a depth) with its U.
struct SwBeforeAfter {
  int step = 0;
  std::string quantity;  // width_x | width_y | depth
  double before_um = 0, after_um = 0, fall_um = 0, promised_um = 0, U_promised_um = 0;
};

// The CMM side taken from a file's stated features (evaluate/sw_features.hpp): per plane what the
// file states and the per-point sigma the budget uses; the rows that fit no plane, listed.
struct SwStatedPlane {
  std::string id, row, matched_by;  // manifest id; the file's id (file:line); id | nominal geometry
  int n_stated = 0, n_planned = 0;  // n_stated 0: not stated
  double form_um = 0;               // NaN: not stated
  double sigma_um = 0;              // per measured point, the largest of what is stated
  std::string sigma_from;           // "form" | "MPE" | "stated u"
};
struct SwFromFeatures {
  std::string file, format, assigned_by;
  std::vector<SwStatedPlane> planes;
  std::vector<std::string> unmatched;  // "file:line: kind 'id' fits no plane (nearest ..., d mm)"
  int other_kinds = 0;
};

struct SwEvaluation {
  std::string experiment;
  // How the walls were joined (the manifest's: non_cutting | fast | continuous) and at what feed
  // (mm/min; a continuous path turns at each step's cutting feed): the control error's variable.
  std::string transition;
  double transition_feed_mm_per_min = 0;
  SwSourceGeometry cmm, probe;
  double probe_repeatability_um = 0;  // 1 sigma per point
  int probe_repeat_pairs = 0;         // 0: the manifest's specification was used
  uncertainty::Budget k_pos_x_um_per_mm, k_pos_y_um_per_mm, k_pos_z_um_per_mm;
  std::vector<SwStepSeparation> steps;
  std::vector<std::string> notes;
  std::string compared_with;
  std::vector<SwBeforeAfter> before_after;
  // The offsets the plan applied (its manifest's compensation; empty: none), written to
  // evaluation.json so that a later --compare promises only the change between the two plans.
  std::vector<parts::SwStepCompensation> applied;
  std::optional<SwFromFeatures> from_features;  // the CMM side from stated features, not points
};

// point_u_um(L): the route's specified standard uncertainty of one point at distance L (mm) from
// the part origin (CMM: MPE(L) / sqrt 3; probe: its repeatability); a plane's slope u uses the
// larger of it and the plane's residual s (the specification: infinite dof, k = 2; the residual:
// n - 3 dof). Absent: the residual alone.
SwSourceGeometry steppedGeometry(const parts::PlanManifest& m, const TtpPoints& points, const std::string& route,
                                 const std::function<double(double)>& point_u_um = {});
// Its two halves: the planes fitted to the points, then the steps from the planes (InputError
// naming a plane the manifest plans that has no points).
std::vector<SwPlane> swPlanes(const parts::PlanManifest& m, const TtpPoints& points,
                              const std::function<double(double)>& point_u_um = {});
SwSourceGeometry swGeometryFromPlanes(const parts::PlanManifest& m, std::vector<SwPlane> planes, const std::string& file,
                                      const std::string& route);
// The CMM's specified standard uncertainty of one point at L mm from the part origin: MPE(L)/sqrt 3.
std::function<double(double)> swCmmPointU(const parts::PlanManifest& m);

// The manifest's repeated probe points (same feature, same nominal contact): s of one point.
struct SwRepeatability {
  double s_um = 0;
  int pairs = 0;  // degrees of freedom: sum over the repeated places of (touches - 1)
};
SwRepeatability probeRepeatability(const parts::PlanManifest& m, const TtpPoints& probe);

SwEvaluation evaluateSteppedWorkpiece(const parts::PlanManifest& m, const TtpPoints& cmm, const TtpPoints& probe);
// The same from the CMM side's geometry already built (the stated-features route).
SwEvaluation evaluateSteppedWorkpiece(const parts::PlanManifest& m, SwSourceGeometry cmm, const TtpPoints& probe);

// Fills before_after from the earlier evaluation.json (InputError naming the file when it is
// not a stepped-workpiece evaluation of the same experiment and steps) and the manifest's
// compensation (InputError when the plan was not compensated). When the earlier part was itself
// compensated (its "compensation_applied"), the promised fall is the change of the offsets.
void compareWithBefore(SwEvaluation& e, const parts::PlanManifest& m, const std::string& before_json_file);

// Outputs: errors.csv (one row per step: the components with u and U), evaluation.json,
// report.md, and the stdout summary.
std::string swErrorsCsv(const SwEvaluation& e);
std::string swEvaluationJson(const SwEvaluation& e);
std::string swReport(const SwEvaluation& e);
std::string swStdout(const SwEvaluation& e, const std::string& out_dir);
// compensation.json (parts/sw_compensation.hpp): each wall half its step's predicted width
// error (L1639), each floor its predicted depth error, with U.
std::string swCompensationFile(const SwEvaluation& e);

}  // namespace probeloop::evaluate
