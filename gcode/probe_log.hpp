// Parser of the probe logs the emitted programs write. Both dialects write one line per
// trigger: "PT <cycle> <position> <point> <x> <y> <z>" (LinuxCNC LOG: 6 decimals; Fanuc
// DPRNT: fixed digits, possibly padded with spaces). Blank lines and '%' are skipped; any
// other line is an InputError with file:line, so a wrong file is never half-read.
#pragma once
#include <Eigen/Dense>
#include <string>
#include <vector>

namespace probeloop::gcode {

struct LoggedProbePoint {
  int line = 0;  // line in the log file
  int cycle = 0, position = 0, point = 0;
  Eigen::Vector3d tip_mm;  // stylus-tip centre at trigger, program coordinates
};

std::vector<LoggedProbePoint> parseProbeLog(const std::string& text, const std::string& file);

}  // namespace probeloop::gcode
