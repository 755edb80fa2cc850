// Force-induced error from static stiffness: the closed-form statics of seed 003 (Yang, MRes
// thesis, Sec. 3.4; notes seeds001-003.md §3.4-3.9, effects E14/E15; docs/seed003-stiffness.md).
//
// A structural unit (a crossbeam, a machine bed) rests on four connection points. A force F
// at the tool is shared by the four points (shear), and its moment about the unit's pivot is
// taken up as a couple by supports a distance S apart:
//   translation  delta = F / (4 k)          seed 003 eqs. 28, 30, 50, 52 (55-57)
//   rotation     eps   = F R / (k S^2)      seed 003 eqs. 29, 31, 33, 35, 49, 51, 53, 54
// k is the unit's stiffness in the force's direction (Table 4, N/mm), R the lever arm from the
// pivot to the force's line (mm), S the support spacing (D_cb, L_cb, L_mb, D_mb; mm).
// The tool tip moves by the unit's twist, first order: dp = delta + eps x arm (seed 003 eqs.
// 11-13; notes §5), arm = pivot -> tool tip (mm). Translation in mm, rotation in rad.
//
// Signs and directions the thesis leaves ambiguous (notes §3.9 [AMBIGUOUS, kinematics]),
// fixed here:
// - A moment path names its lever direction (a signed unit vector, pivot -> the force's
//   line). The rotation vector is the moment's: eps = (R lever) x (F_f e_f) / (k_f S^2)
//   (right-hand rule; eqs. 14, 24, 36 write the moment as such a cross product). The thesis's
//   printed signs of eqs. 62, 66, 69, 72, 73, 77, 79, 80 fix each path's lever direction
//   (seed003Gantry()).
// - The tool-tip displacement uses one arm vector per unit (a rigid body has one). The
//   thesis multiplies each angle by an arm of its own ("Y: x 75 mm, X: x 40 mm"), which no
//   single vector reproduces for every equation: seed003Gantry() picks the arm that
//   reproduces eqs. 64, 67, 68, 71, 75 (and eq. 63's correct value); eq. 70 (Z: alpha x 75)
//   then reads alpha x 40 (docs/seed003-stiffness.md says which and why).
// - The gantry is in the thesis's frame: X the crossbeam's travel, Y vertical (the spindle),
//   Z the head's travel along the beam (Sec. 3.3). The simulator's truth gives its units in
//   the machine's frame (sim/machine_truth.hpp).
// Contract: k > 0 and S > 0 for every path used; a lever perpendicular to its force.
#pragma once
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace probeloop::model {

// seed 003 eqs. 28, 30, 50, 52: shear shared by four points, mm (F in N, k in N/mm).
double shearTranslation_mm(double F_N, double k_N_per_mm);
// seed 003 eqs. 29, 31, 33, 35, 49, 51, 53, 54: the couple F R / S on supports S apart, rad.
double momentRotation_rad(double F_N, double R_mm, double k_N_per_mm, double S_mm);
// seed 003 eqs. 63, 64, 67, 68, 70, 71, 74, 75: an angle times its lever arm, mm.
double leverDisplacement_mm(double angle_rad, double arm_mm);

// One moment load path: the force component force_axis (0 x, 1 y, 2 z) acting at R along
// lever (a signed unit axis), resisted by supports S apart with the unit's k in that direction.
struct MomentPath {
  int force_axis = 0;
  Eigen::Vector3d lever = Eigen::Vector3d::UnitX();
  double R_mm = 0, S_mm = 0;
  std::string eq;  // the source equation, e.g. "seed 003 eq. 29"
};

struct StructuralUnit {
  std::string name;
  Eigen::Vector3d k_N_per_mm = Eigen::Vector3d::Zero();  // stiffness per force direction (Table 4)
  std::array<bool, 3> shear{};  // force directions that translate the unit by F/(4k); the others
                                // are carried by the guide screws (eq. 23, L495)
  std::vector<MomentPath> moments;
  Eigen::Vector3d arm_mm = Eigen::Vector3d::Zero();  // pivot -> tool tip
};

struct Twist {
  Eigen::Vector3d delta_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d eps_rad = Eigen::Vector3d::Zero();
};

// The unit's 6-DOF deformation under the force F at the tool (N).
Twist unitTwist(const StructuralUnit& u, const Eigen::Vector3d& F_N);
// First order: delta + eps x arm (mm).
Eigen::Vector3d tcpDisplacement_mm(const Twist& t, const Eigen::Vector3d& arm_mm);
// Sum over the units (each its own twist and arm): the tool tip's displacement, mm.
Eigen::Vector3d tcpDisplacement_mm(const std::vector<StructuralUnit>& units, const Eigen::Vector3d& F_N);

// seed 003 Table 4 [L666-671], N/mm.
struct Seed003Stiffness {
  double k_cbx = 4679, k_cby = 4926, k_cbz = 142857;
  double k_mbx = 6079, k_mby = 84962, k_mbz = 37341;
};
// Lever arms and spacings, mm: given only inside the substitutions of Sec. 5.2 (eqs. 62, 66,
// 73, 77, 79, 80), except L_cb, R_cbz2, R_cbz1: inferred from eqs. 69, 72 (notes §3.9).
struct Seed003Geometry {
  double R_cby = 75, R_cbx = 40, D_cb = 100;            // eqs. 62, 66
  double L_cb = 50, R_cbz2 = 40, R_cbz1 = 75;           // [INFERRED] eqs. 69, 72
  double R_mbx = 10, L_mb = 100, R_mby = 75;            // eqs. 73, 77
  double R_mb = 20, D_mb = 1800;                         // eq. 79
};

// The gantry's crossbeam and bed in the thesis's frame (see above); [0] crossbeam, [1] bed.
std::vector<StructuralUnit> seed003Gantry(const Seed003Stiffness& k = {}, const Seed003Geometry& g = {});

}  // namespace probeloop::model
