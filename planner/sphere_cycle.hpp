// Plans the sphere-artifact cycle (seed 004 Ch. 5; notes/seed004.md §3.2, §12).
//
// Per cycle: probe in (tool change), then for each C position: retract to the clearance
// plane, index C, and for each point: rapid above its start, protected descent to the start
// (approach distance off the surface), probing move to `overtravel` past the nominal
// contact, log, retract along the approach line, back to the clearance plane; probe out.
//
// Contract: throws SafetyError (naming the position, point and axis) if any target would
// leave the travel, and InputError for inconsistent descriptions. The cycle time is an
// estimate without acceleration: rapids at the rapid feed per axis, probing to the nominal
// contact, C at its maximum speed, tool changes at their stated time.
#pragma once
#include <string>

#include "gcode/probe_program.hpp"
#include "parts/machine.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/sphere_artifact.hpp"

namespace probeloop::planner {

struct CycleTime {
  double tool_change_s = 0, c_index_s = 0, rapid_s = 0, protected_s = 0, probing_s = 0;
  double total() const { return tool_change_s + c_index_s + rapid_s + protected_s + probing_s; }
};

struct SpherePlan {
  gcode::ProbeProgram program;
  parts::PlanManifest manifest;
  CycleTime cycle_time;  // a cycle after the first: its C return, its tool changes only if in the loop
};

struct PlanFiles {
  std::string program_file = "sphere_cycle.ngc";
  std::string log_file = "sphere_probe.log";
};

SpherePlan planSphereCycle(const parts::SphereArtifact& artifact, const parts::Machine& machine,
                           const PlanFiles& files = {});

std::string programText(const SpherePlan& plan, parts::Dialect dialect);

}  // namespace probeloop::planner
