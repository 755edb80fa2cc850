// Loader of user measurement models for `probeloop gum` (kind: gum_model). Schema:
// docs/formats.md#gum-model. Contract: strict like every loader here (unknown keys, missing
// keys, bad numbers -> InputError with file:line); an expression error names the output,
// the column within the expression and, when the expression sits on one line of the file,
// the file column, with a caret under the offending character; inputs are checked (u > 0
// unless a constant, dof > 0, half-widths > 0, >= 2 observations) and so is the correlation
// matrix (symmetric, [-1, 1], positive semidefinite).
#pragma once
#include <string>

#include "uncertainty/text_model.hpp"

namespace probeloop::parts {

uncertainty::TextModel loadGumModel(const std::string& path);

}  // namespace probeloop::parts
