#include "core/units.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace probeloop {
namespace {

using UnitTable = std::vector<std::pair<std::string_view, double>>;

const UnitTable& table(Dimension dim) {
  static const UnitTable length{{"mm", 1.0}, {"m", 1000.0}, {"cm", 10.0}, {"um", 1e-3},
                                {"µm", 1e-3}, {"in", 25.4}};
  static const UnitTable micrometre{{"um", 1.0}, {"µm", 1.0}, {"mm", 1000.0}, {"nm", 1e-3}};
  static const UnitTable microradian{{"urad", 1.0}, {"µrad", 1.0}, {"um/m", 1.0}, {"µm/m", 1.0},
                                     {"mrad", 1e3}, {"rad", 1e6}, {"deg", 1e6 * kPi / 180.0}};
  static const UnitTable feed{{"mm/min", 1.0}, {"m/min", 1000.0}, {"mm/s", 60.0},
                              {"in/min", 25.4}};
  static const UnitTable angle{{"deg", 1.0}, {"°", 1.0}, {"rad", 180.0 / kPi},
                               {"urad", 180.0 / kPi * 1e-6}, {"µrad", 180.0 / kPi * 1e-6}};
  static const UnitTable duration{{"s", 1.0}, {"min", 60.0}, {"h", 3600.0}, {"d", 86400.0},
                                  {"ms", 1e-3}};
  static const UnitTable rotspeed{{"rpm", 1.0}, {"1/min", 1.0}, {"deg/s", 1.0 / 6.0}};
  static const UnitTable temperature{{"K", 1.0}, {"degC", 1.0}};
  switch (dim) {
    case Dimension::Length: return length;
    case Dimension::Micrometre: return micrometre;
    case Dimension::Microradian: return microradian;
    case Dimension::Feed: return feed;
    case Dimension::Angle: return angle;
    case Dimension::Duration: return duration;
    case Dimension::RotSpeed: return rotspeed;
    case Dimension::Temperature: return temperature;
  }
  return length;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

}  // namespace

const char* unitName(Dimension dim) {
  switch (dim) {
    case Dimension::Length: return "mm";
    case Dimension::Micrometre: return "um";
    case Dimension::Microradian: return "urad";
    case Dimension::Feed: return "mm/min";
    case Dimension::Angle: return "deg";
    case Dimension::Duration: return "s";
    case Dimension::RotSpeed: return "rpm";
    case Dimension::Temperature: return "K";
  }
  return "";
}

const char* acceptedUnits(Dimension dim) {
  switch (dim) {
    case Dimension::Length: return "a length: bare number in mm, or with unit mm, m, cm, um, in";
    case Dimension::Micrometre: return "a small length: bare number in um, or with unit um, nm, mm";
    case Dimension::Microradian: return "a small angle: bare number in urad, or with unit urad, um/m, mrad, rad, deg";
    case Dimension::Feed: return "a feed: bare number in mm/min, or with unit mm/min, m/min, mm/s";
    case Dimension::Angle: return "an angle: bare number in deg, or with unit deg, rad, urad";
    case Dimension::Duration: return "a duration: bare number in s, or with unit s, min, h, d, ms";
    case Dimension::RotSpeed: return "a rotational speed: bare number in rpm, or with unit rpm";
    case Dimension::Temperature: return "a temperature difference: bare number in K";
  }
  return "";
}

double parseQuantity(std::string_view text, Dimension dim) {
  const std::string s(trim(text));
  if (s.empty()) throw std::invalid_argument(std::string("empty value; expected ") + acceptedUnits(dim));
  char* end = nullptr;
  const double number = std::strtod(s.c_str(), &end);
  if (end == s.c_str()) {
    throw std::invalid_argument("'" + s + "' is not a number; expected " + acceptedUnits(dim));
  }
  if (!std::isfinite(number)) {
    throw std::invalid_argument("'" + s + "' is not finite; expected " + acceptedUnits(dim));
  }
  const std::string_view unit = trim(std::string_view(end));
  if (unit.empty()) return number;
  for (const auto& [name, factor] : table(dim)) {
    if (unit == name) return number * factor;
  }
  throw std::invalid_argument("unit '" + std::string(unit) + "' in '" + s + "' is not " +
                              acceptedUnits(dim));
}

}  // namespace probeloop
