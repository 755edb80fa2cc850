// Evaluation of the thermal test piece (seed 004 §7.2; docs/thermal-test-piece-evaluation.md):
// measured surface points -> datum frame -> one least-squares plane per Z path and facet ->
// d, d_Z, beta -> E_X, E_Y, E_Z, E_B, E_TTP and the Eq. 7.10 temperature per cutting cycle,
// each with its GUM budget -> spans over the periods of Table 7.2.
//
// Contract:
// - Datum frame (seed 004 L2055): LS plane of TOP -> z axis (up) and z origin; LS planes of
//   FLANK_P, FLANK_N -> y = normalised (n_N - n_P) made perpendicular to z, x = y x z; LS
//   circle of the CYL points in the datum plane -> the origin O (on the TOP plane). Too few
//   datum points -> InputError naming the datum.
// - d of a facet = n . (c - O) with n the fitted normal oriented like the nominal outward
//   normal; d_Z of a Z path = depth of its plane below the datum plane at (x = 0, y = y_j);
//   beta = atan2(n_x, n_z) (urad).
// - Cycle i against cycle 0 by parts::ttpErrors (Eqs. 7.1-7.5, 7.9), dT by Eq. 7.10 with the
//   sign of docs/thermal-test-piece.md §4 (dT = -E_TTP,7.9 / (alpha R)). ETTP_um is Eq. 7.3
//   (diametral) on every route, the dial gauge's too ((g_X1 + g_X2 + g_Y1 + g_Y2) / 2); Eq. 7.9
//   (radial, half of it) is reported as ETTP_7_9_um. A missing reference feature is an
//   InputError ("a missing reference cut"); a missing measurement feature omits the values that
//   need it, with the reason; a feature with 1-2 points or collinear points is an InputError
//   naming it, its point count and its lines.
// - After the alignment every fitted Z path and facet must match its nominal feature: normal
//   within kNominalAngleDeg, centre within kNominalDistanceMm of the nominal surface; otherwise
//   an InputError naming the file, the feature and the line of its first point ("mislabelled
//   points?").
// - The formulas listed are the manifest's (parts::PlanManifest::evaluation); the gauge route
//   lists those of the values it gives.
// - Every value carries a budget (uncertainty::combine): point scatter (type A or B, the
//   larger, as evaluate/location_budget), resolution, machine repeatability, temperature,
//   datum alignment; for dT also alpha. Terms a manifest does not state are listed with 0 and
//   'not stated: <where to set it>'.
// - Deterministic; no NaN: absent values are absent (std::optional), not NaN.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "evaluate/feature_actuals.hpp"
#include "evaluate/ttp_ingest.hpp"
#include "parts/feature.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

// A fitted feature against its nominal one after the alignment (the cut errors are a few um
// and urad; a mislabelled or misassigned feature is off by degrees or tenths of a mm).
constexpr double kNominalAngleDeg = 1.0;
constexpr double kNominalDistanceMm = 0.5;

struct TtpOptions {
  double coverage_k = 2.0;
  bool form_mz = true;    // also the minimum-zone form of every plane (reported, not used)
  bool budgets = true;    // false: values only (Monte Carlo checks)
  // Dial-gauge route: resolution of the gauge, read as a rectangular +-res/2 per reading and
  // per zero setting (CLI: --gauge-resolution-um). The thesis states no gauge uncertainty; 1 um
  // is a common dial gauge.
  double gauge_resolution_um = 1.0;
};

// The datum frame: part coordinates p' = R (p - origin), R's rows the x, y, z axes in the
// input frame.
struct TtpFrame {
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d toPart(const Eigen::Vector3d& p) const { return R * (p - origin_mm); }
};

struct TtpDatum {
  std::string id;
  int points = 0;
  double form_um = 0;  // minimum-zone flatness (planes) or roundness (CYL); LS peak-to-valley if MZ is off
};

struct TtpAlignment {
  TtpFrame frame;
  Eigen::Vector3d rotation_urad = Eigen::Vector3d::Zero();     // file -> part rotation as a rotation vector
  Eigen::Vector3d translation_um = Eigen::Vector3d::Zero();    // file -> part: p' = R p + t
  std::vector<TtpDatum> datums;                                // TOP, FLANK_P, FLANK_N, CYL
};

struct TtpScatter {
  double type_b_sigma_mm = 0;  // specification (CMM: RMS of MPE(L)/2 over the measurement points)
  double type_a_sigma_mm = 0;  // pooled residual of the measurement-feature plane fits
  double type_a_dof = 0;
  bool type_a_used = false;
};

struct TtpFeatureResult {
  std::string id, group;
  int index = 0, cycle = 0;
  double time_s = 0;  // planned cut time
  int points = 0;
  double rms_um = 0, form_mz_um = 0;
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();  // LS plane position (part frame)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    // oriented like the nominal outward normal
  std::optional<double> d_mm, depth_mm, beta_urad;
  double u_d_um = 0;  // point scatter only: of d (facets) or of the depth (Z paths)
};

struct TtpCycleResult {
  int cycle = 0;
  std::string phase;
  double time_s = 0;
  std::vector<uncertainty::Budget> values;  // quantities EX_um, EY_um, EZ_um, EB_urad, ETTP_um, dT_K (those available)
  std::optional<double> EX_printed_um, EY_printed_um, ETTP_7_9_um;
  std::vector<std::string> missing;
  const uncertainty::Budget* value(const std::string& quantity) const;  // nullptr if absent
};

// A period's span needs the value at every cycle of the period; a span with cycles missing is
// incomplete: listed with the missing cycles, without span and U, and left out of comparisons.
struct TtpSpanValue {
  std::string quantity;
  double span = 0, U = 0;            // complete spans only
  std::vector<int> missing_cycles;   // cycles of the period without this value
  bool complete() const { return missing_cycles.empty(); }
};

