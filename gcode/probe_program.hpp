// The sphere-artifact probing program (planner/sphere_cycle.hpp) on the dialect-neutral ops
// of gcode/program.hpp.
//
// Contract: coordinates are program coordinates in mm (= machine coordinates of the
// stylus-tip centre, since the program zeroes its work offset and applies the probe's
// length offset); angles in degrees. The writer wraps `cycle_body` in a loop that runs
// `cycles` times with a dwell of `gap_s` between cycles, opens the log before the loop and
// closes it after. Every probing op names (position, point) for the log line
// "PT <cycle> <position> <point> <x> <y> <z>".
//
// With `live_interval` the wait between cycles is decided outside the program while it runs
// (the live TALC loop, seed 004 Ch. 6): instead of the dwell of `gap_s` the program reads a
// number of seconds still to wait and, while it is > 0, dwells min(value, 60 s) and reads it
// again. Fanuc reads common variable #500 (retained; set by a FOCAS cnc_wrmacro writer) into
// #101; LinuxCNC reads HAL analog input 0 with M66 E0 L0 (#5399) into #<_pl_wait>. The writer
// decides when the next cycle is due: it counts the value down or sets it to 0. Nothing
// writing it (0) runs the cycles back to back.
//
// A live loop orders the points by their time, and LinuxCNC's LOG has no clock: with
// `live_interval` the LinuxCNC program also reads HAL analog input 1 (M66 E1 L0) after every
// probing move and logs it as an eighth field, "PT <cycle> <position> <point> <x> <y> <z> <t>":
// the seconds of the clock the inputs logger stamps its samples with (the same time base as
// the inputs' time_s). Fanuc logs its own clock (#3011, #3012) in every program.
#pragma once
#include <string>
#include <vector>

#include "gcode/program.hpp"

namespace probeloop::gcode {

// Where the live interval comes from, and the longest dwell between two reads of it: the
// lag with which the program sees a new value (a Fanuc control may evaluate the read after a
// dwell as the dwell starts, buffering macro statements: then one chunk late).
inline constexpr int kLiveIntervalFanucVariable = 500;   // read into #101 (#100 counts cycles)
inline constexpr int kLiveIntervalLinuxCncInput = 0;     // M66 E0 L0 -> #5399 -> #<_pl_wait>
inline constexpr int kLiveClockLinuxCncInput = 1;        // M66 E1 L0 -> #5399, logged with each point
inline constexpr double kLiveIntervalChunkS = 60.0;

struct ProbeProgram {
  std::string title;
  std::vector<std::string> header;  // comment lines at the top
  int work_offset = 6;              // 1..6 = G54..G59, zeroed by the program
  bool has_a_axis = false;
  bool has_b_axis = false;
  std::string log_file;             // LinuxCNC LOGOPEN name; Fanuc writes to its DPRNT device
  int cycles = 1;
  double gap_s = 0;
  bool live_interval = false;  // the wait between cycles read from outside (above), not gap_s
  std::vector<Op> before_cycles, cycle_body, after_cycles;
};

std::string writeLinuxCnc(const ProbeProgram& p);
std::string writeFanucMacroB(const ProbeProgram& p, int program_number = 1000);

}  // namespace probeloop::gcode
