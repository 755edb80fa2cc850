// The thermal test piece of seed 004 Ch. 7 (Wiessner et al., Precision Engineering 52 (2018)):
// the description (YAML, kind: thermal_test_piece; docs/formats.md#thermal-test-piece), the
// geometry it implies (datum and measurement features, the hourly cutting sets) and the
// evaluation formulas Eqs. 7.1-7.10 (notes/seed004.md §5).
//
// Part frame (the thesis's CMM frame, seed 004 L2055): origin on the C axis in the finished top
// face, +Z up, X along the large notch (whose flanks are XZ planes at y = +-w/2), +X through
// the sector with the engraved mark. Lengths in mm, angles in degrees, times in s.
//
// Layout (docs/thermal-test-piece.md has the drawing and every stated choice):
// - four segments stand above the notch floor (z = -notch depth) in the quadrants left by the
//   large X notch and the narrow Y notch; segment s = 0..3 holds the facets of side X1 (+X+Y
//   quadrant), Y1 (-X+Y), X2 (-X-Y), Y2 (+X-Y);
// - facet k = 1..n of X1 has its outward normal at first_normal_angle + (k-1) pitch from +X;
//   X2 facet k is its opposite (+180); Y1 facet k is the mirror of X1 facet k about the Y
//   axis (180 - angle) and Y2 its opposite. Opposite facets are parallel (seed 004 L2047);
// - Z path j = 1..n runs along X at y = (j - (n+1)/2) pitch, cut 'cut_depth' below the floor;
// - cutting cycle c = 0..n-1 cuts Z path order[c] and facet order[c] of all four sides; cycle 0
//   makes the references (seed 004 L2034). X1 is cut on the machine's +X side of the C axis,
//   X2 on its -X side, Y1 on +Y, Y2 on -Y, so a shift of the table in X moves X1 and X2 in
//   opposite senses and Eq. 7.1 sees it.
#pragma once
#include <Eigen/Dense>
#include <array>
#include <string>
#include <vector>

#include "parts/feature.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::parts {

// One cylindrical band left by the circular milling of pre-machining step 1 (seed 004 L2006):
// the tool stands still, C turns once.
struct TtpBand {
  double diameter_mm = 0;
  double z_from_mm = 0, z_to_mm = 0;  // part frame, z_from < z_to <= 0
};

struct TtpLoadPhase {
  std::string name;           // warm_up, hold (seed 004 L2024: ISO 230-3)
  int cycles = 0;             // cutting cycles at the end of this phase's hours
  double c_axis_rpm = 0;      // table speed between the cuts (0 = NC hold at C = 0)
};

struct TtpProbing {
  double feed_mm_per_min = 0;        // seed 004 L2145
  double positioning_feed_mm_per_min = 0;
  double approach_mm = 0, overtravel_mm = 0, clearance_mm = 0;
};

