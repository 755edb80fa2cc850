// A workpiece to machine on the table (YAML, kind: workpiece; docs/formats.md#workpiece):
// the stock, its material, the cutting tools, and the CMM that inspects it afterwards. Test
// pieces that are machined (kind: thermal_test_piece, ...) build one of these from their own
// description (parts/piece_kinds.hpp).
//
// Frames: the stock, holes and collision bodies are given in the *part frame*. The part
// frame sits on the table with its axes parallel to the machine's at C = 0 and its origin at
// `frame_origin_mm` in machine (tip) coordinates at C = 0; for kind: workpiece the origin is
// 0, so the part frame is the table frame (machine coordinates at C = 0). CMM points and the
// CMM export are in the part frame at 20 °C.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::parts {

struct CuttingTool {
  int number = 0;
  std::string kind = "flat_end_mill";  // flat_end_mill | engraving (cuts as a flat end mill of its tip width)
  double diameter_mm = 0;
  double length_mm = 0;        // gauge line to the tool tip (tool table, G43)
  double stickout_mm = 0;      // free length out of the holder (L2 of seed 000 Eq. 3.16)
  double flute_length_mm = 0;  // L1 of Eq. 3.16
  double youngs_modulus_N_per_mm2 = 0;
  int flutes = 0;
  std::string name;            // optional, for headers ("HSS 4-flute end mill d16")
};

struct WorkpieceMaterial {
  std::string name;
  double alpha_per_K = 0;                   // nominal expansion coefficient
  double specific_cutting_force_N_per_mm2 = 0;  // k_c: cutting power = k_c x removal rate
  double radial_force_ratio = 0;            // F_radial / F_tangential
  double alpha_um_per_m_K = 0;              // alpha_per_K as written, for outputs (23.4, not 23.399999999999995)
};

struct CmmSpec {
  double mpe_constant_um = 0;   // MPE = A + L / K
  double mpe_length_mm = 0;     // K (L in mm); 0 = no length term
  // The part's temperature in the CMM room lies within 20 °C +- this (seed 004 L2145: 0.3 K);
  // the simulated CMM draws it (seeded), the budgets carry it (seed 004 Eq. 7.6). 0 = exactly 20 °C.
  double temperature_half_width_K = 0;
};

// A vertical cylinder in the part frame: a hole drilled before machining (material that is
// not there), or a collision body (bolt head, adapter) that no tool may touch.
struct VerticalCylinder {
  Eigen::Vector2d centre_mm = Eigen::Vector2d::Zero();
  double radius_mm = 0;
  double z_min_mm = 0, z_max_mm = 0;
  std::string name;
};

struct Workpiece {
  std::string file, name;
  // The blank: a box (stock_min/max) or, with `cylindrical`, the vertical cylinder inscribed in
  // the box's XY extent (centre and radius from it) between its z limits.
  Eigen::Vector3d stock_min_mm = Eigen::Vector3d::Zero(), stock_max_mm = Eigen::Vector3d::Zero();
  bool cylindrical = false;
  std::vector<VerticalCylinder> holes;      // removed before the first cut (through holes, counterbores)
  std::vector<VerticalCylinder> obstacles;  // clamps, bolt heads, adapter: never to be touched
  Eigen::Vector3d frame_origin_mm = Eigen::Vector3d::Zero();  // part frame origin, machine coords at C = 0
  // Height of the support under the part that shares its temperature and expansion
  // coefficient (an adapter and washers of the same alloy): a warm support lifts the part by
  // alpha dT support_height. 0 = the part sits on the table (kind: workpiece).
  double support_height_mm = 0;
  WorkpieceMaterial material;
  std::vector<CuttingTool> tools;
  CmmSpec cmm;
  // The stylus ball the piece is probed with on the machine (the stepped workpiece's
  // probing.tip_diameter); 0 = the machine file's probe tip.
  double probe_tip_diameter_mm = 0;
  const CuttingTool* tool(int number) const;  // nullptr if not listed
  double blankRadius() const { return (stock_max_mm.x() - stock_min_mm.x()) / 2; }
  // The clamping datum: thermal expansion of the workpiece is about this point (part frame).
  Eigen::Vector3d datum() const {
    return Eigen::Vector3d((stock_min_mm.x() + stock_max_mm.x()) / 2, (stock_min_mm.y() + stock_max_mm.y()) / 2,
                           stock_min_mm.z());
  }
};

Workpiece loadWorkpiece(const std::string& path);

// Shared by the loaders of machined test pieces (the same keys and checks everywhere):
// material {name, alpha_um_per_m_K, specific_cutting_force_N_per_mm2, radial_force_ratio},
// tools[] {number, kind, name, diameter, length, stickout, flute_length, youngs_modulus_GPa,
// flutes}, cmm {mpe_constant, mpe_length, temperature_half_width}.
class YamlMap;
WorkpieceMaterial readMaterial(YamlMap m);
std::vector<CuttingTool> readCuttingTools(YamlMap& parent, const std::string& key);
CmmSpec readCmm(YamlMap c);

// The `kind:` of a part file ("sphere_artifact", "workpiece", ...); InputError if absent.
std::string partKind(const std::string& path);

}  // namespace probeloop::parts
