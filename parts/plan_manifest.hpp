// The plan manifest (JSON): which probed point belongs to which feature, with its nominal
// contact point, approach direction, tip radius and planned time. Written by `plan`, read
// by `evaluate` and the simulators. Schema: docs/formats.md#plan-manifest.
#pragma once
#include <Eigen/Dense>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "parts/feature.hpp"
#include "parts/sw_compensation.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::parts {

struct ManifestProgram {
  std::string file, dialect, log_file;
  // Kinds with several programs: pre_machining | test | inspection, and when each starts on
  // the planned clock (back to back from the first program's start) and how long it runs.
  std::string role;
  double start_s = 0, duration_s = 0;
};

// One sphere measurement = one C position of the cycle.
struct ManifestSphere {
  std::string id;       // "S<position>"
  int position = 0;     // 1-based position in the cycle
  double c_deg = 0;     // commanded C
  double angle_deg = 0; // nominal angle of the sphere centre about the C axis, machine frame
  Eigen::Vector3d nominal_centre_mm = Eigen::Vector3d::Zero();
  int formula_index = 0;  // 1..4: index k of seed 004 Eqs. 5.4-5.10; 0 = not used there
  int repeat_of = 0;      // position this one repeats (same angle), 0 = none
  double tilt_deg = 0;    // the tilting axis (PlanManifest::tilt_axis) at this position
  // Seed 004's C-axis evaluation uses the level positions that repeat no other.
  bool usedForCAxis() const { return repeat_of == 0 && tilt_deg == 0; }
};

// The machine's tilting axis when the plan tilts the table (issue 33): its line at tilt 0
// (B: parallel to Y through (x, z); A: parallel to X through (y, z)) and its sense.
struct ManifestTiltAxis {
  std::string name;  // "A" or "B"
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
  bool positive_is_clockwise = true;  // seen from +X (A) or +Y (B)
};

struct ManifestPoint {
  std::string feature;
  int position = 0, point = 0;
  Eigen::Vector3d contact_mm = Eigen::Vector3d::Zero();  // nominal tip centre at contact
  Eigen::Vector3d approach = Eigen::Vector3d::Zero();    // unit direction of travel
  double time_in_cycle_s = 0;                            // planned trigger time
  double c_deg = 0;  // kinds other than the sphere artifact: C while this point is probed
};

// Kinds other than the sphere artifact: a nominal feature with what the plan adds to it.
struct ManifestFeature {
  NominalFeature nominal;    // part frame
  int cycle = -1;            // cutting cycle that finishes it (0 = reference); -1 = pre-machining
  double cut_time_s = NAN;   // planned mid-time of the cut that finishes it (planned clock)
  int position = 0;          // on-machine inspection: the log's position number; 0 = not probed
  double probe_c_deg = NAN;  // C while it is probed on the machine
};

// One cutting cycle of a test (seed 004 Fig. 7.4): the surfaces it finishes and its C indices.
struct ManifestCycle {
  int cycle = 0;
  std::string phase;             // reference | warm_up | hold
  double c_axis_rpm_before = 0;  // the table's speed during the wait before it
  double start_s = 0, end_s = 0;
  int z_path = 0, facet = 0;
  double c_x_deg = 0, c_y_deg = 0;  // C while the X and the Y facets are cut
};

// One cutting move that finishes a feature (or a pre-machining operation).
struct ManifestCut {
  std::string id, program, feature;  // feature "" = no measured feature (roughing, notches ...)
  int cycle = -1;
  int tool = 0;
  double c_deg = 0;
  double start_s = 0, end_s = 0;                        // planned clock
  Eigen::Vector3d from_mm = Eigen::Vector3d::Zero();    // tool tip, program = machine coordinates
  Eigen::Vector3d to_mm = Eigen::Vector3d::Zero();
};

// What the thermal-test-piece evaluation needs beyond the features (seed 004 Ch. 7).
struct ThermalTestPieceConstants {
  int z_paths = 0, facets_per_segment = 0;
  double eq_7_10_alpha_um_per_m_K = 0, alpha_u_um_per_m_K = 0, eq_7_10_radius_mm = 0;
  CmmSpec cmm;
  double on_machine_repeatability_um = 0, on_machine_temperature_change_K = 0;
  std::string cmm_plan;  // the CMM point plan written beside the manifest
};