// Every field is read from the description (every key is required: docs/formats.md); the
// values are in parts/thermal_test_piece.yaml, not here.
struct ThermalTestPiece {
  std::string file, name;
  // Blank (seed 004 L1990) and fixture (L1998).
  double blank_diameter_mm = 0, blank_height_mm = 0;
  WorkpieceMaterial material;
  // Three blind threaded holes from below, symmetric to the part's X axis; the bolts come
  // through the adapter, so nothing of the clamping stands above the part (our choice).
  int bolt_holes = 0;
  double bolt_circle_diameter_mm = 0, bolt_first_angle_deg = 0;
  double bolt_hole_diameter_mm = 0, bolt_hole_depth_mm = 0;
  double adapter_diameter_mm = 0, adapter_height_mm = 0;
  double washer_diameter_mm = 0, washer_thickness_mm = 0;  // fine-ground, under the bolt holes
  // Pre-machining (L2002-L2018).
  double pre_spindle_rpm = 0;
  double face_depth_mm = 0, face_stepover_mm = 0, face_feed_mm_per_min = 0;
  int face_tool = 0;
  std::vector<TtpBand> bands;
  int band_tool = 0;
  double band_feed_mm_per_min = 0;  // at the cutting edge
  int mark_tool = 0;
  Eigen::Vector2d mark_from_mm = Eigen::Vector2d::Zero(), mark_to_mm = Eigen::Vector2d::Zero();
  double mark_depth_mm = 0;
  int y_notch_tool = 0;
  double y_notch_width_mm = 0, y_notch_depth_mm = 0, y_notch_step_mm = 0;
  int x_notch_tool = 0;
  double x_notch_width_mm = 0, x_notch_depth_mm = 0, x_notch_step_mm = 0, x_notch_allowance_mm = 0;
  int facets_per_segment = 0;
  double facet_pitch_deg = 0, facet_apothem_mm = 0, facet_allowance_mm = 0, first_normal_angle_deg = 0;
  int facet_pre_tool = 0;
  double pre_feed_mm_per_min = 0;  // notches and facets
  // The test (L2022-L2047).
  int test_tool = 0;
  double cut_depth_mm = 0;                 // Z paths below the notch floor; facets from their allowance
  double test_feed_mm_per_min = 0, test_spindle_rpm = 0;
  int z_paths = 0;
  double z_path_pitch_mm = 0;
  double z_path_x_from_mm = 0, z_path_x_to_mm = 0;  // the whole length, from outside to outside
  double facet_path_half_length_mm = 0;     // each facet cut runs +-this along its chord
  std::vector<int> order;                    // path and facet number per cycle; [0] = reference
  Eigen::Vector2d waiting_position_mm = Eigen::Vector2d::Zero();  // part frame, at the cutting height
  double ring_radius_mm = 0;               // moves below the top go around the part on this circle
  std::vector<TtpLoadPhase> load;
  double wait_s = 0;                      // waiting time between two cutting cycles (L2034)
  double c_turn_move_s = 0;                 // the C load: alternating incremental C feed moves of this duration
  bool pre_machining_coolant = false;         // all milling is wet (L2000) ...
  bool test_coolant = false;                 // ... but a dry test gets MWF only in pre-machining
  // Inspection (L2053-L2145).
  TtpProbing probing;
  std::vector<double> facet_points_across_mm;  // along the facet, from its centre
  std::vector<double> facet_points_heights_mm;   // part-frame z
  std::vector<double> z_path_points_along_mm;  // x
  std::vector<double> z_path_points_across_mm;    // from the path's centre line
  double datum_circle_z_mm = 0;          // on the band the origin circle is fitted to
  int datum_circle_points = 0;
  double datum_band_diameter_mm = 0;
  CmmSpec cmm;                               // MPE 1.2 um + L/400 (L2145), 20 +- 0.3 °C
  double on_machine_repeatability_um = 0;  // machine repeatability added to the probe's (L2145)
  double on_machine_temperature_change_K = 0;  // part temperature change between compared features
  // Evaluation constants (Eq. 7.10, L2177).
  double eq_7_10_alpha_um_per_m_K = 0, eq_7_10_radius_mm = 0;
  double alpha_u_um_per_m_K = 0;           // standard uncertainty of alpha (budget of Eq. 7.10)
  std::vector<CuttingTool> tools;

  double finishedHeight() const { return blank_height_mm - face_depth_mm; }
  double supportHeight() const { return adapter_height_mm + washer_thickness_mm; }  // table -> piece
  double notchFloorZ() const { return -x_notch_depth_mm; }
  double cuttingZ() const { return -x_notch_depth_mm - cut_depth_mm; }  // tool tip during the test
  int cycles() const { return static_cast<int>(order.size()); }
  const CuttingTool* tool(int number) const;
};

ThermalTestPiece loadThermalTestPiece(const std::string& path);

// --- geometry -----------------------------------------------------------------------------

enum class FacetSide { X1 = 0, Y1 = 1, X2 = 2, Y2 = 3 };
const char* facetSideName(FacetSide s);  // "X1", ...

// Ids: TOP, FLANK_P (y = +w/2), FLANK_N, CYL (the datum band); Z1..Z9; X1_1..X1_9, Y1_1, X2_1, Y2_1...
std::string zPathId(int j);
std::string facetId(FacetSide side, int k);