struct TtpSpan {
  double period_h = 0;
  int first = 0, last = 0;  // cycles
  std::vector<TtpSpanValue> values;
};

struct TtpComparisonRow {
  double period_h = 0;
  std::string quantity;
  double this_span = 0, other_span = 0;
  std::optional<double> reduction_percent;  // absent when this run's span is 0
};

struct TtpComparison {
  std::string against;
  std::string this_route, other_route;  // ttpRouteName of each evaluation
  std::vector<TtpComparisonRow> rows;
  std::vector<std::string> left_out;     // spans not compared and why (incomplete in either run)
};

// The features route (issue 34): a feature the file stated, and how its scatter was taken.
struct TtpStatedFeature {
  std::string id, file_id, matched_by;  // manifest id; the file's id; "id" | "nominal geometry"
  int line = 0, n_stated = 0, n_planned = 0;  // n_stated 0: not stated
  std::optional<double> form_um;              // as stated
  double sigma_um = 0;                        // per placed point in the budget (RMS over them)
  std::string sigma_from;                     // specification | stated forms | stated u
};
struct TtpStatedFeatures {
  std::vector<TtpStatedFeature> features;  // in the manifest's order
  std::vector<std::string> unmatched;      // rows not used: "file:line: kind 'id' (nearest X, d mm: why)"
  int other_kinds = 0;                     // point or line rows, not used
  int points_placed = 0;                   // the plan's points placed on them (TtpEvaluation::points is 0: none read)
};

struct TtpEvaluation {
  std::string manifest_file, input_file, format, assigned_by;
  TtpRoute route = TtpRoute::Cmm;
  int points = 0;
  double coverage_k = 2.0;
  std::optional<TtpAlignment> alignment;  // absent for the gauge route
  TtpScatter scatter;
  std::vector<TtpFeatureResult> features;  // measurement features (Z paths, facets)
  std::vector<TtpCycleResult> cycles;      // cycle 0 (zeros) first
  std::vector<TtpSpan> spans;
  std::optional<TtpComparison> comparison;
  std::vector<parts::EvaluationRule> formulas;
  std::vector<std::string> notes;          // route-specific statements (e.g. what the gauge cannot give)
  double gauge_resolution_um = 0;          // gauge route
  std::optional<TtpStatedFeatures> stated;  // the features route
};

TtpEvaluation evaluateThermalTestPiece(const parts::PlanManifest& m, const TtpPoints& points, const TtpOptions& options = {});
// From the features a CMM states (feature CSV, QIF MeasuredFeatures or DMIS FA actuals without
// points; evaluate/feature_match.hpp, evaluate/feature_points.hpp): the plan's points placed on
// each stated feature, then the CMM route's steps, so every value equals the point route's from
// the same least-squares features. The point scatter: the stated forms of the Z paths and facets
// turned into sigmas (form over d2(n) sqrt((n-3)/n)) and pooled as the point route pools its
// residuals (type A, sum of rangeDof(n); in e.scatter's type A fields), used where larger than
// MPE(L)/2; per feature the sigma a stated u of its location implies where larger; all times the
// feature's point_scale (never below the planned layout's). e.stated lists each feature; e.notes
// says what is lost; e.points is 0 (none read).
TtpEvaluation evaluateThermalTestPieceFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows,
                                                   const std::string& file, const std::string& format,
                                                   const TtpOptions& options = {});
TtpEvaluation evaluateThermalTestPieceGauge(const parts::PlanManifest& m, const TtpGaugeReadings& readings,
                                            const TtpOptions& options = {});

// The datum frame alone (file frame -> part frame) from labelled points. InputError naming the
// datum when it has too few or degenerate points.
TtpFrame ttpDatumFrame(const TtpPoints& points);

// Table 7.2: spans per period (first hour = cycles 0-1, half, all; E(t0) = 0 included) and
// the comparison with another evaluation.json of the same kind (this run = UC, other = C).
// compareSpans refuses (InputError naming the other file) an evaluation of another kind, or
// one whose formula for a compared quantity differs from this run's (e.g. an E_TTP of another
// form): the routes may differ, the quantities may not. Incomplete spans (either run) are left
// out and listed.
std::vector<TtpSpan> ttpSpans(const std::vector<TtpCycleResult>& cycles);
std::string cycleRanges(const std::vector<int>& sorted_cycles);  // {3, 4, 5, 8} -> "3-5, 8"
TtpComparison compareSpans(const TtpEvaluation& e, const std::string& other_evaluation_json);

// A-priori U (k = 2) of every value from the planned points and the specifications alone
// (type B scatter, no measured values): per route, the largest over the measurement cycles.
struct TtpPredictedValue {
  std::string quantity, unit;
  double U = 0;
  int cycle = 0;
  std::string largest;  // the largest contribution
};
struct TtpPrediction {
  std::vector<TtpPredictedValue> cmm, on_machine;
  std::string note;  // when nothing can be predicted (no planned points)
};
TtpPrediction predictThermalTestPiece(const parts::PlanManifest& m, double k = 2.0);

// Writers (formats: docs/thermal-test-piece-evaluation.md §7).
std::string ttpErrorsCsv(const TtpEvaluation& e);
std::string ttpEvaluationJson(const TtpEvaluation& e);
std::string ttpReport(const TtpEvaluation& e);
std::string ttpStdout(const TtpEvaluation& e, const std::string& errors_file, const std::string& json_file,
                      const std::string& report_file);

}  // namespace probeloop::evaluate
