// Sphere artifact on the rotary table (YAML, kind: sphere_artifact), seed 004 Ch. 5.
// Schema: docs/formats.md#sphere-artifact. Lengths in mm, angles in degrees.
#pragma once
#include <cmath>
#include <string>
#include <vector>

namespace probeloop::parts {

struct SphereArtifact {
  std::string file;
  double sphere_diameter_mm = 0;
  double sphere_form_error_um = 0;     // from the sphere's calibration certificate
  double stem_diameter_mm = 0;
  double stem_length_mm = 0;           // table surface to the sphere's lowest point
  double radius_from_axis_mm = 160;    // d/2 (seed 004: 0.16 m)
  double angle_at_c0_deg = 180;        // sphere angle about C at C = 0, seen from +Z, from +X
  std::vector<double> c_positions_deg{0, 90, 180, 270, 360};
  // Positions with the table tilted (issue 33), after the C positions: the tilting axis's
  // angle (A or B, the machine's) and C. They calibrate the tilting axis's location errors
  // beside C's (evaluate/rotary_calibration.hpp); the C positions alone keep seed 004's seven.
  struct TiltedPosition { double tilt_deg = 0, c_deg = 0; int line = 0; };
  std::vector<TiltedPosition> tilted_positions;
  char tilt_axis = 0;  // 'A' or 'B' when tilted_positions is not empty
  // Probing: `equator_points` lateral points at machine angles 0, 360/n, ... (+X first)
  // plus the top point; all stylus-tip centres.
  int equator_points = 4;
  bool top_point = true;
  double probing_feed_mm_per_min = 200;
  double positioning_feed_mm_per_min = 1000;  // protected moves near the artifact
  double approach_mm = 3;              // start of the probing move before nominal contact
  double overtravel_mm = 2;            // how far past nominal contact a probe move may go
  double clearance_mm = 20;            // clearance plane above the sphere top (tip centre)
  // Campaign.
  int cycle_count = 0;                 // either a count ...
  double duration_s = 0;               // ... or a duration (count derived)
  double gap_s = 300;                  // end of one cycle to start of the next
  // The wait between cycles decided outside the running program (the live TALC loop writes it:
  // Fanuc #500, LinuxCNC analog input 0; gcode/probe_program.hpp); gap_s then only sets the
  // nominal schedule of the plan manifest.
  bool live_interval = false;
  bool tool_change_each_cycle = true;  // probe in and out every cycle (seed 004: 2 ATC)
  // Budget inputs (docs/uncertainty.md); NaN = not stated (listed in the budget as such).
  double radius_from_axis_u_mm = NAN;           // standard uncertainty of d/2
  double alpha_um_per_m_K = NAN;                // stem and sphere material
  double temperature_change_half_width_K = NAN;  // bound of the artifact's uncorrected temperature change

  double sphereRadius() const { return sphere_diameter_mm / 2; }
  double centreHeightAboveTable() const { return stem_length_mm + sphereRadius(); }
  int pointsPerPosition() const { return equator_points + (top_point ? 1 : 0); }
};

SphereArtifact loadSphereArtifact(const std::string& path);

}  // namespace probeloop::parts
