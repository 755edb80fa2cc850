#include "evaluate/budget_json.hpp"

#include <cmath>

namespace probeloop::evaluate {

using nlohmann::ordered_json;

ordered_json finiteOrNull(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }

ordered_json budgetJson(const uncertainty::Budget& b) {
  ordered_json jb;
  jb["quantity"] = b.quantity;
  jb["unit"] = b.unit;
  jb["value"] = b.value;
  jb["u_c"] = b.u_c;
  jb["nu_eff"] = finiteOrNull(b.nu_eff);
  jb["k"] = b.k;
  jb["U"] = b.U;
  jb["contributions"] = ordered_json::array();
  for (const auto& ct : b.contributions)
    jb["contributions"].push_back({{"input", ct.input},
                                   {"type", std::string(1, ct.type)},
                                   {"distribution", ct.distribution},
                                   {"basis", ct.basis},
                                   {"u", ct.u},
                                   {"dof", finiteOrNull(ct.dof)}});
  return jb;
}

}  // namespace probeloop::evaluate
