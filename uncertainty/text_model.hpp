// A measurement model given as text (one or more outputs of the same inputs), evaluated by
// the GUF and, on request, by the MCM with the JCGM 101 §8 validation; reports as text and
// JSON. This is what `probeloop gum <model.yaml>` runs (the YAML loader is parts/gum_model).
//
// Contract:
// - Every output gets its GUF budget (sorted by contribution, nu_eff, k from t, U) at the
//   coverage probability p. With MCM options, every output also gets the MCM estimate,
//   u, symmetric and shortest intervals and the validation verdict; all outputs share the
//   same trials (one draw of the inputs per trial), so they are deterministic for a seed.
// - Several outputs: their correlation matrix from the GUF (JCGM 100 H.2.4).
// - A model not defined (or not differentiable) at the estimate, or not finite in a trial:
//   InputError naming the file, the output's line and the output.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "uncertainty/expression.hpp"
#include "uncertainty/gum.hpp"

namespace probeloop::uncertainty {

struct TextOutput {
  std::string name, unit;
  Expression model;
  int line = 0;  // where the model is written (for messages)
};

struct TextModel {
  std::string title, file;
  Problem inputs;  // Problem::output/unit unused; inputs and their correlation
  std::vector<TextOutput> outputs;
  double p = 0.95;
};

struct TextOutputResult {
  GufResult guf;
  std::optional<McmResult> mcm;
  std::optional<Validation> validation;
};

struct TextModelResult {
  std::vector<TextOutputResult> outputs;
  Eigen::MatrixXd correlation;  // outputs x outputs (GUF)
  long mcm_trials = 0;
  bool mcm_converged = false;
  bool mcm_adaptive = false;
};

// options: nullopt = GUF only. Adaptive MCM stops when every output has converged.
TextModelResult evaluateTextModel(const TextModel& m, const std::optional<McmOptions>& options);

std::string textModelReport(const TextModel& m, const TextModelResult& r);
std::string textModelJson(const TextModel& m, const TextModelResult& r);

}  // namespace probeloop::uncertainty
