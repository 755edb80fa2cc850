// Where an error model fails and which effect is missing (docs/architecture.md#what-probeloop-is; issue 5).
//
// Per channel: the residual (measured - model) against the measurement's uncertainty, its
// whiteness (Ljung-Box on the training residual), the time windows where |residual| > U of
// the sample, and its cross-correlation with every input over lags. Then every candidate
// effect not in the channel's model is fitted on top (model/fit.hpp) and scored on the
// held-out validation span and by Rissanen's MDL on the training span. A candidate counts
// for a channel when it lowers both the validation RMSE (by >= 10 %) and the MDL, and the
// validation mean square falls by at least (u/2)^2 — so chance improvements at the noise
// floor do not count. Parsimony at the noise floor: of a channel's counting candidates
// within 10 % of the best validation RMSE, the one with the fewest parameters is the
// channel's preferred explanation (a known expansion beats a fitted lag that fits as well);
// of those reading one input (rival descriptions of one heat path) the channel keeps only its
// best by the same rule. Candidates are grouped by effect and input across channels and
// ranked by the validation mean square they explain, in units of each channel's u^2, summed
// over the channels that prefer them (then over all the channels they help).
//
// Verdict: "missing" (a ranked list), "nothing_missing" (no candidate counts, every residual
// is white (p >= 0.01) and its validation RMS <= 1.5 u), or "unexplained" (no candidate counts
// but some residual is not white or too large: the library lacks the effect).
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "model/dataset.hpp"
#include "model/error_model.hpp"
#include "model/fit.hpp"

namespace probeloop::model {

struct ResidualWindow {
  double from_s = 0, to_s = 0, peak = 0;
  int samples = 0;
};

struct CrossCorrelation {
  std::string input;
  double lag_s = 0, r = 0;
  bool significant = false;  // |r| > 2 / sqrt(n)
};

struct ChannelDiagnosis {
  std::string channel, unit;
  double u_measurement = 0;
  double rms_training = 0, rms_validation = 0;  // rms_validation: 0 without a validation span
  bool has_validation = false;
  // The RMS the verdict "within 1.5 u" judges: the validation span's, else the training span's.
  double rms_judged() const { return has_validation ? rms_validation : rms_training; }
  double ljung_box_Q = 0, ljung_box_p = 1;
  int ljung_box_lags = 0;
  bool white = true, within = true;
  std::vector<ResidualWindow> windows;        // the largest, in time order
  std::vector<CrossCorrelation> cross;        // per input, at the lag of the largest |r|
};

struct CandidateOnChannel {
  std::string channel;
  double rmse_before = 0, rmse_after = 0, mdl_before = 0, mdl_after = 0;
  double explained = 0;  // (rmse_before^2 - rmse_after^2) / u^2
  ChannelFit fit;        // model + candidate
};

struct Recommendation {
  Effect effect;  // tau_s: the median fitted value over the channels
  std::vector<CandidateOnChannel> channels;
  double score = 0;  // explained, summed over the channels where this is the preferred explanation
  double total = 0;  // explained, summed over every channel it helps (the tie-break)
  int parameters = 0;
  std::string sentence, command;
};

struct DiagnoseOptions {
  std::optional<ExpansionLevers> levers;
  std::string model_path = "model.yaml";  // for the printed command
  std::string part_path;                  // ditto (expansion candidates)
};

struct Diagnosis {
  std::vector<ChannelFit> fits;
  std::vector<ChannelDiagnosis> channels;
  std::vector<Recommendation> ranked;
  std::string verdict, message;
  int candidates_tried = 0;
};

Diagnosis diagnose(const Campaign& c, const ErrorModel& m, const DiagnoseOptions& opt);

// Ljung-Box Q over lags 1..h of a series and its p-value against chi^2(h).
void ljungBox(const std::vector<double>& x, int h, double& Q, double& p);

}  // namespace probeloop::model
