// Machine description (YAML, kind: machine). Schema: docs/formats.md#machine.
//
// Coordinates: machine coordinates in mm. With the probe's length offset active the
// controlled point is the stylus-tip centre, so "tip coordinates" = machine coordinates of
// the gauge line minus (0, 0, probe.length). Travel limits apply to the gauge line.
#pragma once
#include <cmath>
#include <Eigen/Dense>
#include <array>
#include <optional>
#include <string>

namespace probeloop::parts {

enum class Dialect { LinuxCnc, FanucMacroB };
const char* dialectName(Dialect d);  // "linuxcnc", "fanuc"

struct LinearAxis {
  double min_mm = 0, max_mm = 0;       // travel of the gauge line, machine coordinates
  double max_feed_mm_per_min = 0;
  double resolution_mm = 0.001;
};

struct RotaryAxis {
  bool present = false;
  bool continuous = false;              // no travel limit
  double min_deg = 0, max_deg = 0;
  double max_speed_rpm = 0;          // positioning (G0, indexing)
  // Continuous turning in a feed move of this axis alone (a table in turning mode, seed 004
  // L2024: C at 1200 rpm); default max_speed.
  double max_turning_speed_rpm = 0;
  double resolution_deg = 0.001;
  // Sense in which the table turns for +C, seen from +Z (for A and B: seen from +X, +Y). A workpiece-side C' axis turns the
  // table clockwise for +C (ISO 841: the workpiece moves opposite to the tool's +C).
  bool positive_is_clockwise = true;
};

struct ProbeSpec {
  int tool = 0;
  double length_mm = 0;                 // gauge line to stylus-tip centre (tool table)
  double tip_diameter_mm = 0;
  double repeatability_2sigma_um = 0;   // manufacturer's unidirectional repeatability (2 sigma)
  double tool_change_repeatability_2sigma_um = NAN;  // of the probe's position after a tool change; NaN = not stated
  // Geometry for the safety verifier (verify/safety.hpp); optional keys, defaults of a
  // Renishaw OMP60 with an M4 stylus: stylus shaft diameter 0.75 x the tip's, 50 mm from the
  // tip centre to the probe body, body 63 mm across; overtravel 5 mm past the contact.
  double stylus_diameter_mm = 0;        // 0 = 0.75 x tip_diameter
  double stylus_length_mm = 50;         // tip centre to the bottom of the probe body
  double body_diameter_mm = 63;         // the probe body, from the stylus up to the gauge line
  double max_overtravel_mm = 5;         // how far a probing move may go past the contact
};

struct ToolChangeSpec {
  double time_s = 0;                    // one tool change, chip to chip
  double z_mm = 0;                      // machine Z of the gauge line for tool changes (G53)
  int empty_tool = 0;                   // the tool number that empties the spindle
  // The tool holder of every cutting tool (safety verifier): a cylinder of this diameter from
  // the tool's stickout up to the gauge line (key tool_change.holder_diameter; SK40/HSK-A63 size).
  double holder_diameter_mm = 63;
};

struct Machine {
  std::string file;
  std::string name;
  std::string iso10791_code;
  Dialect dialect = Dialect::LinuxCnc;
  LinearAxis x, y, z;
  RotaryAxis a, b, c;  // A tilts about X, B about Y (a trunnion carrying C), C turns the table
  double rapid_feed_mm_per_min = 0;     // non-probing moves (the thesis: 6000 mm/min)
  Eigen::Vector2d c_axis_centre_mm = Eigen::Vector2d::Zero();  // X, Y of C in machine coords
  // Where the tilting axis lies (machine coordinates, tip coordinates with the probe's length
  // offset, at A = B = C = 0): B's axis line through (x, z) parallel to Y, A's through (y, z)
  // parallel to X. Optional: only the cycles that tilt the table need them (issue 33).
  std::optional<Eigen::Vector2d> b_axis_centre_xz_mm, a_axis_centre_yz_mm;
  double table_surface_z_mm = 0;        // machine Z (tip coordinates) of the table surface
  int work_offset = 6;                  // 1..6 = G54..G59; the program zeroes it
  ToolChangeSpec tool_change;
  ProbeSpec probe;
  // X, Y, Z: does the axis move the workpiece (true) or the tool (false)? From the ISO
  // 10791-1 code: axes between w and the frame b carry the workpiece; without b, a primed
  // axis (X', ISO 841) does. Decides the Abbe lever of the axis's angular errors.
  std::array<bool, 3> workpiece_side{false, false, false};
};

std::array<bool, 3> workpieceSideAxes(const std::string& iso10791_code);  // std::invalid_argument

Machine loadMachine(const std::string& path);

// How the table turns things (docs/conventions.md): a part-frame direction at angle th (deg,
// about the C axis) shows in the machine at th + tableTurnSign(..) * C; on a C' axis (table
// on the workpiece side, +C clockwise seen from +Z) the sign is -1.
inline double tableTurnSign(bool positive_is_clockwise) { return positive_is_clockwise ? -1.0 : 1.0; }
// A part-frame XY vector (from the C axis) as the machine sees it with the table at C, and back.
Eigen::Vector2d turnedByTable(const Eigen::Vector2d& v, double c_deg, bool positive_is_clockwise);
Eigen::Vector2d unturnedByTable(const Eigen::Vector2d& v, double c_deg, bool positive_is_clockwise);

}  // namespace probeloop::parts
