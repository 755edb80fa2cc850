// The error-model file (YAML, kind: error_model; docs/formats.md#error-model): which effects
// each error channel has, and which data the model is fitted on.
//
//   kind: error_model
//   data: {inputs: run/inputs.csv, errors: eval/errors.csv}   # optional; relative to this file
//   training_fraction: 0.6                                    # optional (seed 004: 60/40)
//   channels:
//     EY0C_um:
//       - {effect: static, input: T_env_C}
//       - {effect: lag, input: c_rpm, tau: 40 min}            # tau: where the fit starts
//     EZ0T_um:
//       - {effect: expansion, input: T_table_C, alpha_um_per_m_K: 11.5, length: 90 mm}
//     EX0C_um: []                                             # the offset only
//
// Contract: loadErrorModel throws InputError with file:line for an unknown kind, key or
// effect, a missing input, a non-positive tau/alpha/length, a channel listed twice, the
// same effect twice in a channel. saveErrorModel writes the canonical form atomically
// (comments are not kept).
//
// patchErrorModelText edits the file's own text instead (what `probeloop model add` uses, so
// a user's comments and layout survive): effects appended after a channel's last item,
// channels after the last one, `just_added: true` dropped where it was cleared. It returns
// nothing when the layout is one it does not edit (flow-style channels, block-style effect
// maps with a cleared flag) or when the edited text, parsed again, would not be exactly the
// updated model; the caller then writes the canonical form and says so.
#pragma once
#include <optional>
#include <string>

#include "model/error_model.hpp"

namespace probeloop::parts {

model::ErrorModel loadErrorModel(const std::string& path);
model::ErrorModel errorModelFromText(const std::string& text, const std::string& path);
std::optional<std::string> patchErrorModelText(const std::string& text, const model::ErrorModel& updated);
void saveErrorModel(const model::ErrorModel& m, const std::string& path);
std::string errorModelYaml(const model::ErrorModel& m);

}  // namespace probeloop::parts
