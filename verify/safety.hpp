// The safety verifier: G-code programs checked against the machine and the part, from the
// program text alone (docs/reliability.md#safety-verifier).
//
// Contract:
// - Input: program texts (run back to back on one machine: position, tool, material carry
//   over), the machine description, the test-piece description. Never the planner's
//   operations: the programs are read by the project's interpreter (gcode/interpreter.hpp),
//   which talks to a checking machine instead of a simulated one. Independent of planner/
//   and sim/ (its own geometry, its own material model).
// - Output: every finding with the program's file:line, a rule, what happened, where (the
//   stylus-tip centre or tool tip in machine coordinates, mm) and the limit it broke.
//   No finding = the programs are safe by these rules. A program the interpreter cannot read
//   (a word it does not model, an unknown tool) is an InputError naming file:line, never a
//   finding.
// - Rules (names as they appear in reports):
//   travel                 the gauge line outside X/Y/Z travel, A/B/C outside a limited rotary travel;
//   collision              a rapid or feed move (and a probe move before its tip touches) in which
//                          the tool (cutter, shank, holder) or the probe (tip ball, stylus shaft,
//                          body) meets the artifact (sphere, stem), the stock or what remains of
//                          it after the programs' own cuts, an obstacle (clamp, adapter, washer)
//                          or the table; a cutter's fluted length may enter material only in a
//                          feed move with the spindle on (it cuts);
//   probe-unprotected      a probe move (G38.2/G38.3, G31) after which the program does not stop
//                          when the outcome is the unexpected one (a positioning move that
//                          touches, a measuring move that does not);
//   probe-unbounded        a measuring move that goes on more than the probe's max_overtravel
//                          past the contact;
//   positioning-unprotected a rapid or feed move with the probe in the spindle that, below the
//                          clearance plane, brings the probe closer to the part (not a retreat);
//   rotary-below-clearance a C move on the level table while the tool or probe is below the
//                          clearance plane and inside the envelope the turning part sweeps (a cut
//                          by a feed move of C with the spindle on is a cut, not a positioning
//                          move); an A or B move below the plane when the machine does not
//                          locate the tilting axis's line;
//   tilt-swing             an A or B move (or a C move on the tilted table) during which what the
//                          table carries, or the table (a disc), comes within 2 mm of the tool or
//                          probe, or the probe is below the tilted table plane, at some angle
//                          between the start and the end (issue 33);
//   spindle-with-probe     M3/M4 with the probe in the spindle;
//   program-stops          the program itself stops (alarm, ABORT, G38.2 without contact) on the
//                          nominal part: a protected move that touches, a probing move that
//                          meets nothing.
// - Geometry: every tool is vertical and rotationally symmetric: vertical cylinders and the
//   stylus ball. Material is a height field of `cell_mm` cells in the table frame; a tool
//   within `tolerance_mm` of material counts as clear. With the table tilted (a machine that
//   locates its A or B axis line) every body is placed by the pose, the stock as its bounding
//   cylinder, the table as a disc (docs/reliability.md#geometry-modelled).
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"

namespace probeloop::verify {

struct Finding {
  std::string file;
  int line = 0;
  std::string rule;
  std::string what;
  Eigen::Vector3d where_mm = Eigen::Vector3d::Zero();  // tip (tool tip or stylus-tip centre), machine coordinates
  std::string limit;
};

struct ProgramText {
  std::string file;  // as reported; its extension decides the dialect (.ngc LinuxCNC, .nc/.tap Fanuc)
  std::string text;
};

struct Options {
  double cell_mm = 0.5;
  double tolerance_mm = 0.1;
  // Dialect of a program whose extension does not say: the machine's.
};

struct Report {
  std::vector<std::string> programs;
  std::vector<Finding> findings;
  std::string model;  // what was modelled, one sentence per body
  bool safe() const { return findings.empty(); }
};

Report checkPrograms(const std::vector<ProgramText>& programs, const parts::Machine& machine,
                     const parts::TestPiece& piece, const Options& options = {});

// One line per finding: "file:line: rule: what, at X.. Y.. Z.. (mm), limit".
std::string reportText(const Report& r);
std::string reportJson(const Report& r);

}  // namespace probeloop::verify
