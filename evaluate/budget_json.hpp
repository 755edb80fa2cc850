// One GUM budget as the evaluation JSONs write it (docs/formats.md): quantity, unit, value,
// u_c, nu_eff (null when infinite), k, U and every contribution with its dof. Shared by the
// sphere campaign's and the thermal test piece's evaluation.json so the two cannot drift.
#pragma once

#include <nlohmann/json.hpp>

#include "uncertainty/budget.hpp"

namespace probeloop::evaluate {

nlohmann::ordered_json finiteOrNull(double v);
nlohmann::ordered_json budgetJson(const uncertainty::Budget& b);

}  // namespace probeloop::evaluate
