// What `probeloop simulate` reads besides the programs and descriptions, as the simulator
// takes it.
//
// Contract:
// - loadCmmRequest: the CMM's part of a run from one file: a CSV of points to measure
//   (cmm_stage.hpp), or a QIF 3.0 plan or a DMIS program, whose planned points are measured
//   and answered in both QIF and DMIS (SimulationPart::cmm_plan). Errors name the file. A DMIS
//   program is read strictly (it drives the CMM): what the lenient reader of results would
//   warn about (a missing ENDFIL or ENDMES, statements after ENDFIL, a label defined again) is
//   refused at its line.
// - scheduleFromManifest: each program starts at its planned time (the manifest's
//   programs[].start_s, matched by file name), the machine off in between (the stepped
//   workpiece's 3 h waits). A program the manifest does not plan is an InputError naming the
//   manifest and the programs it does plan.
#pragma once
#include <string>
#include <vector>

#include "sim/virtual_machine.hpp"

namespace probeloop::sim {

void loadCmmRequest(SimulationPart& part, const std::string& file);
void scheduleFromManifest(std::vector<ProgramSource>& programs, const std::string& manifest_file);

}  // namespace probeloop::sim