double facetNormalAngle(const ThermalTestPiece& t, FacetSide side, int k);  // deg from +X
double zPathY(const ThermalTestPiece& t, int j);                             // mm
std::vector<NominalFeature> nominalFeatures(const ThermalTestPiece& t);       // datums, Z paths, facets

// One cutting cycle (seed 004 Fig. 7.4): the Z path and the four facets it finishes.
struct TtpCuttingCycle {
  int cycle = 0;        // 0 = references
  int z_path = 0;       // path number
  int facet = 0;        // facet number (same on all four sides)
  std::string phase;    // reference | warm_up | hold
  double c_axis_rpm_before = 0;  // table speed during the hour before this cycle
  double nominal_time_s = 0;     // cycle * period (the planner times the cuts exactly)
};
std::vector<TtpCuttingCycle> cuttingCycles(const ThermalTestPiece& t);

// The workpiece the simulator machines: the blank (cylinder) with its bolt holes, the bolt
// heads and the adapter as collision bodies, material, tools, CMM; frame origin 0 (set by the
// planner/simulator from the machine: partOriginOnMachine).
Workpiece thermalTestPieceWorkpiece(const ThermalTestPiece& t);

// Where the part frame's origin sits in machine (tip) coordinates at C = 0: on the C axis,
// adapter + washers + finished height above the table surface.
Eigen::Vector3d partOriginOnMachine(const ThermalTestPiece& t, const Eigen::Vector2d& c_axis_centre_mm,
                                    double table_surface_z_mm);

// --- evaluation formulas (seed 004 §7.2; notes/seed004.md §5.5) -------------------------

// What one cutting cycle's surfaces measure: distances of the four facets from the origin
// (along each facet's own normal), the depth of the Z path below the datum plane at its
// centre, and the angle beta of its plane about +Y (right-hand: atan2(n_x, n_z)).
struct TtpMeasures {
  double d_X1_mm = 0, d_X2_mm = 0, d_Y1_mm = 0, d_Y2_mm = 0;
  double d_Z_mm = 0;
  double beta_urad = 0;
};

struct TtpErrors {
  double EX_um = 0, EY_um = 0;                 // Eqs. 7.1, 7.2 with the sign typo corrected
  double EX_printed_um = 0, EY_printed_um = 0;  // as printed: "- d_X1(t0)" does not cancel
  double ETTP_7_3_um = 0;   // (dl_X + dl_Y) / 2: the mean change of the two diameters
  double ETTP_7_9_um = 0;   // mean of the four one-sided changes: half of Eq. 7.3
  double EZ_um = 0;         // Eq. 7.4
  double EB_urad = 0;       // Eq. 7.5
};

// Eqs. 7.1-7.5 and 7.9 for cycle i against the reference cycle 0.
TtpErrors ttpErrors(const TtpMeasures& at_i, const TtpMeasures& at_0);

// Manual forms from dial-gauge readings g (um): each facet's distance to the reference facet
// of its segment (seed 004 Eqs. 7.7-7.9).
struct GaugeErrors {
  double EX_um = 0, EY_um = 0, ETTP_um = 0;
};
GaugeErrors gaugeErrors(double g_X1_um, double g_X2_um, double g_Y1_um, double g_Y2_um);

// Eq. 7.6: U_dT = alpha dT E (um for alpha in um/(m K), dT in K, E in um).
double measurementDeviationEq76_um(double alpha_um_per_m_K, double dT_K, double E_um);
// Eq. 7.10: dT = E / (alpha R) (K for E in um, alpha in um/(m K), R in mm).
double temperatureEquivalentEq710_K(double E_um, double alpha_um_per_m_K, double R_mm);
// Table 7.2: span of E over cycles 0..n (max - min, E(t0) = 0 included), and the reduction of
// a compensated span against an uncompensated one, in percent.
double span(const std::vector<double>& values_from_t0);
double spanReductionPercent(double uncompensated, double compensated);

}  // namespace probeloop::parts
