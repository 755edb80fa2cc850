#include "gcode/probe_log.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::gcode {
namespace {

// Seconds since 1970-01-01 of a Fanuc date YYYYMMDD and time HHMMSS (H. Hinnant's days_from_civil).
double clockSeconds(const std::string& date, const std::string& time, const std::string& file, int line) {
  double dv = 0, tv = 0;
  if (!parseFiniteNumber(date, dv) || !parseFiniteNumber(time, tv) || dv != std::round(dv) || tv != std::round(tv) || dv < 19000101 ||
      dv > 99991231 || tv < 0 || tv > 235959)
    throw InputError(file, line, "clock '" + date + " " + time + "': expected the date YYYYMMDD and the time HHMMSS (#3011, #3012)");
  const long d = static_cast<long>(dv), t = static_cast<long>(tv);
  long y = d / 10000;
  const long m = d / 100 % 100, day = d % 100, hh = t / 10000, mm = t / 100 % 100, ss = t % 100;
  if (m < 1 || m > 12 || day < 1 || day > 31 || mm > 59 || ss > 59)
    throw InputError(file, line, "clock '" + date + " " + time + "': not a date and a time of day");
  y -= m <= 2 ? 1 : 0;
  const long era = (y >= 0 ? y : y - 399) / 400, yoe = y - era * 400;
  const long doy = (153 * (m > 2 ? m - 3 : m + 9) + 2) / 5 + day - 1, doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  const long days = era * 146097 + doe - 719468;
  return static_cast<double>(days) * 86400.0 + static_cast<double>(hh * 3600 + mm * 60 + ss);
}

}  // namespace

std::vector<LoggedProbePoint> parseProbeLog(const std::string& text, const std::string& file, int first_line,
                                            std::optional<double>* session_start_s) {
  std::vector<LoggedProbePoint> out;
  std::optional<double> own_start;  // the first START line's clock
  std::optional<double>& start = session_start_s ? *session_start_s : own_start;
  std::istringstream in(text);
  std::string line;
  int n = first_line - 1;
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
    if (tok[0] == "START" && tok.size() == 3) {
      const double s = clockSeconds(tok[1], tok[2], file, n);
      if (!start) start = s;
      continue;
    }
    if (tok[0] != "PT" || tok.size() < 7 || tok.size() > 9) {
      throw InputError(file, n,
                       "unrecognised log line '" + line +
                           "'; expected 'PT <cycle> <position> <point> <x> <y> <z> [<date> <time> | <clock s>]' or "
                           "'START <date> <time>'");
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
      // Bounded before the conversion to int: 1e300 was undefined behaviour (fuzz/probe_log).
      if (v[i] != std::round(v[i]) || v[i] < 1 || v[i] > 2147483647.0)
        throw InputError(file, n, "cycle, position and point must be positive integers (at most 2147483647), found '" +
                                      tok[i + 1] + "'");
    }
    p.cycle = static_cast<int>(v[0]);
    p.position = static_cast<int>(v[1]);
    p.point = static_cast<int>(v[2]);
    p.tip_mm = Eigen::Vector3d(v[3], v[4], v[5]);
    if (tok.size() == 9 && start) p.time_s = clockSeconds(tok[7], tok[8], file, n) - *start;
    if (tok.size() == 8) {  // LinuxCNC: the inputs logger's clock from analog input 1 (gcode/probe_program.hpp)
      double t = 0;
      if (!parseFiniteNumber(tok[7], t) || t < 0)
        throw InputError(file, n, "field 8 '" + tok[7] + "' (the clock, s) is not a finite number >= 0");
      p.time_s = t;
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace probeloop::gcode
