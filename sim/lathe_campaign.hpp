// The seed 002 turning centre on the virtual machine: a turning campaign whose errors come
// from time-varying parametric errors through the lathe's chain (geometry/lathe_chain.hpp).
//
// Per cycle a part is turned at the workpiece point W and measured: its diameter error and
// its face (Z) position error, exactly through the chain (latheCutErrors), relative to the
// first cycle (the machine cold and idle), with measurement noise. The parametric errors are
// driven by a small thermal model: each heat source (spindle speed, an axis's mean feed)
// warms one body through a first-order lag (model::lagStep, the same primitive the model's
// `lag` effect integrates), and the body's error twist is the warming times a twist per
// kelvin, plus, on a linear axis, the warmed screw's scale error along its own axis times
// the axis position (the error as a function of its own axis variable).
//
// Seed 002 gives no values of any parametric error, no temperatures and no load definition
// (notes §2.6): the example truth (examples/lathe/lathe_truth.yaml) is scaled to the one
// number that survives, the 65 um cold-start resultant (docs/lathe-seed002.md).
//
// Contract: loadLatheTruth throws InputError (file:line, the field) for a bad file; the
// campaign is deterministic for the truth and the seed (one random stream per source for
// its load levels, one for the measurement noise; sim/random_streams.hpp).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/lathe_chain.hpp"

namespace probeloop::sim {

struct LatheHeatSource {
  std::string input;                 // inputs.csv column: spindle_rpm, feed_z_mm_per_min, ...
  int body = 1;                      // the paper's body 1..4 it warms
  std::vector<double> levels;        // load levels, drawn at random per hold (input units)
  double hold_s = 3600;
  double K_per_unit = 0;             // steady warming per input unit (K per rpm, per mm/min)
  double tau_s = 3600;               // its lag
  geometry::Twist per_K;             // error twist per kelvin (mm, rad)
  double screw_um_per_m_K = 0;       // linear axis: scale error along its axis, x position
};

struct LatheTruth {
  std::string file;
  geometry::LatheOffsets offsets = geometry::latheDefaultOffsets();
  Eigen::Vector3d tool_tip_mm{-150, 0, -100};
  Eigen::Vector3d workpiece_point_mm{25, 0, 80};
  double duration_s = 24 * 3600.0;
  double cycle_s = 600;              // one part turned and measured per cycle
  double inputs_rate_s = 60;
  double cold_start_s = 2 * 3600.0;  // every source at its highest level from the start
  double diameter_noise_um = 0.7;    // 1 sigma of one measured diameter
  double face_noise_um = 0.7;        // 1 sigma of one measured face position
  std::vector<LatheHeatSource> sources;
};

// Schema: docs/lathe-seed002.md#the-campaign (kind: lathe_truth).
LatheTruth loadLatheTruth(const std::string& path);

struct LatheCampaign {
  std::string inputs_csv, errors_csv, truth_csv;
  double max_resultant_um = 0;             // |P| over the campaign (the paper's eq. 30)
  double cold_start_resultant_um = 0;      // |P| warm at the cold-start load (steady state)
  double after_warm_up_resultant_um = 0;   // |P| still to come after cold_start_s of it
  int cycles = 0;
};

// Sample 0 is the machine cold and idle (every input 0): the lags start in equilibrium with
// it, as the model's do. Then the cold start, then random levels per hold.
LatheCampaign simulateLatheCampaign(const LatheTruth& truth, std::uint64_t seed);

}  // namespace probeloop::sim
