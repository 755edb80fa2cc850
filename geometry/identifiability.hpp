// Which error parameters a measurement can tell apart: the sensitivity matrix of the
// observations to the parameters, its rank, and the combinations that leave every
// observation unchanged (issue 33: `plan` says which location errors a chosen set of rotary
// positions can and cannot identify).
//
// The sensitivity is taken on the exact chain by central differences of +-1 um or urad, so
// it is the first-order model with no linearisation error of its own above 1e-12 of a unit.
// The rank is decided on the column-normalised matrix (units differ between columns) with
// a relative tolerance: a parameter is identifiable when no null combination involves it.
#pragma once
#include <Eigen/Dense>
#include <functional>
#include <string>
#include <vector>

#include "geometry/kinematic_chain.hpp"

namespace probeloop::geometry {

// d(observation)/d(parameter): rows = observations (as `observe` returns them), columns =
// parameters, in observation units per um or urad.
Eigen::MatrixXd chainSensitivity(const std::function<Eigen::VectorXd(const ChainState&)>& observe,
                                 const ChainState& base, const std::vector<ChainParameter>& params,
                                 int body_count);

struct Identifiability {
  std::vector<std::string> names;   // one per parameter (column)
  int rank = 0;
  std::vector<bool> identifiable;   // per parameter
  // Each relation: coefficients per parameter (um, urad) that change no observation, in
  // reduced echelon form (the first non-zero coefficient is 1 and belongs to no other
  // relation). Empty when every parameter is identifiable.
  std::vector<Eigen::VectorXd> relations;

  bool all() const { return static_cast<int>(names.size()) == rank; }
  // One sentence per relation: "EB0B, EB0C, EX0C cannot be separated: +1 EB0B - 1 EB0C ...".
  std::vector<std::string> sentences() const;
};

Identifiability identifiability(const Eigen::MatrixXd& sensitivity, const std::vector<std::string>& names,
                                double relative_tolerance = 1e-9);

}  // namespace probeloop::geometry