// One step of a stepped-workpiece experiment: its cutting conditions (Table 4.1) and when it
// was cut on the planned clock; temp_state_min is the thesis's 'Temp state' T (the mid-time of
// the step's wall cuts from the start of step 1's first cut, min).
struct ManifestStep {
  int step = 0;
  double feed_xy_mm_per_min = 0, feed_z_mm_per_min = 0, spindle_speed_rpm = 0;
  double start_s = 0, end_s = 0, temp_state_min = 0;
};

// What the stepped-workpiece evaluation needs beyond the features (seed 000).
struct SteppedWorkpieceConstants {
  std::string experiment, transition;
  double transition_feed_mm_per_min = 0, tool_runout_mm = 0;
  double tool_diameter_mm = 0;  // the finishing tool (its centre travels size + d between opposite walls)
  std::vector<SwStepCompensation> compensation;  // applied to the finishing path (empty: none)
  std::string compensation_file;
  std::vector<double> sizes_mm;
  std::vector<ManifestStep> steps;
  CmmSpec cmm;
  std::string cmm_plan;
};

// The kinds of test piece a plan is made for. The manifest keeps the kind's name (`kind`, the
// JSON field); every dispatcher switches on the type (PlanManifest::pieceKind()).
enum class PieceKind { SphereArtifact, ThermalTestPiece, SteppedWorkpiece };
std::optional<PieceKind> parsePieceKind(const std::string& name);  // nullopt: not a kind with a plan

struct PlanManifest {
  std::string file;
  std::string kind = "sphere_artifact";
  // The kind as a type; InputError naming the file for a kind no planner writes.
  PieceKind pieceKind() const;
  std::string dialect;
  std::vector<ManifestProgram> programs;
  // Machine.
  std::string machine_name;
  Eigen::Vector2d c_axis_centre_mm = Eigen::Vector2d::Zero();
  bool c_positive_is_clockwise = true;
  std::optional<ManifestTiltAxis> tilt_axis;  // written only when a position tilts the table
  double table_surface_z_mm = 0;
  double coordinate_resolution_mm = 0.001;
  // Probe and artifact.
  int probe_tool = 0;
  double tip_radius_mm = 0;
  double probe_repeatability_2sigma_um = 0;
  double sphere_radius_mm = 0;
  double sphere_form_error_um = 0;
  double radius_from_axis_mm = 0;  // d/2
  // Budget inputs; NaN = not stated.
  double probe_tool_change_repeatability_2sigma_um = NAN;
  double sphere_centre_height_mm = NAN;  // above the table surface
  double radius_from_axis_u_mm = NAN;
  double artifact_alpha_um_per_m_K = NAN;
  double artifact_temperature_change_half_width_K = NAN;
  bool tool_change_each_cycle = false;
  std::vector<ManifestSphere> spheres;
  std::vector<ManifestPoint> points;
  // Schedule.
  int cycles = 0;
  double gap_s = 0;
  double cycle_time_s = 0;
  std::vector<double> cycle_start_s;
  // Kinds other than the sphere artifact (empty for it).
  std::string part_name;
  Eigen::Vector3d part_origin_mm = Eigen::Vector3d::Zero();  // part frame origin, machine coords at C = 0
  std::string material_name;
  double material_alpha_um_per_m_K = NAN;
  std::vector<ManifestFeature> features;
  std::vector<ManifestCycle> cut_cycles;
  std::vector<ManifestCut> cuts;
  std::vector<EvaluationRule> evaluation;
  ThermalTestPieceConstants ttp;
  SteppedWorkpieceConstants sw;

  const ManifestSphere* sphere(int position) const;
  const ManifestFeature* feature(const std::string& id) const;  // nullptr if absent
  const ManifestFeature* featureAtPosition(int position) const;
  const ManifestProgram* program(const std::string& role) const;
  int pointsPerSphere() const;
};

std::string manifestToJson(const PlanManifest& m);
PlanManifest readManifest(const std::string& path);  // InputError on any inconsistency
// The same from the manifest's text (a campaign store keeps it); `file` names it in errors.
PlanManifest parseManifest(const std::string& text, const std::string& file);

}  // namespace probeloop::parts
