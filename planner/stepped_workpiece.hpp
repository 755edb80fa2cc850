// Plans one experiment (W1-W8, Table 4.1) on the stepped workpiece of seed 000
// (docs/stepped-workpiece.md §4): three programs that run on the machine with the
// procedure's waits between them — roughing from the blank to the finishing margin, the
// finishing of the four steps at the experiment's conditions with the warm-up between steps
// (Sec. 4.1, L988-996), and the on-machine probing after the cool-down (L1040) — the CMM point
// plan and the plan manifest, whose per-step cut times are the thesis's 'Temp state'.
//
// Frames: part frame as parts/stepped_workpiece.hpp, origin at parts::steppedWorkpieceOrigin;
// every program zeroes its work offset (G10 L2) and applies each tool's length (G43), so
// program coordinates are machine coordinates of the tool tip (stylus-ball centre).
//
// Paths (our choices, the thesis gives none): square contours about the steps' centre, the
// tool moving clockwise seen from above (climb milling with M3); roughing level by level from
// outside the blank inward, leaving the margin on every face; finishing of step k: (step 1:
// the top, raster along X from outside the top), the floor ring from outside in at its depth
// (plunge at feed_z, contours at feed_xy), then the four walls in one full-height pass each,
// joined by the experiment's transition — non_cutting and fast: each wall is cut past both
// roughed ends by the lead and the tool moves to the next wall's start at the transition feed,
// clear of the walls, its end face at the floor's depth; continuous: one closed contour at the cutting feed. The warm-up before
// step k + 1: spindle idle at that step's speed for procedure.warm_up.spindle_idle, then
// (axis_manoeuvre) that step's path replayed in the air at the clearance plane.
//
// Contract: InputError (file, key, value) before any text exists for an unknown experiment, a
// feed above the machine's axes, a tool or probe that cannot reach the deepest cut or clear
// the part within the Z travel, a tool-change height that leaves a tool below the clearance
// plane; SafetyError "<program>: <operation>: ..." for a target
// outside the travel, a tool or stylus that would touch material outside an intended cut (the
// material as roughing and finishing leave it, face by face, and the fixture; straight-up
// moves are exempt: the material only narrows upward), a G0 of several axes below the top of
// the part — all checked by walking the programs with the simulator's clock
// (planner/program_walker.hpp).
#pragma once
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/stepped_workpiece.hpp"
#include "parts/sw_compensation.hpp"
#include "planner/program_walker.hpp"

namespace probeloop::planner {

// One step of the experiment as planned: its conditions and when it is cut.
struct SwPlannedStep {
  int step = 0;
  parts::SwCutConditions conditions;
  double start_s = 0, end_s = 0;       // first cut to the last wall cut (planned clock)
  double walls_mid_s = 0;              // mid-time of its four wall cuts
  double temp_state_min = 0;           // walls_mid_s from the start of step 1's first cut, min (the thesis's T)
};

struct SteppedWorkpiecePlan {
  std::string experiment;
  std::vector<double> sizes_mm;               // the step sizes this experiment cuts
  std::vector<NotedProgram> programs;         // roughing, finishing, probing
  std::vector<double> start_s, duration_s;    // per program; the procedure's waits between them
  std::vector<WalkTimes> times;               // per program
  std::vector<SwPlannedStep> steps;
  parts::PlanManifest manifest;
  std::string cmm_points_csv;
};

struct SwFiles {
  std::string roughing, finishing, probing, log = "sw_probe.log", cmm_points = "cmm_points.csv";
};
SwFiles swFiles(parts::Dialect dialect);  // roughing.ngc, finishing.ngc, probing.ngc (LinuxCNC); .nc for Fanuc

// compensation (optional, `plan --compensate`): the predicted errors of this experiment's walls
// and floors (parts/sw_compensation.hpp), taken out of the finishing path; refused when it is
// for another experiment or another number of steps. The manifest records it.
SteppedWorkpiecePlan planSteppedWorkpiece(const parts::SteppedWorkpiece& w, const std::string& experiment,
                                          const parts::Machine& m, parts::Dialect dialect,
                                          const parts::SwCompensation* compensation = nullptr);

// Program text of one planned program in the dialect (Fanuc numbers O3001..O3003).
std::string swProgramText(const NotedProgram& p, parts::Dialect dialect);

}  // namespace probeloop::planner
