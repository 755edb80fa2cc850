// A dialect-neutral machining and probing program: what a planner decides, before any
// dialect. Both writers (LinuxCNC RS274NGC, Fanuc macro B; gcode/writers.cpp) emit it.
//
// Contract: coordinates are program coordinates in mm (= machine coordinates of the tool
// tip or stylus-tip centre, since every program zeroes its work offset with G10 L2 and
// applies each tool's length offset with G43); angles in degrees; feeds in mm/min, and in
// deg/min for a move of C alone (TurnC); times in s. The writers print coordinates to 4 decimals
// and C, feeds and dwells to 3: a planner that times its ops rounds them the same way
// (planner/program_walker.hpp). Every probing op names (position, point) for the log line
// "PT <cycle> <position> <point> <x> <y> <z>" (docs/formats.md#probe-logs).
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
// G0 of a rotary axis alone (indexing at its positioning speed).
struct RotateC { double c_deg; };
struct RotateB { double b_deg; };
struct RotateA { double a_deg; };  // a cradle tilting about X (a table-table A/C machine)
// T.. M6, then G43 H<tool> (length offset on) or G49 (the empty spindle).
struct ToolChange { int tool; bool apply_length_offset; };
// A move near the part that must not touch it: contact stops the program.
struct ProtectedMove { double x, y, z, feed_mm_per_min; };
// The measuring move: stops at contact and logs the trigger point; no contact within the
// move stops the program.
struct ProbeMove { double x, y, z, feed_mm_per_min; int position, point; };
struct Dwell { double seconds; };
// S<rpm> M3 (clockwise seen from the spindle); rpm = 0 is M5.
struct Spindle { double rpm; };
struct Coolant { bool on; };  // M8 / M9 (flood)
// G1: a feed move of X, Y and/or Z (absolute, program coordinates).
struct Feed { std::optional<double> x, y, z; double feed; };
// G91 G1 C<delta_deg> F<feed>, then G90: a feed move of C alone by `delta_deg` (F in deg/min),
// the cut of a tool that stands still while the table turns, or a turn of the table as a
// thermal load. Incremental on purpose: on a table with C rollover (Fanuc ROA, LinuxCNC
// WRAPPED_ROTARY) an absolute G1 C360 or C72000 from C0 is a null move; an incremental one
// turns the commanded amount on every control.
struct TurnC { double delta_deg; double feed_deg_per_min; };
// A counted loop: the ops up to the matching LoopEnd run `count` times. LinuxCNC: o-while
// on the named parameter #<name>; Fanuc: WHILE/DO on a common variable #101, #102 ... by
// nesting depth (#100 is the cycle number of the probe log).
struct LoopBegin { int count; std::string name; };
struct LoopEnd {};

using Op = std::variant<Comment, Rapid, RapidMachineZ, RotateC, ToolChange, ProtectedMove, ProbeMove, Dwell,
                        RotateB, Spindle, Coolant, Feed, TurnC, LoopBegin, LoopEnd, RotateA>;

// Whether every number of the op is finite (a NaN or an infinity must never reach a program).
bool allFinite(const Op& op);

// One program file: header, zeroed work offset, the ops, end (M2 / M30).
struct Program {
  std::string title;
  std::vector<std::string> header;  // comment lines at the top
  int number = 1000;                // Fanuc O-number
  int work_offset = 6;              // 1..6 = G54..G59, zeroed by the program
  bool has_a_axis = false;  // the work offset zeroes the rotary axes the machine has
  bool has_b_axis = false;
  bool has_c_axis = true;  // false: a 3-axis machine (no C word in the work offset)
  // Programs that probe: LinuxCNC LOGOPEN name (Fanuc writes to its DPRNT device); the log's
  // cycle number is 1. Empty: the program opens no log and must not probe.
  std::string log_file;
  std::vector<Op> ops;
};

// std::invalid_argument for an unbalanced loop, loops nested deeper than 3 (Fanuc DO1..3),
// a probe move in a program without a log, or a number that is not finite.
std::string writeLinuxCnc(const Program& p);
std::string writeFanucMacroB(const Program& p);

}  // namespace probeloop::gcode
