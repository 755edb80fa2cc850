#include "uncertainty/budget.hpp"

#include <algorithm>
#include <cmath>

namespace probeloop::uncertainty {

Budget combine(std::string quantity, std::string unit, double value,
               std::vector<Contribution> contributions, double k) {
  Budget b;
  b.quantity = std::move(quantity);
  b.unit = std::move(unit);
  b.value = value;
  std::stable_sort(contributions.begin(), contributions.end(),
                   [](const Contribution& a, const Contribution& c) { return a.u > c.u; });
  double s2 = 0;
  for (const auto& c : contributions) s2 += c.u * c.u;
  b.u_c = std::sqrt(s2);
  double ws = 0;  // G.2b as 1 / sum (u_i/u_c)^4 / nu_i: no over- or underflow of u^4
  for (const auto& c : contributions)
    if (std::isfinite(c.dof) && c.u > 0) ws += std::pow(c.u / b.u_c, 4) / c.dof;
  b.contributions = std::move(contributions);
  b.nu_eff = ws > 0 ? 1.0 / ws : std::numeric_limits<double>::infinity();
  b.k = k;
  b.U = k * b.u_c;
  return b;
}

}  // namespace probeloop::uncertainty
