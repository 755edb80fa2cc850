#include "gcode/probe_log.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::gcode {
std::vector<LoggedProbePoint> parseProbeLog(const std::string& text, const std::string& file) {
  std::vector<LoggedProbePoint> out;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::vector<std::string> tok;
    for (std::string t; ls >> t;) {
      // DPRNT may separate a sign from its digits: "- 12.3400".
      if (!tok.empty() && (tok.back() == "-" || tok.back() == "+")) {
        tok.back() += t;
      } else {
        tok.push_back(t);
      }
    }
    if (tok.empty() || (tok.size() == 1 && tok[0] == "%")) continue;
    if (tok[0] != "PT" || tok.size() != 7) {
      throw InputError(file, n,
                       "unrecognised log line '" + line +
                           "'; expected 'PT <cycle> <position> <point> <x> <y> <z>'");
    }
    double v[6];
    for (int i = 0; i < 6; ++i) {
      if (!parseFiniteNumber(tok[i + 1], v[i]))
        throw InputError(file, n, "field " + std::to_string(i + 2) + " '" + tok[i + 1] +
                                      "' is not a finite number");
    }
    LoggedProbePoint p;
    p.line = n;
    for (int i = 0; i < 3; ++i) {
      if (v[i] != std::round(v[i]) || v[i] < 1)
        throw InputError(file, n, "cycle, position and point must be positive integers, found '" +
                                      tok[i + 1] + "'");
    }
    p.cycle = static_cast<int>(v[0]);
    p.position = static_cast<int>(v[1]);
    p.point = static_cast<int>(v[2]);
    p.tip_mm = Eigen::Vector3d(v[3], v[4], v[5]);
    out.push_back(p);
  }
  return out;
}

}  // namespace probeloop::gcode
