// The two-axis horizontal turning centre of seed 002 (Ramesh Babu et al., Sec. "lathe
// kinematic chain", eqs. 10-30; notes/seeds001-003.md §2.4-2.5) as a KinematicChain, its
// 24 parametric errors, the volumetric error P = P_tool - P_work exactly through the chain,
// and the paper's first-order model written out independently.
//
// Bodies (the paper's numbers; frames R = machine zero):
//   1 Z carriage on R, linear along +Z (axis "Z", position z), origin offset o1 = (a1, b1, c1)
//   2 X cross-slide on 1, linear along +X (axis "X", position x), o2 = (a2, b2, c2)
//   3 turret on 2, o3 = (a3, b3, c3); the tool tip T = (Tx, Ty, Tz) in its frame (eq. 17)
//   4 spindle on R, o4 = (a4, b4, c4); the workpiece point W = (Wx, Wy, Wz) in its frame
//     (eq. 18), the spindle axis along its Z through its origin.
// Tool branch R -> 1 -> 2 -> 3 -> tip, workpiece branch R -> 4 -> W (eqs. 15-16).
//
// The rotary motions: the paper's turret index ("zt") and spindle rotation ("zw") carry no
// nominal rotation in eqs. 12-13, only their six errors. We keep that: bodies 3 and 4 are
// fixed joints; the index angle and the spindle angle are only the arguments at which the
// caller evaluates their error twists. The tool offset T is then that of the active tool
// (the index is absorbed in T), and W is the point at the angle at which it is cut or
// measured (a turned diameter is the same at every angle to first order).
//
// Errors: each body's error is its `motion` twist (delta mm, eps rad), applied after the
// nominal motion about the body's origin: eq. 10's matrix [I + skew(eps), p + delta] with
// the exact rotation Rot(x)Rot(y)Rot(z) in place of I + skew (geometry/kinematic_chain.hpp).
// The caller evaluates each body's twist at its own axis variable (1: z, 2: x, 3: zt, 4: zw).
// No location errors and no squareness: the paper models none (notes §2.1).
#pragma once
#include <array>
#include <string>
#include <vector>

#include "geometry/kinematic_chain.hpp"

namespace probeloop::geometry {

// The frame offsets a_i, b_i, c_i (mm), index 0..3 = the paper's bodies 1..4. The paper
// gives no values (notes §2.6); latheDefaultOffsets() is our documented example.
struct LatheOffsets {
  std::array<Eigen::Vector3d, 4> o{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                   Eigen::Vector3d::Zero()};
};

// A small slant-free turning centre, machine zero at the Z carriage's home: the spindle
// nose 600 mm along -Z ahead of it, the spindle axis 250 mm from the carriage's X origin;
// no value of it is from the paper (docs/lathe-seed002.md).
LatheOffsets latheDefaultOffsets();

// The 24 parametric errors: twist per body, index 0..3 = the paper's bodies 1..4, each
// already evaluated at its own axis variable.
struct LatheErrors {
  std::array<Twist, 4> body;
};

// Chain body index (KinematicChain::body order: the workpiece branch first) of the paper's
// body 1..4.
int latheChainIndex(int paper_body);

KinematicChain latheChain(const LatheOffsets& off, const Eigen::Vector3d& tool_tip_mm);

// The chain's state at the nominal positions x, z (mm) with the errors.
ChainState latheState(double x_mm, double z_mm, const LatheErrors& e);

// Eq. 24 with its -z corrected (notes §2.4): the tool offset that closes the ideal chain at
// x, z on the workpiece point W.
Eigen::Vector3d latheIdealToolOffset(const LatheOffsets& off, double x_mm, double z_mm, const Eigen::Vector3d& w_mm);
// The nominal x, z that bring the tool tip T to W; the Y closure (centre height) is the
// tool offset's, not an axis's: Ty = b4 + Wy - b1 - b2 - b3 is the caller's to keep.
Eigen::Vector2d latheNominalXZ(const LatheOffsets& off, const Eigen::Vector3d& tool_tip_mm, const Eigen::Vector3d& w_mm);

// P = P_tool - P_work (mm) in R, exact through the chain (the sign of eqs. 27-29, notes §2.4).
Eigen::Vector3d latheVolumetricError(const KinematicChain& chain, double x_mm, double z_mm, const LatheErrors& e,
                                     const Eigen::Vector3d& w_mm);

// The first-order model, notes §2.5's compact form:
//   P = sum_{i=1..3} [delta_i + eps_i x (p_tip - o_i)] - [delta_4 + eps_4 x W]
// with o_i the nominal origin of body i in R and p_tip the nominal tool tip.
Eigen::Vector3d latheVolumetricErrorFirstOrder(const LatheOffsets& off, const Eigen::Vector3d& tool_tip_mm,
                                               double x_mm, double z_mm, const LatheErrors& e,
                                               const Eigen::Vector3d& w_mm);

// The resultant |P| (eq. 30).
inline double latheResultant(const Eigen::Vector3d& p) { return p.norm(); }

// What a turned part shows of the errors at W: the tool tip seen in the spindle frame (exact
// through the chain); diameter error 2 (r_cut - r_W) and face position error z_cut - Wz
// (mm), the diameter about the spindle frame's Z axis.
struct LatheCutErrors {
  double diameter_mm = 0;
  double face_z_mm = 0;
};
LatheCutErrors latheCutErrors(const KinematicChain& chain, double x_mm, double z_mm, const LatheErrors& e,
                              const Eigen::Vector3d& w_mm);

// The 24 errors as chain parameters ("dx1" ... "ez4": delta in um, eps in urad; the
// paper's delta_x1 ... eps_z4), for chainSensitivity / identifiability.
std::vector<ChainParameter> latheParameters();

}  // namespace probeloop::geometry
