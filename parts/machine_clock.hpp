// The machine's clock (docs/simulator.md §2 "Clock"): how long each motion of a machine takes,
// the one copy that the simulator (sim/machine_motion.cpp, machine_probing.cpp) and the
// planners (planner/program_walker, planner/sphere_cycle) share, so that planned and simulated
// times cannot drift apart (issue 29). No acceleration: a move runs at its speed from start to
// end.
//
// Contract (seconds; mm, deg, mm/min, deg/min):
// - rapidSeconds: every axis at once, the linear ones at the machine's rapid feed, A, B and C at
//   their max_speed; the slowest axis's time.
// - rotaryIndexSeconds: a rotary axis indexing by delta at its positioning speed; 0 for no
//   move; an InputError for a move of an axis the machine does not have (or has no speed for).
// - linearFeedSeconds: XYZ path length / F. rotaryFeedSeconds: |degrees| / F, for a move of
//   rotary axes alone (LinuxCNC and Fanuc read F in deg/min there).
#pragma once
#include <Eigen/Dense>

#include "parts/machine.hpp"

namespace probeloop::parts {

double rapidSeconds(const Machine& m, const Eigen::Vector3d& gauge_delta_mm, double b_delta_deg = 0, double c_delta_deg = 0,
                    double a_delta_deg = 0);
double rotaryIndexSeconds(double delta_deg, const RotaryAxis& axis);
double linearFeedSeconds(double path_mm, double feed_mm_per_min);
double rotaryFeedSeconds(double delta_deg, double feed_deg_per_min);

}  // namespace probeloop::parts
