// Angles in the planners: one wrap into [0, 360) with one tolerance, used by the sphere cycle
// and the thermal test piece alike.
#pragma once
#include <cmath>

namespace probeloop::planner {

// a in degrees -> [0, 360); a value within 1e-9 deg below 360 (a rounding residue of 0) is 0.
inline double wrapDeg360(double a) {
  a = std::fmod(a, 360.0);
  if (a < 0) a += 360.0;
  if (a >= 360.0 - 1e-9) a = 0.0;
  return a;
}

}  // namespace probeloop::planner
