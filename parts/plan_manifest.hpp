// The plan manifest (JSON): which probed point belongs to which feature, with its nominal
// contact point, approach direction, tip radius and planned time. Written by `plan`, read
// by `evaluate` and the simulators. Schema: docs/formats.md#plan-manifest.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::parts {

struct ManifestProgram {
  std::string file, dialect, log_file;
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
};

struct ManifestPoint {
  std::string feature;
  int position = 0, point = 0;
  Eigen::Vector3d contact_mm = Eigen::Vector3d::Zero();  // nominal tip centre at contact
  Eigen::Vector3d approach = Eigen::Vector3d::Zero();    // unit direction of travel
  double time_in_cycle_s = 0;                            // planned trigger time
};

struct PlanManifest {
  std::string file;
  std::string kind = "sphere_artifact";
  std::string dialect;
  std::vector<ManifestProgram> programs;
  // Machine.
  std::string machine_name;
  Eigen::Vector2d c_axis_centre_mm = Eigen::Vector2d::Zero();
  bool c_positive_is_clockwise = true;
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

  const ManifestSphere* sphere(int position) const;
  int pointsPerSphere() const;
};

std::string manifestToJson(const PlanManifest& m);
PlanManifest readManifest(const std::string& path);  // InputError on any inconsistency

}  // namespace probeloop::parts
