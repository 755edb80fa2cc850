// The TALC options (model/talc.hpp) as `model talc` and `campaign run` take them: one set of
// names, defaults and checks for both.
#pragma once
#include <CLI/CLI.hpp>
#include <sstream>
#include <string>

#include "model/talc.hpp"

namespace probeloop::cli {

// `inputs_csv` receives --model-inputs (comma-separated); talcInputsFrom() splits it.
inline void addTalcOptions(CLI::App* c, model::TalcOptions& t, std::string& inputs_csv) {
  c->add_option("--cp-h", t.cp_h, "calibration phase, h (0: as short as possible)")->capture_default_str()->check(CLI::NonNegativeNumber);
  c->add_option("--post-interval-h", t.post_interval_h, "measurement interval after the CP, h")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--ng-interval-min", t.ng_interval_min, "No-Good phase measurement interval, min")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--ng-measurements", t.ng_measurements, "measurements per No-Good phase")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--update-interval-h", t.update_interval_h, "periodic parameter update, h (0: none)")->capture_default_str()->check(CLI::NonNegativeNumber);
  c->add_option("--limit-linear-um", t.limit_linear_um, "action limit of the linear errors, um")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--limit-angular-urad", t.limit_angular_urad, "action limit of the angular errors, urad (= um/m)")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--na", t.na, "ARX output order")->capture_default_str()->check(CLI::NonNegativeNumber);
  c->add_option("--nb", t.nb, "ARX input order (coefficients per input)")->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--model-inputs", inputs_csv, "comma-separated input columns ('|c_rpm|' for a magnitude); default: the temperatures");
  c->add_option("--predicted-weight", t.predicted_weight, "WLS weight of rows whose target is a prediction (Eq. 4.20)")->capture_default_str();
}

inline std::vector<std::string> talcInputsFrom(const std::string& csv) {
  std::vector<std::string> out;
  std::stringstream ss(csv);
  for (std::string s; std::getline(ss, s, ',');)
    if (!s.empty()) out.push_back(s);
  return out;
}

}  // namespace probeloop::cli
