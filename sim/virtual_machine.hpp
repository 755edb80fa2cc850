// The virtual machine: runs an emitted program (gcode::Interpreter) on a machine whose
// physical error effects are known (MachineTruth) with a sphere artifact on its C table,
// and writes what the controller would: its log, plus the canonical points CSV, the
// inputs CSV and the truth behind every probe event.
//
// Physics (docs/simulator.md; machining and the CMM stage in §2.4):
// - clock: rapids per axis at the rapid feed (C and B at their maximum speed), feeds along
//   the XYZ path, dwells, tool changes at the machine's tool-change time; no acceleration;
// - the stylus tip (sphere of radius r_tip) = gauge line - tool length + tool-side errors
//   (linear-axis polynomials, squareness, thermal tool drift, ATC step);
// - the artifact (sphere on a stem on the table) sits where the C axis with its location
//   errors (static + keyframes + thermal) and the artifact's expansion put it;
// - a probe move stops where the tip meets the sphere, plus pre-travel (lobed, by
//   direction) and feed x trigger delay; the reported position carries repeatability noise
//   and is quantised to the axes' resolution;
// - a move whose tip would touch the stem, the table or (for a non-probing move) the
//   sphere is a SafetyError with the program line; so is leaving the travel.
//
// Contract: same program, machine, part, truth and seed -> byte-identical outputs.
#pragma once
#include <cstdint>
#include <string>

#include "gcode/interpreter.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"
#include "parts/workpiece.hpp"
#include "sim/cmm_stage.hpp"
#include "sim/machine_truth.hpp"

namespace probeloop::sim {

struct SimulationOutputs {
  std::string log_name;    // as the program opened it (LinuxCNC LOGOPEN) or "dprnt.txt"
  std::string log_text;    // the controller log
  std::string points_csv;  // canonical points CSV (docs/formats.md)
  std::string inputs_csv;  // temperatures and machine state over time
  std::string truth_json;  // injected error values per probe event and per cycle
  std::string cuts_json;   // workpiece: the surfaces actually cut (swept volumes), forces
  std::string cmm_csv;     // workpiece with CMM points: the CMM export
  std::string trace_csv;   // with SimulationPart::trace: every motion, dwell and tool change
  double end_time_s = 0;
  long probe_events = 0;
  long blocks = 0;
};

// What stands on the table: a sphere artifact or a workpiece (exactly one).
struct SimulationPart {
  const parts::SphereArtifact* artifact = nullptr;
  const parts::Workpiece* workpiece = nullptr;
  std::vector<CmmPoint> cmm_points;  // workpiece: measured on the CMM after the program
  std::string cmm_points_file = "CMM points";  // for error messages
  bool trace = false;                // also write the motion trace
};

SimulationOutputs simulateProgram(const std::string& program_file, const std::string& program_text,
                                  const parts::Machine& machine, const SimulationPart& part,
                                  const MachineTruth& truth, std::uint64_t seed);

inline SimulationOutputs simulateProgram(const std::string& program_file, const std::string& program_text,
                                         const parts::Machine& machine, const parts::SphereArtifact& artifact,
                                         const MachineTruth& truth, std::uint64_t seed) {
  SimulationPart part;
  part.artifact = &artifact;
  return simulateProgram(program_file, program_text, machine, part, truth, seed);
}

}  // namespace probeloop::sim
