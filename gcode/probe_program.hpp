// The sphere-artifact probing program (planner/sphere_cycle.hpp) on the dialect-neutral ops
// of gcode/program.hpp.
//
// Contract: coordinates are program coordinates in mm (= machine coordinates of the
// stylus-tip centre, since the program zeroes its work offset and applies the probe's
// length offset); angles in degrees. The writer wraps `cycle_body` in a loop that runs
// `cycles` times with a dwell of `gap_s` between cycles, opens the log before the loop and
// closes it after. Every probing op names (position, point) for the log line
// "PT <cycle> <position> <point> <x> <y> <z>".
#pragma once
#include <string>
#include <vector>

#include "gcode/program.hpp"

namespace probeloop::gcode {

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
