// A dialect-neutral probing program: what the planner decides, before any dialect.
//
// Contract: coordinates are program coordinates in mm (= machine coordinates of the
// stylus-tip centre, since the program zeroes its work offset and applies the probe's
// length offset); angles in degrees. The writer wraps `cycle_body` in a loop that runs
// `cycles` times with a dwell of `gap_s` between cycles, opens the log before the loop and
// closes it after. Every probing op names (position, point) for the log line
// "PT <cycle> <position> <point> <x> <y> <z>".
#pragma once
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace probeloop::gcode {

struct Comment { std::string text; };
// G0 in program coordinates; absent components are not moved.
struct Rapid { std::optional<double> x, y, z; };
// G0 in machine coordinates (G53), Z only: the tool-change height.
struct RapidMachineZ { double z_mm; };
struct RotateC { double c_deg; };
struct ToolChange { int tool; bool apply_length_offset; };
// A move near the artifact that must not touch it: contact stops the program.
struct ProtectedMove { double x, y, z, feed_mm_per_min; };
// The measuring move: stops at contact and logs the trigger point; no contact within the
// move stops the program.
struct ProbeMove { double x, y, z, feed_mm_per_min; int position, point; };
struct Dwell { double seconds; };

using Op = std::variant<Comment, Rapid, RapidMachineZ, RotateC, ToolChange, ProtectedMove,
                        ProbeMove, Dwell>;

struct ProbeProgram {
  std::string title;
  std::vector<std::string> header;  // comment lines at the top
  int work_offset = 6;              // 1..6 = G54..G59, zeroed by the program
  bool has_b_axis = false;
  std::string log_file;             // LinuxCNC LOGOPEN name; Fanuc writes to its DPRNT device
  int cycles = 1;
  double gap_s = 0;
  std::vector<Op> before_cycles, cycle_body, after_cycles;
};

std::string writeLinuxCnc(const ProbeProgram& p);
std::string writeFanucMacroB(const ProbeProgram& p, int program_number = 1000);

}  // namespace probeloop::gcode
