// Quantities with units in input files. Contract: a value is either a bare number, read in
// the dimension's canonical unit (mm, mm/min, deg, s, um, rpm, K), or "<number> <unit>"
// with a unit of the right dimension (urad for Microradian). Anything else throws std::invalid_argument whose
// message names the accepted units; callers add file:line.
#pragma once
#include <string>
#include <string_view>

namespace probeloop {

enum class Dimension { Length, Micrometre, Microradian, Feed, Angle, Duration, RotSpeed, Temperature };

// Value in the canonical unit of `dim` (see unitName).
double parseQuantity(std::string_view text, Dimension dim);
const char* unitName(Dimension dim);         // "mm", "mm/min", "deg", "s", ...
const char* acceptedUnits(Dimension dim);    // for error messages

constexpr double kPi = 3.141592653589793238462643383279502884;
constexpr double degToRad(double deg) { return deg * kPi / 180.0; }
constexpr double radToDeg(double rad) { return rad * 180.0 / kPi; }

}  // namespace probeloop
