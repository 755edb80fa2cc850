// The stepped workpiece's error separation and forward prediction (seed 000, Yaqoob 2017,
// Ch. 3 and 5; notes/seed000.md §4, §9.1 items 6-9; docs/stepped-workpiece.md#separation-and-the-thesiss-tables).
//
// Separation turns measured dimensions of the steps into error components: the position
// error (CMM - probe), the thermal position error of a later step against the first
// (Eq. 3.5/3.6), the process error of a feed (measured - thermal - position, L1629; a two-wall
// sum, halved for one wall, L1639), the control errors of a feed change and of the process
// force (Eq. 3.11-3.15), the face-to-face widths of the walls (Table 5.3 from Table 5.2), the
// table tilt (floor slope) and the spindle tilt (wall inclination - table tilt, Sec. 3.4.1).
// Prediction sums the fitted components of a component model (parts/component_model_file.hpp)
// per axis at (x, y, z, T, S, feed), each with its standard uncertainty.
//
// Units: mm, min, rpm, mm/min; tilts are dimensionless slopes (~rad).
// Contract: every function refuses (GeometryError, with the reason) what would give a NaN or an
// infinity: a zero distance, a negative speed or feed, non-finite inputs, unequal row counts.
#pragma once
#include <array>
#include <map>
#include <string>
#include <vector>

#include "parts/component_model_file.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate::stepped {

// ---- Speed interpolation between the thermal stages (seed 000 Eq. 3.7-3.10, 5.17-5.44) ----

// Linear: piecewise-linear in S through (1000 rpm, stage 2), (3500 rpm, stage 1), (5500 rpm,
// stage 3), proportional to S below 1000 (S/1000 x stage 2) and above 5500 (S/5500 x stage 3).
// ThesisPrintedWeights: Eq. 3.7-3.10 as printed, with the weights swapped: Eq. 3.7 (3500 <= S <=
// 5500) gives the stage-3 function at 3500 and stage 1 at 5500, Eq. 3.8 (1000 <= S < 3500) stage 1
// at 1000; below 1000 Eq. 3.9 scales stage 1. An erratum kept so the Ch. 6 tables can be recomputed
// as the thesis did; at S = 4500, the only speed of Ch. 6, both give weights 0.5/0.5.
enum class SpeedWeights { Linear, ThesisPrintedWeights };

struct StageWeights {
  double stage_1000_rpm = 0, stage_3500_rpm = 0, stage_5500_rpm = 0;
};
StageWeights stageWeights(double spindle_rpm, SpeedWeights rule = SpeedWeights::Linear);

// A thermal component (e_pt_x, e_pt_y, e_splz, e_spd_x, e_spd_y, e_tt_x, e_tt_y) at Temp state
// T (min since machine start) and spindle speed S: the weighted stage functions of the model.
double thermalComponent(const parts::ComponentModel& m, const std::string& component, double T_min, double spindle_rpm,
                        SpeedWeights rule = SpeedWeights::Linear);

// ---- Separation rules (Ch. 3) ----

// Eq. 3.5/3.6: e_pt = (d6 - d6a) - (d5 - d5a) - e_pos: the later step's dimensional error minus
// the first step's (cut at thermal zero), minus the position error of the distance moved.
// Eq. 3.6 prints the x dimensions for Y; the y dimensions are meant (notes §4.4).
double thermalPositionError_mm(double d_later_mm, double d_later_nominal_mm, double d_first_mm, double d_first_nominal_mm,
                               double e_pos_mm);

// L1629: process error = measured dimensional error - thermal error at the cut time - position
// error (W8, whose 100 mm/min transitions carry no control error). It is a two-wall sum.
double processErrorTwoWalls_mm(double dimensional_error_mm, double e_pt_mm, double e_pos_mm);
// L1639: "the actual process error for forward prediction will be half the value reported".
double processErrorOneWall_mm(double two_wall_mm);

// The per-workpiece terms of one step that Eq. 3.11-3.15 subtract.
struct StepTerms {
  double d_mm = 0;      // measured dimension
  double e_pf_mm = 0;   // process error at the step's feed
  double e_pt_mm = 0;   // thermal error at the step's cut time
  double e_pos_mm = 0;  // position error of the distance moved
};
// Eq. 3.11/3.12: e_ctrl(2400-100) = (d_W2 - d_W8) - (e_pf_W2 - e_pf_W8) - (e_pt_W2 - e_pt_W8) - (e_pos_W2 - e_pos_W8).
double controlErrorFeedChange_mm(const StepTerms& fast_transitions_w2, const StepTerms& slow_transitions_w8);
// Eq. 3.15: e_cpr = (d_W2 - d_W5) - (e_pf) - (e_pt) - (e_pos) differences - e_ctrl(2400-100).
double controlErrorProcessForce_mm(const StepTerms& w2, const StepTerms& w5, double e_ctrl_2400_100_mm);
// Eq. 3.13/3.14: (Feed - 100)/(2400 - 100) with the model's feed change; 0 at or below the low
// feed (the 100 mm/min transitions are the thesis's zero of control error, L1629).
double controlFeedFactor(const parts::ComponentModel& m, double feed_mm_per_min);

