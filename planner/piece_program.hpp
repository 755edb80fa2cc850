// What the builders of machined test pieces (thermal_test_piece.hpp, stepped_workpiece.hpp)
// write and walk alike: the programs' file extension and text in the dialect, an op's note, the
// header lines of a program and of a tool, and one program walked on the planned clock (each
// op's start and end, the probe points' times in their cycle, the program's start, duration
// and share of the times). What they fill alike in the manifest is in piece_manifest.hpp.
#pragma once
#include <string>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/workpiece.hpp"
#include "planner/program_walker.hpp"

namespace probeloop::planner {

// ".ngc" (LinuxCNC) or ".nc" (Fanuc).
std::string programExtension(parts::Dialect dialect);

// A planned program's text in the dialect.
std::string programText(const NotedProgram& p, parts::Dialect dialect);

// The note of an op: where it is, whether it is an intended cut and the manifest cut it makes.
OpNote opNote(const std::string& where, bool cut, int cut_index);

// The first header lines of a program: the machine, `part` (the part and its frame) and the
// coordinates (the zeroed work offset, tool tips with G43).
std::vector<std::string> programHeader(const parts::Machine& m, const std::string& part);

// A tool's header line: "T<number>: <name or kind>, d = <diameter> mm, length <length> mm".
std::string toolLine(int number, const parts::CuttingTool& tool);

// How a cut of several ops is timed: by its last op alone, or from its first op's start to its
// last op's end.
enum class CutTimes { LastOp, FirstToLastOp };

// The planned clock of one walked program: each op's start and end (the offset added).
struct WalkedOps {
  std::vector<double> before, after;
};

// Walks `p` on `walker` (its checks set by the caller), `offset_s` (the procedure's waits,
// machine off) after the walker's clock: sets the manifest cuts' start and end (`cuts`) and
// each probe point's time in its cycle (from the program's start), and appends the program's
// start (offset added), duration and share of the walker's times (since `total`, which moves
// on) to the plan's lists.
WalkedOps walkProgram(ProgramWalker& walker, const NotedProgram& p, double offset_s, CutTimes cuts,
                      parts::PlanManifest& man, std::vector<double>& start_s, std::vector<double>& duration_s,
                      std::vector<WalkTimes>& times, WalkTimes& total);

}  // namespace probeloop::planner
