#include "geometry/chain_offsets.hpp"

#include <stdexcept>

#include "geometry/identifiability.hpp"

namespace probeloop::geometry {

using Eigen::Vector3d;

Vector3d workpiecePointUnderTip(const KinematicChain& chain, const ChainState& pose) {
  return workpieceFrame(chain, pose).inverse() * toolTip(chain, pose);
}

Eigen::MatrixXd chainOffsetSensitivity(const KinematicChain& chain, const ChainState& pose,
                                       const std::vector<ChainParameter>& params, double reference_radius_mm) {
  const Vector3d w = workpiecePointUnderTip(chain, pose);
  auto observe = [&](const ChainState& s) { return Eigen::VectorXd(machineCoordinatesOf(chain, s, w)); };
  const bool radial = reference_radius_mm > 0;
  Eigen::MatrixXd J(3, static_cast<Eigen::Index>(params.size()) + (radial ? 1 : 0));
  if (!params.empty()) J.leftCols(static_cast<Eigen::Index>(params.size())) = chainSensitivity(observe, pose, params, chain.bodyCount()) * 1e3;
  if (radial) {
    if (chain.workpiece_branch.empty() || chain.workpiece_branch.back().joint.kind != JointKind::Rotary)
      throw std::invalid_argument("chain offsets: the radial scale needs a rotary table as the workpiece branch's last body");
    // The table's frame is the workpiece-body frame; its axis line there is the joint's line
    // (the joint turns the body about it, which leaves the line in place).
    const Joint& table = chain.workpiece_branch.back().joint;
    const Vector3d n = table.direction.normalized();
    Vector3d r = w - table.point_mm;
    r -= r.dot(n) * n;
    const Vector3d per_um = r * (1e-3 / reference_radius_mm);  // mm of displacement per um of ER0T
    J.rightCols(1) = (machineCoordinatesOf(chain, pose, w + per_um) - machineCoordinatesOf(chain, pose, w - per_um)) / 2.0 * 1e3;
  }
  return J;
}

std::vector<ChainParameter> seed004Parameters(const KinematicChain& chain) {
  std::vector<ChainParameter> p;
  for (int k : {0, 1, 2, 3, 4, 5}) p.push_back(locationParameter(chain, "C", k));
  p[2].name = "EZ0T";   // seed 004 Table 5.2: the table surface's Z (ISO's EZ0C at the pivot)
  p[5].sign = -1.0;     // docs/conventions.md: EC0C positive = clockwise seen from +Z
  return p;
}

Eigen::Matrix<double, 3, 7> seed004OffsetSensitivity(const KinematicChain& chain, const ChainState& pose,
                                                     double reference_radius_mm) {
  if (!(reference_radius_mm > 0)) throw std::invalid_argument("chain offsets: d/2 must be positive");
  const Eigen::MatrixXd J = chainOffsetSensitivity(chain, pose, seed004Parameters(chain), reference_radius_mm);
  // Columns of J: EX EY EZ EA EB EC, ER; LocationErrors order: EX EY EZ ER EA EB EC.
  Eigen::Matrix<double, 3, 7> out;
  out.leftCols(3) = J.leftCols(3);
  out.col(3) = J.col(6);
  out.rightCols(3) = J.middleCols(3, 3);
  return out;
}

}  // namespace probeloop::geometry
