// A workpiece to machine on the table (YAML, kind: workpiece; docs/formats.md#workpiece):
// the stock, its material, the cutting tools, and the CMM that inspects it afterwards.
//
// Coordinates: the stock box is given in machine coordinates of the tool tip at C = 0 (the
// table frame); the workpiece frame used by CMM points is the same frame at 20 °C.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::parts {

struct CuttingTool {
  int number = 0;
  double diameter_mm = 0;
  double length_mm = 0;        // gauge line to the tool tip (tool table, G43)
  double stickout_mm = 0;      // free length out of the holder (L2 of seed 000 Eq. 3.16)
  double flute_length_mm = 0;  // L1 of Eq. 3.16
  double youngs_modulus_N_per_mm2 = 0;
  int flutes = 0;
};

struct WorkpieceMaterial {
  std::string name;
  double alpha_per_K = 0;                   // nominal expansion coefficient
  double specific_cutting_force_N_per_mm2 = 0;  // k_c: cutting power = k_c x removal rate
  double radial_force_ratio = 0;            // F_radial / F_tangential
};

struct CmmSpec {
  double mpe_constant_um = 0;   // MPE = A + L / K
  double mpe_length_mm = 0;     // K (L in mm); 0 = no length term
};

struct Workpiece {
  std::string file, name;
  Eigen::Vector3d stock_min_mm = Eigen::Vector3d::Zero(), stock_max_mm = Eigen::Vector3d::Zero();
  WorkpieceMaterial material;
  std::vector<CuttingTool> tools;
  CmmSpec cmm;
  const CuttingTool* tool(int number) const;  // nullptr if not listed
  // The clamping datum: thermal expansion of the workpiece is about this point.
  Eigen::Vector3d datum() const {
    return Eigen::Vector3d((stock_min_mm.x() + stock_max_mm.x()) / 2, (stock_min_mm.y() + stock_max_mm.y()) / 2,
                           stock_min_mm.z());
  }
};

Workpiece loadWorkpiece(const std::string& path);

// The `kind:` of a part file ("sphere_artifact", "workpiece", ...); InputError if absent.
std::string partKind(const std::string& path);

}  // namespace probeloop::parts
