// What the virtual machine really is (YAML, kind: machine_truth; docs/formats.md#machine-truth):
// the physical error effects the simulator applies and that evaluation must find.
//
// Conventions (docs/conventions.md): every error is the displacement of the stylus tip
// relative to the workpiece that a commanded position produces. Tool-side displacements
// (`tool_X/Y/Z`, ATC steps, linear-axis errors) move the tip; table-side ones (C-axis
// location errors, artifact expansion) move the artifact. A tip displaced by +d finds the
// artifact at -d, so the evaluation sees a table error e and a tool error d as e - d.
//
// Contract: loadMachineTruth throws InputError with file:line for unknown keys, wrong units,
// unknown node names, negative noise; every effect is off unless the file names it.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "geometry/location_errors.hpp"
#include "model/structural_stiffness.hpp"
#include "sim/rigid_campaign.hpp"
#include "sim/thermal_network.hpp"

namespace probeloop::sim {

// The 7 location errors of the C axis plus a tool-side translation (um), per unit of
// something (a kelvin of a node; nothing for a static term).
struct ErrorVector {
  std::array<double, 7> location{};  // EX0C_um ... EC0C_urad
  std::array<double, 3> tool_um{};   // tool_X_um, tool_Y_um, tool_Z_um
  // Linear positioning (scale) error of X, Y, Z: EXX = s x at the axis's machine coordinate x
  // (um per mm of travel; a heated ball screw stretches its axis's scale: seed 000's thermal
  // position error e_pt, which grows with the distance).
  std::array<double, 3> scale_um_per_mm{};  // EXX_um_per_mm, EYY_um_per_mm, EZZ_um_per_mm
  // Location errors of the tilting axis (B or A, issue 33), right-hand about +X +Y +Z as
  // ISO 230-7 counts them, at its axis line: EX0B_um, EY0B_um, EZ0B_um, EA0B_urad, EB0B_urad,
  // EC0B_urad (or the same with A). The table with C and the artifact rides on it.
  std::array<double, 6> tilt_location{};
  bool any() const;
};


// Polynomial error of a linear axis as a function of its machine coordinate (mm):
// sum_k coeff[k] * pos^k, in um (translations) or urad (rotations).
struct AxisErrorPolynomials {
  // [axis X,Y,Z][error: EX*, EY*, EZ*, EA*, EB*, EC*] -> coefficients
  std::array<std::array<std::vector<double>, 6>, 3> coeff;
  bool any = false;
};

struct EnvironmentEvent {
  double at_s = 0, change_K = 0, ramp_s = 0, hold_s = 0, recover_s = 0;
};

struct EnvironmentProfile {
  double mean_C = 20;
  double daily_amplitude_K = 0;  // half the peak-to-peak daily swing
  double peak_clock_s = 15 * 3600.0;
  double start_clock_s = 0;      // clock time of day at t = 0
  double drift_K_per_s = 0;
  std::vector<EnvironmentEvent> events;
  double at(double t_s) const;
};

enum class HeatInput { CAxisRpm, SpindleRpm, AxisSpeed, Mwf, Constant };

struct HeatSourceSpec {
  int node = 0;
  HeatInput input = HeatInput::Constant;
  double gain = 0;  // W per rpm (|speed|), W per m/min of path speed, W when the MWF is on, W
};

struct SensorSpec {
  std::string column;  // e.g. T_env_C (inputs CSV)
  int node = -1;       // -1 = environment
  double noise_K = 0;
  std::optional<double> offset_K;  // `random` in the file = drawn uniformly in +-0.5 K (DS1820
                                   // accuracy); absent in the file = 0
};

struct ThermalTruth {
  bool present = false;
  double max_step_s = 60;
  EnvironmentProfile environment;
  std::vector<ThermalNodeSpec> nodes;
  std::vector<ThermalLinkSpec> links;
  std::vector<HeatSourceSpec> sources;
  std::vector<SensorSpec> sensors;
  std::vector<ErrorVector> per_node_K;  // displacement per kelvin rise of each node
  int nodeIndex(const std::string& name) const;  // -1 if none
};

// Load between measurements (the thesis turned the C axis at random speeds): applied while
// the program dwells; the machine is busy probing otherwise.
struct DutyTruth {
  std::vector<double> c_levels_rpm;  // random level every `hold_s` (seeded)
  double hold_s = 0;
  std::vector<std::pair<double, double>> c_profile;  // explicit (time_s, rpm) steps
  std::vector<std::pair<double, bool>> mwf_profile;  // (time_s, on)
  // Production work with other tools while the probe waits: the probe leaves and is
  // re-seated at seeded random times (a Poisson process on the dwell clock, so the rate is
  // per hour of dwelling), which puts tool changes at times unrelated to the probing.
  double tool_changes_per_hour = 0;
};

struct ProbeTruth {
  double pretravel_um = 0;          // mean lateral pre-travel
  int lobes = 3;                    // kinematic probes: 3 lobes
  double lobe_amplitude_um = 0;
  double lobe_phase_deg = 0;
  double pretravel_vertical_um = 0; // along -Z
  double trigger_delay_s = 0;       // latch delay: the machine travels feed * delay more
  double noise_um = 0;              // repeatability, 1 sigma, along the approach
  bool quantise = false;            // report at the axes' resolution
};

struct ArtifactTruth {
  int node = -1;            // node whose temperature rise the artifact and table share
  std::optional<double> alpha_per_K;  // expansion coefficient; absent: the workpiece material's
  Eigen::Vector3d placement_error_mm = Eigen::Vector3d::Zero();  // where it really sits
};

struct MachineTruth {
  std::string file;
  ErrorVector static_errors;                    // constant
  std::vector<LocationKeyframe> keyframes;      // piecewise linear in time
  AxisErrorPolynomials axes;
  double EC0Y_urad = 0, EB0Z_urad = 0, EA0Z_urad = 0;  // squareness (right-hand rotations)
  ThermalTruth thermal;
  DutyTruth duty;
  ProbeTruth probe;
  double atc_repeatability_um = 0;  // 1 sigma per axis of the tip after each tool change
  // Settling after a tool change: the seated holder and the spindle nose exchange heat, and
  // the tip moves along Z by settling_tool_Z_um, decaying with settling_tau_s (0 = off).
  double settling_tool_Z_um = 0, settling_tau_s = 0;
  ArtifactTruth artifact;
  double inputs_rate_s = 60;        // inputs CSV sample period
  // Static stiffness of the structure at the tool (seed 003: F/k), N/um per machine axis;
  // 0 = rigid.
  Eigen::Vector3d stiffness_N_per_um = Eigen::Vector3d::Zero();
  // Seed 003's structural units (crossbeam, bed) in the machine frame: under the force on the
  // tool each translates by F/(4k) and turns by F R/(k S^2), and the tip moves by
  // delta + eps x arm (model/structural_stiffness.hpp); added to the F/k above. Empty = none.
  std::vector<model::StructuralUnit> structure_units;
  // Speed-dependent lost motion of each drive (um per m/min of the axis's last speed, capped
  // at lost_motion_max_um): a semi-closed-loop drive's screw and nut wound up by friction
  // while the axis moved, held by stiction when it stops; the tip lags the command against
  // the axis's last direction. A wall cut after a fast transition sits further out than after
  // a slow one: the simulator's stand-in for seed 000's control error (docs/simulator.md).
  Eigen::Vector3d lost_motion_um_per_m_per_min = Eigen::Vector3d::Zero();
  double lost_motion_max_um = 0;

  geometry::LocationErrors keyframeAt(double t_s) const;
};

MachineTruth loadMachineTruth(const std::string& path);

}  // namespace probeloop::sim
