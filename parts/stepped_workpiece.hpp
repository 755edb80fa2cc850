// The stepped workpiece of seed 000 (Yaqoob, MSc thesis, Sabanci University 2017): the
// description (YAML, kind: stepped_workpiece; docs/formats.md#stepped-workpiece), the
// geometry it implies (the top and, per step, four walls and a floor) and the experiments
// W1-W8 of Table 4.1 as data (notes/seed000.md §1-§3). Issue 14, first part: the planner,
// the simulation and the error separation build on this.
//
// Part frame (notes §1.2, derived from Tables 5.1/5.3: the drawing, Fig. 3.2, is lost): origin
// at a corner of the top step in its top face, X and Y along its walls, Z up. Every step is a
// square centred on (c, c), c = half the top step's size (15 mm for the shipped 30 mm); step
// k = 1..4 stands from the floor of step k-1 (the top face for k = 1) down to its own floor
// at depth floor_depth[k]. Lengths in mm, feeds in mm/min, speeds in rpm, times in s.
//
// Features (parts/feature.hpp), ids fixed by the step and the side:
// - TOP: the top face of step 1 (the Z reference of the 9-point top plane, L1124);
// - S<k>_XP, S<k>_XN, S<k>_YP, S<k>_YN: the walls of step k with outward normals +X, -X, +Y,
//   -Y (group S<k>, the X width is XP - XN, the Y width YP - YN);
// - S<k>_F: the floor around step k at -floor_depth[k], a square ring out to the next step
//   (or the blank's edge for the last); its nominal plane is the ring's mid-line square.
#pragma once
#include <string>
#include <vector>

#include "parts/feature.hpp"
#include "parts/machine.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::parts {

struct SwStep {
  double size_mm = 0;         // outer X and Y of the square (Table 5.3)
  double floor_depth_mm = 0;  // below the top face (Table 5.3 "Z1", notes §1.2)
};

// One step's cutting conditions in one experiment (Table 4.1).
struct SwCutConditions {
  double feed_xy_mm_per_min = 0, feed_z_mm_per_min = 0;
  double spindle_speed_rpm = 0;
};

// One experiment W1..W8 (Tables 3.1 and 4.1): per-step conditions and how the tool gets from
// one wall to the next.
struct SwExperiment {
  std::string id;          // W1 ... W8
  std::string purpose;     // Table 3.1's "expected error changes", in words
  // non_cutting: lift and move between walls at transition_feed (W1, W3, W4, W6-W8);
  // fast: the same at a high transition feed (W2: 1200 mm/min in Table 3.1, 2400 in Eqs.
  // 3.11-3.14 and L1708, unresolved in the source: the value is the description's);
  // continuous: one path around each step at its cutting feed (W5, L896-900).
  std::string transition;
  double transition_feed_mm_per_min = 0;  // non_cutting and fast; 0 for continuous
  double tool_runout_mm = 0;              // dial indicator (Table 4.1), compensated in the path (L973)
  bool alternative_sizes = false;         // W2/W5 were cut to 29/44/79/99 (Tables 5.6/5.7)
  std::vector<SwCutConditions> steps;     // one per step, in step order
};

// How the piece is probed, on the machine and on the CMM (Sec. 3.4, L757-800; notes §3): per
// wall 3 positions x 2 Z levels, per floor and on the top 9 points, approach along the
// outward normal. The layout within a face is ours (Fig. 3.8 is lost): docs/stepped-workpiece.md.
struct SwProbing {
  std::vector<double> wall_positions;  // along the wall, fractions of its half length (-1..1)
  std::vector<double> wall_levels;     // below the wall's top edge, fractions of its height (0..1)
  double top_grid = 0;                 // the top's 3 x 3 grid at -g, 0, +g of its half size
  double tip_diameter_mm = 0;          // the stylus ball: every point keeps its radius + 0.5 mm from the face's edges
  double feed_mm_per_min = 0, positioning_feed_mm_per_min = 0;
  double approach_mm = 0, overtravel_mm = 0, clearance_mm = 0;
  double repeatability_mm = 0;         // +-2 um on W8 step 3 (L769), read as 2 sigma
  // Step 3's wall points are probed this many times in all (L769: the repeatability came from
  // random repeats on W8 step 3): 1 = no repeat.
  int step3_wall_passes = 1;
};

