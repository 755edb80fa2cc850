// Quality indicators of a prediction against measurements (seed 004 Eqs. 4.27-4.32).
//
// Contract: measured and predicted have the same length N >= 1 and are finite (InputError
// otherwise, naming the first bad sample). The residual is measured - predicted.
// - rmse: sqrt(mean(residual^2)) (4.27), in the data's unit.
// - smape: (100/N') sum |E - Ê| / (|E| + |Ê|) in % (4.28), over the N' samples where
//   neither E nor Ê is 0 (seed 004 L1261 excludes them); an under-estimation |Ê| < |E| is
//   first mirrored about E into the equally distant over-estimation (L1261, read as the
//   notes §6.5 propose: same |E - Ê|, larger |Ê|). With no sample left smape is 0 and
//   smape_samples = 0 says it is undefined (never a NaN).
// - pv_ratio: [max(res) + |min(res)|] / [max(E) + |min(E)|] x 100 (4.29); 0 when the
//   denominator is 0 and the residual is 0, otherwise undefined (pv_defined = false).
// - p99: the Hazen percentile (Hyndman-Fan type 5; Eqs. 4.30-4.32) of |residual| at 0.99.
#pragma once
#include <vector>

namespace probeloop::model {

struct Indicators {
  int n = 0;
  double rmse = 0;
  double smape_percent = 0;
  int smape_samples = 0;
  double pv_ratio_percent = 0;
  bool pv_defined = true;
  double p99 = 0;
};

Indicators indicators(const std::vector<double>& measured, const std::vector<double>& predicted);

// Hazen percentile (Eqs. 4.30-4.32) of the values at X in [0, 1].
double hazenPercentile(std::vector<double> values, double X);

}  // namespace probeloop::model
