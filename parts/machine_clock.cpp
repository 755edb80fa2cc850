#include "parts/machine_clock.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace probeloop::parts {

double rotaryIndexSeconds(double delta_deg, const RotaryAxis& ax) {
  if (delta_deg == 0) return 0;
  if (!ax.present || !(ax.max_speed_rpm > 0)) throw InputError("", 0, "move of a rotary axis the machine does not have");
  return std::fabs(delta_deg) / (ax.max_speed_rpm * 360.0) * 60.0;
}

double rapidSeconds(const Machine& m, const Eigen::Vector3d& d, double db, double dc, double da) {
  return std::max({d.cwiseAbs().maxCoeff() / m.rapid_feed_mm_per_min * 60.0, rotaryIndexSeconds(dc, m.c),
                   rotaryIndexSeconds(db, m.b), rotaryIndexSeconds(da, m.a)});
}

double linearFeedSeconds(double path_mm, double F) { return path_mm / F * 60.0; }
double rotaryFeedSeconds(double delta_deg, double F) { return std::fabs(delta_deg) / F * 60.0; }

}  // namespace probeloop::parts
