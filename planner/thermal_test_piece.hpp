// Plans the thermal test piece of seed 004 Ch. 7 (docs/thermal-test-piece.md §5): three
// programs that run back to back on the machine — pre-machining (L2002-L2018), the test
// (L2022-L2047: the reference cuts, then one cutting cycle after every hour of load) and the
// on-machine inspection (L2097-L2101) — the CMM point plan and the plan manifest.
//
// Frames: the part frame (parts/thermal_test_piece.hpp) sits on the C axis with its origin at
// parts::partOriginOnMachine and its axes parallel to the machine's at C = 0. Every program
// zeroes its work offset (G10 L2) and applies each tool's length (G43): program coordinates
// are machine coordinates of the tool tip (stylus-tip centre for the probe). A part-frame
// point p appears at C in the machine at origin + parts::turnedByTable(p, C) (a C' table turns
// clockwise for +C). Every turn of C by a feed (the bands, the C load) is incremental
// (gcode::TurnC), every absolute C word lies in [0, 360) and is given with the tool clear of
// the part, so the programs run alike on a C axis with or without rollover (docs §5).
//
// Contract: InputError for a machine without a C axis (naming its file) or a description the
// programs cannot be made of, naming the key (a ring too small for a tool, a C index off the
// C resolution, inspection points on the mark, a facet whose centre lies in a notch, notches
// that leave no room for the TOP or flank points, Z-path points on the strips the test's facet
// cuts re-cut); SafetyError "<program>: <operation>: <axis/value>" for any
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
  double test_cutting_z_mm = 0;             // the test's one Z (machine tip coordinates)
};

struct TtpFiles {
  std::string pre_machining, test, inspection, log = "ttp_probe.log", cmm_points = "cmm_points.csv";
};
// pre_machining.ngc, thermal_test.ngc, inspection.ngc (LinuxCNC); .nc for Fanuc.
TtpFiles ttpFiles(parts::Dialect dialect);

// `features` (the manifest's features; their order gives the probing positions) and `evaluation` come from the
// loaded parts::TestPiece (planTestPiece hands them over); the ids TOP, FLANK_P, FLANK_N, CYL,
// Z1.., X1_1.. must be among the features.
ThermalTestPiecePlan planThermalTestPiece(const parts::ThermalTestPiece& t, const std::vector<parts::NominalFeature>& features,
                                          const std::vector<parts::EvaluationRule>& evaluation, const parts::Machine& m,
                                          parts::Dialect dialect);
// The same with parts::nominalFeatures(t) and parts::thermalTestPieceEvaluation() (tests that
// vary the description).
ThermalTestPiecePlan planThermalTestPiece(const parts::ThermalTestPiece& t, const parts::Machine& m,
                                          parts::Dialect dialect);

// Walks planned programs (possibly edited after planning) back to back with every check the
// planner makes: the walker's (travel, feeds, tools, spindle, tool-change height) and the
// collision rules of docs §5. SafetyError as planThermalTestPiece.
void checkThermalTestPiecePrograms(const parts::ThermalTestPiece& t, const parts::Machine& m,
                                   const std::vector<NotedProgram>& programs);

// Program text of one planned program in the dialect (Fanuc numbers O2001..O2003).
std::string ttpProgramText(const NotedProgram& p, parts::Dialect dialect);

// C that turns the part-frame direction `part_angle_deg` to the machine direction
// `machine_angle_deg` on this machine (sense of C from the machine file), in [0, 360).
double cToFace(const parts::Machine& m, double part_angle_deg, double machine_angle_deg);

}  // namespace probeloop::planner
