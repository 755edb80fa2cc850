// Test-only helpers of chain_offsets_test.cpp and printed_offsets_test.cpp: a B/C trunnion
// chain built by hand (as seed 004's NMV 5000: B on the workpiece side, C' on it, X Y Z on the
// tool side), its offset frame, and the exact truth the offsets must reach, written from the
// conventions (docs/conventions.md) and not from the code under test.
#pragma once
#include <Eigen/Dense>
#include <random>

#include "geometry/compensation_offsets.hpp"
#include "geometry/kinematic_chain.hpp"
#include "geometry/location_errors.hpp"

namespace probeloop::geometry::test {

constexpr double kHalfD = 160.0;  // d/2, seed 004 L1430

struct Trunnion {
  double b_sense = -1;                                     // B about +Y (+1) or -Y (-1)
  Eigen::Vector2d b_axis_xz_mm = Eigen::Vector2d::Zero();  // B's line at B = 0
  Eigen::Vector2d c_axis_xy_mm = Eigen::Vector2d::Zero();  // C's line at B = 0
  double pivot_z_mm = 0;                                   // where C's errors hold
};

inline KinematicChain trunnion(const Trunnion& t) {
  KinematicChain c;
  const Eigen::Vector3d b_point(t.b_axis_xz_mm.x(), 0, t.b_axis_xz_mm.y());
  const Eigen::Vector3d c_point(t.c_axis_xy_mm.x(), t.c_axis_xy_mm.y(), t.pivot_z_mm);
  c.workpiece_branch = {Body{"B trunnion", Eigen::Vector3d::Zero(), {JointKind::Rotary, "B", t.b_sense * Eigen::Vector3d::UnitY(), b_point}},
                        Body{"C table", Eigen::Vector3d::Zero(), {JointKind::Rotary, "C", -Eigen::Vector3d::UnitZ(), c_point, LocationConvention::BodyOnAxis}}};
  const char* n[3] = {"X", "Y", "Z"};
  for (int k = 0; k < 3; ++k)
    c.tool_branch.push_back(Body{n[k], Eigen::Vector3d::Zero(), {JointKind::Linear, n[k], Eigen::Vector3d::Unit(k), Eigen::Vector3d::Zero()}});
  return c;
}

inline TrunnionFrame frameOf(const Trunnion& t) {
  TrunnionFrame f;
  f.table.axis_centre_xy_mm = t.c_axis_xy_mm;
  f.table.pivot_z_mm = t.pivot_z_mm;
  f.table.reference_radius_mm = kHalfD;
  f.b_axis_xz_mm = t.b_axis_xz_mm;
  f.b_sense = t.b_sense;
  return f;
}

// One error of 1 um or 1 urad, in LocationErrors order (EX EY EZ ER EA EB EC).
inline LocationErrors unitError(int k) {
  std::array<double, LocationErrors::kCount> v{};
  v[static_cast<std::size_t>(k)] = 1.0;
  return LocationErrors::fromValues(v);
}

inline LocationErrors randomErrors(std::mt19937& g) {
  std::uniform_real_distribution<double> lin(-30, 30), ang(-60, 60);
  LocationErrors e;
  e.EX0C_um = lin(g), e.EY0C_um = lin(g), e.EZ0T_um = lin(g), e.ER0T_um = lin(g) / 3;
  e.EA0C_urad = ang(g), e.EB0C_urad = ang(g), e.EC0C_urad = ang(g);
  return e;
}

// Where the tool must go (machine coordinates, mm) to meet the workpiece point it meets
// nominally at `pose`, on the exact chain: the C joint located by Trans(EX, EY, EZ)
// Rx(EA) Ry(EB) Rz(-EC) about its pivot in the trunnion's frame, the table grown radially by
// ER0T / (d/2) about its axis (docs/conventions.md, geometry/location_errors.hpp).
inline Eigen::Vector3d trueContact(const KinematicChain& chain, const ChainState& pose, const LocationErrors& e) {
  const Eigen::Vector3d w = workpieceFrame(chain, pose).inverse() * toolTip(chain, pose);
  const Eigen::Vector3d& p = chain.workpiece_branch.back().joint.point_mm;
  const Eigen::Vector3d grown(p.x() + (w.x() - p.x()) * (1 + e.ER0T_um * 1e-3 / kHalfD),
                              p.y() + (w.y() - p.y()) * (1 + e.ER0T_um * 1e-3 / kHalfD), w.z());
  ChainState s = pose;
  s.location.assign(static_cast<std::size_t>(chain.bodyCount()), Twist{});
  Twist& c = s.location[static_cast<std::size_t>(chain.indexOfAxis("C"))];
  c.translation_mm = Eigen::Vector3d(e.EX0C_um, e.EY0C_um, e.EZ0T_um) * 1e-3;
  c.rotation_rad = Eigen::Vector3d(e.EA0C_urad, e.EB0C_urad, -e.EC0C_urad) * 1e-6;
  return machineCoordinatesOf(chain, s, grown);
}

}  // namespace probeloop::geometry::test
