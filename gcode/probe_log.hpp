// Parser of the probe logs the emitted programs write. Both dialects write one line per
// trigger: "PT <cycle> <position> <point> <x> <y> <z>" (LinuxCNC LOG: 6 decimals; Fanuc
// DPRNT: fixed digits, possibly padded with spaces). Fanuc adds the controller's clock,
// "<date YYYYMMDD> <time HHMMSS>" (#3011, #3012), to each PT line and writes
// "START <date> <time>" when each program starts: a point's time is its clock minus the log's
// first START (the session's start), to the second. LinuxCNC's LOG cannot read a clock: its
// points have no time, unless the program logs one as an eighth field (a live-interval program
// reads HAL analog input 1, the inputs logger's clock: gcode/probe_program.hpp); that value is
// the point's time as it stands. Blank lines and '%' are skipped; any other line is an InputError with
// file:line, so a wrong file is never half-read.
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>
#include <vector>

namespace probeloop::gcode {

struct LoggedProbePoint {
  int line = 0;  // line in the log file
  int cycle = 0, position = 0, point = 0;
  Eigen::Vector3d tip_mm;  // stylus-tip centre at trigger, program coordinates
  std::optional<double> time_s;  // since the log's first START, when both carry the clock
};

// A log read in pieces (the campaign store follows a growing log): `first_line` is the file
// line of the text's first line, and `session_start_s` carries the first START's clock from one
// piece to the next (read and updated when given).
std::vector<LoggedProbePoint> parseProbeLog(const std::string& text, const std::string& file, int first_line = 1,
                                            std::optional<double>* session_start_s = nullptr);

}  // namespace probeloop::gcode
