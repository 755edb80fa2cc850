// Location errors of every rotary axis (the tilting A or B axis and the C table on it) from
// sphere centres probed at level and tilted positions: least squares on the machine's
// kinematic chain (parts/machine_chain.hpp), a GUM budget per parameter (issue 33).
//
// Two estimates per complete cycle:
// - absolute (a geometric calibration, as Heidenhain KinematicsOpt or Renishaw AxiSet do):
//   the location errors now, with the sphere's placement on the table (3 unknowns, um)
//   estimated beside them. EC0C, EZ0T and ER0T are left out: a zero of C, a table height and
//   a table radius are the same as a sphere placed elsewhere (the identifiability report says
//   so), and they are relative quantities in seed 004 anyway.
// - relative to the reference cycle (the thermal drift, as seed 004 Ch. 5): the change of
//   seed 004's seven C errors and of the tilting axis's four since the reference cycle;
//   the placement cancels. With level positions only, this is seed 004's least squares
//   (evaluate/location_errors.hpp) to 1e-9 um.
//
// Conventions: C's errors as everywhere (docs/conventions.md: EX0C, EY0C and the tilts'
// pivot at the sphere centre's height; EC0C positive = the table turned clockwise seen from
// +Z). The tilting axis's errors are ISO 230-7's, right-hand about +X +Y +Z at its axis line:
// for B EX0B, EZ0B (um), EA0B, EC0B (urad); for A EY0A, EZ0A, EB0A, EC0A. Its zero (EB0B,
// EA0A) is not identifiable from sphere centres: it equals a tilt of C with a shift of C.
//
// Contract: GeometryError when the plan's positions cannot identify the parameters (the
// sentence names the inseparable combination); InputError when the plan's nominal centres do
// not follow its machine chain.
#pragma once
#include <string>
#include <vector>

#include "evaluate/sphere_campaign.hpp"
#include "geometry/identifiability.hpp"
#include "parts/plan_manifest.hpp"
#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

struct RotaryCycleCalibration {
  int cycle = 0;
  double time_s = 0;
  std::vector<uncertainty::Budget> absolute;   // RotaryCalibration::absolute_names order
  std::vector<uncertainty::Budget> placement;  // the sphere's placement dx, dy, dz (um, table frame at C = 0)
  std::vector<uncertainty::Budget> relative;   // relative_names order; empty for the reference cycle's zeros
  double residual_rms_um = 0;                  // of the absolute fit
  int dof = 0;
};

struct RotaryCalibration {
  std::string tilt_axis;                                   // "B" or "A"
  std::vector<std::string> absolute_names, relative_names;  // with units: "EX0B_um", "EA0B_urad"
  int reference_cycle = 0;
  std::vector<int> positions;                              // the manifest positions used
  std::vector<RotaryCycleCalibration> cycles;
};

// The parameters the plan's positions can and cannot identify, in both modes.
struct RotaryIdentifiability {
  geometry::Identifiability absolute, relative;
  // The drift's parameters with the tilting axis's own zero (EB0B, EA0A) added: why it is
  // not among them.
  geometry::Identifiability with_tilt_zero;
  std::vector<std::string> absolute_names, relative_names;
};
RotaryIdentifiability rotaryIdentifiability(const parts::PlanManifest& m);
// What `probeloop plan` prints for a plan that tilts the table.
std::string rotaryIdentifiabilityText(const parts::PlanManifest& m);

RotaryCalibration calibrateRotaryAxes(const parts::PlanManifest& m, const CampaignEvaluation& e);

std::string rotaryCalibrationText(const RotaryCalibration& r);
std::string rotaryCalibrationJson(const RotaryCalibration& r);
// time_s,cycle, then per relative parameter its value and U_ (k = 2): errors.csv's layout.
std::string rotaryErrorSeriesCsv(const RotaryCalibration& r);

}  // namespace probeloop::evaluate
