// What `probeloop model fit|compare|diagnose` print and write: text tables for the terminal
// and the JSON the HTML report (report/model_report.hpp) draws from. The JSON keys carry
// their units; the schema is in docs/formats.md#model-json.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/diagnose.hpp"
#include "model/error_model.hpp"
#include "model/fit.hpp"

namespace probeloop::model {

struct ModelFit {  // a whole model fitted on a campaign; `before` is empty when nothing was just added
  std::vector<ChannelFit> after, before;
  int train_end = 0;
};

// training_fraction > 0 overrides the model's (compare uses one split for all models).
// Two model channels that name one errors.csv column ("EY0C" and "EY0C_um") would be fitted
// twice with two verdicts: refused (InputError naming both and the column). fitModel checks it.
void requireDistinctChannels(const Campaign& c, const ErrorModel& m);
ModelFit fitModel(const Campaign& c, const ErrorModel& m, double training_fraction = 0);

std::string fitText(const Campaign& c, const ErrorModel& m, const ModelFit& f);
nlohmann::json fitJson(const Campaign& c, const ErrorModel& m, const ModelFit& f);

// Side by side: the validation indicators of several models on the same campaign.
std::string compareText(const Campaign& c, const std::vector<ErrorModel>& models, const std::vector<ModelFit>& fits);
nlohmann::json compareJson(const Campaign& c, const std::vector<ErrorModel>& models, const std::vector<ModelFit>& fits);

std::string diagnosisText(const Campaign& c, const ErrorModel& m, const Diagnosis& d);
nlohmann::json diagnosisJson(const Campaign& c, const ErrorModel& m, const Diagnosis& d);

}  // namespace probeloop::model