// How Eq. 5.54 is read. WholeBracket: factor x Eq. 5.52 (Eq. 3.13's intent). Table67: factor x the
// linear term + the quadratic term, constant dropped — the reading that reproduces Table 6.7.
enum class ControlYReading { WholeBracket, Table67 };
double controlErrorY_mm(const parts::ComponentModel& m, double dy_mm, double feed_mm_per_min,
                        ControlYReading reading = ControlYReading::Table67);
// Eq. 5.55 read as Eq. 3.14 intends: factor x Eq. 5.53. Table 6.7's e_ctrl_x does not follow it
// (notes §9.2 row 5; the formula behind that column is not recoverable).
double controlErrorX_mm(const parts::ComponentModel& m, double dx_mm, double feed_mm_per_min);

// e_prog, the force model's deflection, is linear in feed: e_prog = k x Feed with k derived from
// four coefficient pairs (Eq. 5.47/5.49, 5.46/5.51, e_pfx/5.50, 5.56/5.57; notes §4.8).
constexpr double kEProgPerFeed = 1.9937e-8;
double eProgFromFeed(double feed_mm_per_min);

// ---- Geometry of the steps ----

struct Separated {
  double value = 0;  // mm or slope
  double u = 0;      // standard uncertainty, same unit
};

// Widths face to face per row and Z level (Table 5.3 from Table 5.2): high-side wall minus
// low-side wall, each row given as its face coordinate at the Z levels. u_point_mm: the standard
// uncertainty of one probed coordinate (independent points: u = sqrt(2) u_point).
std::vector<std::vector<Separated>> faceToFaceWidths(const std::vector<std::vector<double>>& low_wall_mm,
                                                     const std::vector<std::vector<double>>& high_wall_mm, double u_point_mm);

// Sec. 3.4.1: a floor cut by the tool's end does not show spindle tilt, so its slope is the table
// tilt: (z_b - z_a) / distance(a, b). A side wall shows spindle + table tilt: (x_A - x_B)/(z_A - z_B).
Separated tableTilt(double z_a_mm, double z_b_mm, double distance_ab_mm, double u_point_mm);
Separated wallInclination(double x_A_mm, double z_A_mm, double x_B_mm, double z_B_mm, double u_point_mm);
// "A simple subtraction operation" (L800): spindle tilt = wall inclination - table tilt.
Separated spindleTilt(const Separated& wall_inclination, const Separated& table_tilt);
// L812: e_splz = h7 - h3, a height cut warm minus one cut at thermal zero.
Separated spindleGrowth(double h_warm_mm, double h_cold_mm, double u_point_mm);
// A tilt seen at a lever arm: the Z error it makes (Table 6.5: 10 mm for the table tilts,
// 9 mm, the depth, for the spindle tilts; the thesis's signs are inconsistent, so signed).
double tiltToZ_mm(double tilt, double lever_arm_mm);

// ---- Forward prediction (notes §9.1 item 9) ----

struct PredictionPoint {
  double x_mm = 0, y_mm = 0, z_mm = 0;  // distance moved along each axis (z: the depth)
  double T_min = 0, spindle_rpm = 3500;
  double feed_x_mm_per_min = 100, feed_y_mm_per_min = 100, feed_z_mm_per_min = 100;
  double table_lever_arm_mm = 10, spindle_lever_arm_mm = 9;  // Table 6.5's
  SpeedWeights weights = SpeedWeights::Linear;
  ControlYReading control_y = ControlYReading::Table67;
  // Standard uncertainty of each component by name ("e_pt_x", ...). The thesis gives none
  // (notes §8): a component not listed enters the budget with 0 and says so.
  std::map<std::string, double> u_mm;
};

struct Component {
  std::string name, equation;  // "e_pf_x", "unnumbered e_pfx / 2 (L1639)"
  double value_mm = 0;
  double u_mm = 0;
};

struct AxisPrediction {
  char axis = 'X';
  std::vector<Component> components;  // in the order of the sum
  double total_mm = 0;                // the sum of the components (L2028: "not stacked")
  uncertainty::Budget budget;         // the components as uncorrelated contributions
};

// X: e_pos_x + e_pt_x + e_pf_x/2 + e_ctrl_x + e_cpr_x; Y likewise; Z: e_pos_z + e_splz + e_splf_z
// + table tilts x table lever arm + spindle tilts x spindle lever arm. Feeds below the low control
// feed give no process error (L1658).
std::array<AxisPrediction, 3> predict(const parts::ComponentModel& m, const PredictionPoint& p);

}  // namespace probeloop::evaluate::stepped
