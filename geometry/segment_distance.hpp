// Closest distance between two line segments in space (Ericson, Real-Time Collision Detection,
// 2005, Sec. 5.1.9), in the segments' unit. Degenerate segments (a point) are handled; the
// simulator's collision checks and the safety verifier's tilting-table sweep share it.
#pragma once
#include <Eigen/Dense>

namespace probeloop::geometry {

double segmentDistance(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& q0,
                       const Eigen::Vector3d& q1);

}  // namespace probeloop::geometry
