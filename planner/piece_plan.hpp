// The planner's entry for every kind of test piece (docs/architecture.md#how-to-add-a-test-piece, docs/test-pieces.md):
// a loaded TestPiece + machine + dialect -> the program texts, the plan manifest, the other
// files beside it and the summary `probeloop plan` prints.
//
// Contract: sphere_artifact -> the sphere cycle (planner/sphere_cycle.hpp), byte for byte
// what planSphereCycle + programText give; thermal_test_piece -> planner/thermal_test_piece.hpp
// with the piece's own `features` and `evaluation` (into the manifest as they are);
// stepped_workpiece -> planner/stepped_workpiece.hpp for `experiment` (required: one of the
// description's W1..W8; InputError listing them when empty or unknown, and for any other kind
// when given); workpiece -> InputError (a plain workpiece has no planner). Nothing is written here: the
// caller writes programs[].text to programs[].file, files[] and plan.json
// (parts::manifestToJson(manifest)) into one folder. `out_dir` only names that folder in the
// summary's "wrote" line.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/piece_kinds.hpp"

namespace probeloop::planner {

struct PlannedProgram {
  std::string role, file, text;
  double start_s = 0, duration_s = 0;  // planned clock, programs back to back
};

struct TestPiecePlan {
  std::vector<PlannedProgram> programs;
  parts::PlanManifest manifest;
  std::vector<std::pair<std::string, std::string>> files;  // other files beside plan.json: name, content
  std::string summary;  // what `probeloop plan` prints: times, counts, files
};

TestPiecePlan planTestPiece(const parts::TestPiece& piece, const parts::Machine& machine, parts::Dialect dialect,
                            const std::string& out_dir = "", const std::string& experiment = "",
                            const parts::SwCompensation* compensation = nullptr);

}  // namespace probeloop::planner
