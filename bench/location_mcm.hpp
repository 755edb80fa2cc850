// The location-error model of one cycle as a GUM measurement model (for the MCM benchmark
// and its numpy peer, bench/numpy_mcm.py, which draws the same distributions).
// Inputs (32): x, y, z of the four sphere centres of this cycle and of the reference cycle
// (um, normal, u from the known-radius fit of 5 points with sigma = 0.5 um), d/2 (mm,
// normal, u = 0.05), the tool-change translation of each cycle (um, normal, sigma 0.75 per
// axis) and the artifact's temperature change (K, rectangular +-1).
// Output: EA0C (um/m) by seed 004 Eq. 5.8 with the ATC translations and the artifact's
// expansion (alpha (h + R) dT lifts every z of this cycle) added to the centres.
#pragma once
#include "uncertainty/gum.hpp"

namespace probeloop::bench {

inline uncertainty::Problem locationErrorProblem() {
  uncertainty::Problem p;
  p.output = "EA0C";
  p.unit = "um/m";
  const double u_xy = 0.5 * std::sqrt(0.5), u_z = 0.5;  // (J^T J)^-1 = diag(1/2, 1/2, 1)
  const char* axes[3] = {"x", "y", "z"};
  for (const std::string cyc : {"i", "1"})
    for (int k = 1; k <= 4; ++k)
      for (int a = 0; a < 3; ++a)  // z of position 2 of this cycle 3 um up: EA0C = 3 um / 0.32 m
        p.inputs.push_back(uncertainty::Input::normal(std::string(axes[a]) + "_" + cyc + "," + std::to_string(k),
                                                      cyc == "i" && k == 2 && a == 2 ? 3.0 : 0.0, a == 2 ? u_z : u_xy));
  p.inputs.push_back(uncertainty::Input::normal("d/2", 160.0, 0.05));
  for (const char* cyc : {"i", "1"})
    for (int a = 0; a < 3; ++a)
      p.inputs.push_back(uncertainty::Input::normal(std::string("atc_") + axes[a] + "_" + cyc, 0.0, 0.75));
  p.inputs.push_back(uncertainty::Input::rectangular("dT", 0.0, 1.0));
  return p;
}

// x: 24 centre coordinates (cycle i: 0..11, reference: 12..23, k-major, x y z), d/2, 6 ATC,
// dT. Eq. 5.8: EA0C = (z_i,2 - z_i,4)/d - (z_1,2 - z_1,4)/d with d in m and z in um.
struct LocationErrorModel {
  template <class T>
  T operator()(const T* x) const {
    const double lift_per_K = 11.5e-3 * 90.0;  // um/K: alpha (h + R)
    const T d_m = 2.0 * x[24] * 1e-3;
    const T z_i2 = x[3 * 1 + 2] + x[25 + 2] + lift_per_K * x[31], z_i4 = x[3 * 3 + 2] + x[25 + 2] + lift_per_K * x[31];
    const T z_12 = x[12 + 3 * 1 + 2] + x[28 + 2], z_14 = x[12 + 3 * 3 + 2] + x[28 + 2];
    return (z_i2 - z_i4) / d_m - (z_12 - z_14) / d_m;
  }
};

}  // namespace probeloop::bench
