// A GUM uncertainty budget (JCGM 100 §5, §6, Annex G).
// Contract: contributions are uncorrelated and given in the output's unit; combine() sorts
// them by size, computes u_c = sqrt(sum u_i^2), nu_eff by Welch-Satterthwaite (G.2b;
// infinite dof for type B inputs given as exact), and U = k u_c.
#pragma once
#include <limits>
#include <string>
#include <vector>

namespace probeloop::uncertainty {

struct Contribution {
  std::string input;         // what varies, in the field's words
  char type = 'B';           // 'A' (statistics of repeated observations) or 'B' (other)
  std::string distribution;  // normal, rectangular, ...
  std::string basis;         // where the input's uncertainty comes from
  double u = 0;              // contribution to u_c, in the output unit
  double dof = std::numeric_limits<double>::infinity();
};

struct Budget {
  std::string quantity, unit;
  double value = 0;
  std::vector<Contribution> contributions;  // sorted, largest first
  double u_c = 0;
  double nu_eff = std::numeric_limits<double>::infinity();
  double k = 2;
  double U = 0;
};

Budget combine(std::string quantity, std::string unit, double value,
               std::vector<Contribution> contributions, double k = 2.0);

}  // namespace probeloop::uncertainty
