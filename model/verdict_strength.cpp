#include "model/verdict_strength.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

namespace probeloop::model {
namespace {

std::string printf1(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

}  // namespace

std::string pValueText(double p) {
  if (!std::isfinite(p)) return "n/a";
  if (p < 1e-4) return "< 1e-4";
  return printf1("%.2g", p);  // plain notation down to 1e-4 (printf's %g switches below 1e-4)
}

std::string pValueClause(double p) {
  const std::string t = pValueText(p);
  return t.rfind("<", 0) == 0 ? "p " + t : "p = " + t;
}

double uOverResidual(double u, double rms) {
  if (!std::isfinite(u) || !std::isfinite(rms) || u < 0 || rms < 0 || (u == 0 && rms == 0))
    return std::numeric_limits<double>::quiet_NaN();
  if (rms == 0) return std::numeric_limits<double>::infinity();
  return u / rms;
}

std::string ratioText(double r) {
  if (std::isnan(r)) return "n/a";
  if (r > 1000) return "> 1000";
  return r < 9.95 ? printf1("%.1f", r) : printf1("%.0f", r);
}

std::string weakVerdictSentence(double u, double rms, const std::string& unit) {
  const double r = uOverResidual(u, rms);
  if (!(r >= kWeakVerdictRatio)) return "";
  const std::string with_unit = unit.empty() ? "" : " " + unit;
  return "the measurement's uncertainty (u = " + printf1("%.3g", u) + with_unit + ") is " + ratioText(r) +
         "\u00d7 the residual (RMS " + printf1("%.3g", rms) + with_unit +
         "): the model cannot be judged finer than u.";
}

}  // namespace probeloop::model
