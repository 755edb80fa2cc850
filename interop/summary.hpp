// What probeloop read from a CMM exchange document (`probeloop read FILE`), for a person (text)
// and for a script (JSON): the length unit, the measurement runs, the features by kind, each
// feature with its name, kind, line, geometry and number of points, the characteristics, and
// what was passed over. Lengths in mm after conversion.
#pragma once
#include <string>

#include "interop/cmm_document.hpp"

namespace probeloop::interop {

std::string cmmDocumentText(const CmmDocument& d);
std::string cmmDocumentJson(const CmmDocument& d);

}  // namespace probeloop::interop
