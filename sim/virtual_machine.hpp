// The virtual machine: runs emitted programs (gcode::Interpreter) on a machine whose
// physical error effects are known (MachineTruth) with a sphere artifact or a workpiece on
// its table, and writes what the controller would: its logs, plus the canonical points CSV,
// the inputs CSV, the truth behind every probe event and every cut surface, the cuts and
// the CMM's measurement.
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
//   sphere is a SafetyError with the program line; so is leaving the travel;
// - a workpiece (parts::Workpiece: a box or cylindrical blank, holes, obstacles) sits in its
//   part frame, whose origin is `frame_origin_mm` in machine tip coordinates at C = 0; cuts
//   with flat end mills (linear, or by turning C alone) remove material exactly
//   (sim/material_removal.hpp); obstacles may not be touched; the table may turn with the
//   tool below the top of the stock only while the tool is clear of its material (0.5 mm),
//   and X/Y/Z may move together with C only above the top (below it: not modelled); a warm
//   support (`support_height`, the part's alloy) lifts the part by alpha dT support_height;
// - a feed move of C alone reads F in deg/min and is limited by the axis's turning speed;
//   C's real speed in such moves heats the C-axis node and is inputs.csv's c_rpm (rapid
//   indexing is not counted: < 1 s per quarter turn, and the sphere campaigns' outputs stay
//   as they were);
// - several programs run one after the other on the same machine (clock, thermal state,
//   stock, tool, position carry over; each program has its own interpreter, so modal state
//   and work offsets are each program's own, and M2/M30 of one stops spindle and coolant
//   before the next).
//
// Contract: same programs, machine, part, truth and seed -> byte-identical outputs; one
// program through simulatePrograms gives what simulateProgram gives.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gcode/interpreter.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"
#include "parts/piece_kinds.hpp"
#include "parts/workpiece.hpp"
#include "sim/cmm_stage.hpp"
#include "sim/live_link.hpp"
#include "sim/machine_truth.hpp"

namespace probeloop::sim {

struct LogOutput {
  std::string name;  // file name: the LinuxCNC LOGOPEN name, or dprnt.txt (Fanuc)
  std::string text;
};

struct SimulationOutputs {
  std::string log_name;    // the first log: as the program opened it (LinuxCNC LOGOPEN) or "dprnt.txt"
  std::string log_text;    // the controller log
  std::vector<LogOutput> logs;  // every log of the run (one program: just the one above; several: none if none logged)
  std::string points_csv;  // canonical points CSV (docs/formats.md)
  std::string inputs_csv;  // temperatures and machine state over time
  std::string truth_json;  // injected error values per probe event and per cycle; a thermal test piece's as-cut truth
  std::string cuts_json;   // workpiece: the surfaces actually cut (swept volumes), forces
  std::string cmm_csv;     // workpiece with CMM points: the CMM export
  std::string cmm_qif;     // ... planned in QIF or DMIS: the CMM's QIF 3.0 Results
  std::string cmm_dmo;     // ... and its DMIS output
  std::string trace_csv;   // with SimulationPart::trace: every motion, dwell and tool change
  double end_time_s = 0;
  long probe_events = 0;
  long blocks = 0;
};

// What stands on the table: a sphere artifact, a workpiece, or a test piece (exactly one).
// A test piece (parts/piece_kinds.hpp) stands as its kind says: a sphere artifact as the
// artifact; a machined one (thermal test piece, plain workpiece) as its stock placed on the
// machine by placeOnMachine; for a thermal test piece truth.json then also holds the as-cut
// surfaces, the datum frame and E_X ... E_TTP per cutting cycle (docs/simulator.md §3.1).
struct SimulationPart {
  const parts::SphereArtifact* artifact = nullptr;
  const parts::Workpiece* workpiece = nullptr;
  const parts::TestPiece* test_piece = nullptr;
  std::vector<CmmPoint> cmm_points;  // workpiece: measured on the CMM after the program
  std::string cmm_points_file = "CMM points";  // for error messages
  std::optional<interop::CmmDocument> cmm_plan;  // the points came as a QIF plan or a DMIS program: answer in both
  bool trace = false;                // also write the motion trace
  // A live loop on the controller side (sim/live_link.hpp): logs and samples go to it as they
  // are written, its offsets move the axes, programs read its values. Not owned.
  LiveLink* live = nullptr;
  // Stop at the first block at or after this time (the machine switched off there): a
  // campaign whose program would run longer, as a live loop's longer intervals make it.
  std::optional<double> until_s;
};

SimulationOutputs simulateProgram(const std::string& program_file, const std::string& program_text,
                                  const parts::Machine& machine, const SimulationPart& part,
                                  const MachineTruth& truth, std::uint64_t seed);

// Several programs back to back on one machine (pre-machining, test, inspection). Logs:
// each LinuxCNC program's LOGOPEN file (a name an earlier program of the run used is
// refused: LinuxCNC would overwrite it; a program that logs without LOGOPEN writes
// <program stem>.log), one dprnt.txt for all Fanuc DPRNT output (as the DPRNT device
// collects it). points.csv and truth.json hold the probe events of all programs; trace.csv
// gets a last column `program` (only when there is more than one program, so a single
// program's trace stays as it was). Errors name the program file and line.
struct ProgramSource {
  std::string file;  // its name decides the dialect (.ngc LinuxCNC, .nc/.tap Fanuc, else the machine's)
  std::string text;
  // Planned start on the run's clock (the plan manifest's programs[].start_s): when the
  // previous program ended earlier, the machine is off until then (MachineTruth's thermal
  // network cools); when later, the program starts at once. Absent: back to back.
  std::optional<double> start_s = std::nullopt;
};
SimulationOutputs simulatePrograms(const std::vector<ProgramSource>& programs, const parts::Machine& machine,
                                   const SimulationPart& part, const MachineTruth& truth, std::uint64_t seed);

// The workpiece a machined test piece is on this machine: its stock with the part frame's
// origin where the piece stands (thermal test piece: on the C axis, adapter + washers +
// finished height above the table, parts::partOriginOnMachine); a plain workpiece as it is.
// InputError for a test piece that is not machined (sphere artifact) or a machine without
// the C axis the piece needs.
parts::Workpiece placeOnMachine(const parts::TestPiece& piece, const parts::Machine& machine);

inline SimulationOutputs simulateProgram(const std::string& program_file, const std::string& program_text,
                                         const parts::Machine& machine, const parts::SphereArtifact& artifact,
                                         const MachineTruth& truth, std::uint64_t seed) {
  SimulationPart part;
  part.artifact = &artifact;
  return simulateProgram(program_file, program_text, machine, part, truth, seed);
}

}  // namespace probeloop::sim
