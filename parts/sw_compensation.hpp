// The compensation of a stepped workpiece (seed 000 Ch. 6: "step wise compensations", Table
// 6.1): per step the error each wall and the floor is predicted to have, which `probeloop plan
// --compensate` takes out of the finishing path. `probeloop evaluate` writes it
// (compensation.json) from the separated components; a user may write one by hand.
//
// File (JSON): {"format": "probeloop-compensation", "kind": "stepped_workpiece",
//   "experiment": "W8", "steps": [{"step": 1, "wall_um": {"XP": .., "XN": .., "YP": .., "YN": ..},
//   "floor_um": .., optional "U_wall_um": {...}, "U_floor_um": ..}, ...], optional "basis"}.
// wall_um: the wall's predicted error along its outward normal (+ = the wall lies outside
// nominal; the planner moves the wall's path inward by it). floor_um: the floor's predicted
// depth error (+ = too deep; the planner raises the step's path by it).
//
// Contract: loadSwCompensation throws InputError naming the file and the key for a wrong
// format or kind, a missing or non-finite value, a step out of order, or an offset beyond
// +-0.5 mm (a compensation, not a redesign).
#pragma once
#include <array>
#include <string>
#include <vector>

namespace probeloop::parts {

struct SwStepCompensation {
  int step = 0;
  std::array<double, 4> wall_um{};    // XP, XN, YP, YN
  double floor_um = 0;
  std::array<double, 4> U_wall_um{};  // 0 when not given
  double U_floor_um = 0;
};

struct SwCompensation {
  std::string file, experiment, basis;
  std::vector<SwStepCompensation> steps;
};

inline constexpr const char* kSwWalls[4] = {"XP", "XN", "YP", "YN"};

SwCompensation loadSwCompensation(const std::string& path);
// The checks the loader makes, for a compensation built in memory (a prediction): finite
// offsets within +-500 um, steps in order; InputError naming c.file and the key.
void validateSwCompensation(const SwCompensation& c);
std::string swCompensationJson(const SwCompensation& c);

}  // namespace probeloop::parts
