// Plans the thermal test piece of seed 004 Ch. 7 (docs/thermal-test-piece.md §5): three
// programs that run back to back on the machine — pre-machining (L2002-L2018), the test
// (L2022-L2047: the reference cuts, then one cutting cycle after every hour of load) and the
// on-machine inspection (L2097-L2101) — the CMM point plan and the plan manifest.
//
// Frames: the part frame (parts/thermal_test_piece.hpp) sits on the C axis with its origin at
// parts::partOriginOnMachine and its axes parallel to the machine's at C = 0. Every program
// zeroes its work offset (G10 L2) and applies each tool's length (G43): program coordinates
// are machine coordinates of the tool tip (stylus-tip centre for the probe). A part-frame
// point p appears at C in the machine at origin + Rz(s C) p, s = -1 for a table that turns
// clockwise for +C (C'), +1 otherwise.
//
// Contract: InputError for a machine without a C axis (naming its file) or a description the
// programs cannot be made of (a ring too small for a tool, a C index off the C resolution,
// inspection points on the mark); SafetyError "<program>: <operation>: <axis/value>" for any
// target outside the travel, a feed above the machine's maxima, a rotary feed above C's
// max_turning_speed, a tool or probe that would touch the part outside an intended cut, or a
// C turn with anything inside the part's swept circle — all checked by walking the programs
// with the simulator's clock (planner/program_walker.hpp) before any text exists.
#pragma once
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/thermal_test_piece.hpp"
#include "planner/program_walker.hpp"

namespace probeloop::planner {

// The C load of one wait (docs/thermal-test-piece.md §2): pairs of C feed moves of +turns and
// back to 0 at rpm, then a dwell; a hold is a dwell only.
struct TtpLoad {
  int before_cycle = 0;
  std::string phase;
  double requested_rpm = 0, rpm = 0;  // rpm = min(requested, C's max_turning_speed)
  int turns_per_move = 0, pairs = 0;
  double move_s = 0, dwell_s = 0;
};

struct ThermalTestPiecePlan {
  // pre_machining, test, inspection: file, role, program, what each op does.
  std::vector<NotedProgram> programs;
  std::vector<double> start_s, duration_s;  // per program, on the planned clock
  std::vector<WalkTimes> times;             // per program
  parts::PlanManifest manifest;
  std::string cmm_points_csv;               // cmm_points.csv
  std::vector<TtpLoad> loads;               // one per wait
  double cycle_s_min = 0, cycle_s_max = 0;  // durations of the cutting cycles
  double top_z_mm = 0;                      // machine Z of the part's finished top (C = 0)
  double test_cutting_z_mm = 0;             // the test's one Z (machine tip coordinates)
};

struct TtpFiles {
  std::string pre_machining, test, inspection, log = "ttp_probe.log", cmm_points = "cmm_points.csv";
};
// pre_machining.ngc, thermal_test.ngc, inspection.ngc (LinuxCNC); .nc for Fanuc.
TtpFiles ttpFiles(parts::Dialect dialect);

ThermalTestPiecePlan planThermalTestPiece(const parts::ThermalTestPiece& t, const parts::Machine& m,
                                          parts::Dialect dialect);

// Program text of one planned program in the dialect (Fanuc numbers O2001..O2003).
std::string ttpProgramText(const NotedProgram& p, parts::Dialect dialect);

// C that turns the part-frame direction `part_angle_deg` to the machine direction
// `machine_angle_deg` on this machine (sense of C from the machine file), in [0, 360).
double cToFace(const parts::Machine& m, double part_angle_deg, double machine_angle_deg);

}  // namespace probeloop::planner