// How the programs cut (the thesis gives none of it, notes §2.2: our choices, stated in
// docs/stepped-workpiece.md): roughing from the blank to the finishing margin, the stepover
// of roughing contours and floor passes, the lead past a wall's roughed end before a
// non-cutting transition, the clearance plane above the blank.
struct SwMachining {
  double roughing_spindle_rpm = 0, roughing_feed_xy_mm_per_min = 0;
  double roughing_depth_per_level_mm = 0;
  double stepover = 0;  // of the tool's diameter
  double lead_mm = 0;
  double clearance_mm = 0;
};

// One planned contact on a face: the nominal point on the face, the outward normal (the probe
// approaches against it), the feature and its 1-based number within the feature.
struct SwProbePoint {
  std::string feature;
  int point = 0;
  Eigen::Vector3d contact_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

struct SteppedWorkpiece {
  std::string file, name;
  // Blank (our choice: the source gives none) and fixture (a circular stainless steel plate
  // with threaded holes, turned on both faces, L719-733; its size is our choice).
  double blank_x_mm = 0, blank_y_mm = 0, blank_height_mm = 0;
  WorkpieceMaterial material;
  int clamp_holes = 0;                 // drilled at full diameter in roughing (L697)
  double clamp_hole_diameter_mm = 0;
  double clamp_hole_inset_mm = 0;      // from the blank's corners along both diagonals' axes
  double fixture_diameter_mm = 0, fixture_height_mm = 0;
  std::vector<SwStep> steps;           // top (1) to bottom; sizes grow, depths grow
  std::vector<double> alternative_sizes_mm;  // the W2/W5 set (29/44/79/99)
  double finishing_margin_mm = 0;      // left on every face by roughing (L695)
  std::vector<CuttingTool> tools;
  int finishing_tool = 0;
  // The procedure (Sec. 4.1, notes §2.3): alignment, machine off before, warm-up after each
  // step (spindle idle at the experiment's speed, then the axis manoeuvre that replays the
  // path without cutting), machine off before probing.
  double alignment_tolerance_mm = 0;   // walls parallel to X/Y within 5 um (L968)
  double off_before_s = 0, off_after_s = 0;
  double warm_up_idle_s = 0;           // 30 min (L992)
  bool warm_up_axis_manoeuvre = false; // L739-741
  std::vector<SwExperiment> experiments;
  SwProbing probing;
  SwMachining machining;
  CmmSpec cmm;

  const SwExperiment* experiment(const std::string& id) const;
  // The step sizes an experiment cuts (the standard set or the alternative one).
  std::vector<double> sizesFor(const SwExperiment& e) const;
  double centreXY() const { return steps.front().size_mm / 2; }
  // The blank's top in the part frame: the top face plus the finishing margin (roughing leaves
  // the margin on every face, the top included, L695; finishing faces the top at z 0).
  double blankTopZ() const { return finishing_margin_mm; }
  const CuttingTool& finishingTool() const;
};

SteppedWorkpiece loadSteppedWorkpiece(const std::string& path);

// TOP, then per step its four walls and its floor (see above), for the given step sizes
// (default: the description's own).
std::vector<NominalFeature> nominalFeatures(const SteppedWorkpiece& w, const std::vector<double>& sizes_mm = {});

// Every planned contact for the given features (nominalFeatures of one size set), in the
// features' order: TOP 9 (3 x 3 grid), per wall positions x levels (level by level, along the
// wall in the direction of its u), per floor 9 on the ring's mid-line: two per side at half
// the side's half length either way of its middle, and the middle of the +X side. InputError
// when a point would lie closer to a face's edge than the stylus ball's radius + 0.5 mm.
std::vector<SwProbePoint> probePoints(const SteppedWorkpiece& w, const std::vector<NominalFeature>& features);

// The blank on its fixture as the simulator machines it: a box centred on (c, c) from the top
// face down, clamp holes through it, the fixture below as a collision body.
Workpiece steppedWorkpieceStock(const SteppedWorkpiece& w);

// The part frame's origin in machine (tip) coordinates: the steps' centre over the middle of
// the X/Y travel ("position errors at the centre of the worktable", L2030), the blank on its
// fixture on the table surface (the C axis's centre and table on a machine with a rotary
// table, left at C = 0).
Eigen::Vector3d steppedWorkpieceOrigin(const SteppedWorkpiece& w, const Machine& m);

// Centres of the clamp holes (part frame), near the blank's corners.
std::vector<Eigen::Vector2d> clampHoleCentres(const SteppedWorkpiece& w);

}  // namespace probeloop::parts
