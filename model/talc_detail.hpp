// Text helpers shared by the TALC replay and the TALC state machine (not public API).
#pragma once
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace probeloop::model::talc_detail {

// Fixed decimals, no "-0.0" for a value that rounds to zero.
inline std::string fmt(double v, int decimals) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << v;
  std::string r = s.str();
  if (r == "-0" || r.rfind("-0.", 0) == 0) {
    bool zero = true;
    for (char ch : r)
      if (ch >= '1' && ch <= '9') zero = false;
    if (zero) r.erase(0, 1);
  }
  return r;
}

inline std::string hours(double s) { return fmt(s / 3600.0, 2) + " h"; }

inline std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace probeloop::model::talc_detail
