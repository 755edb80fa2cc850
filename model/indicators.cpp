#include "model/indicators.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"

namespace probeloop::model {

double hazenPercentile(std::vector<double> R, double X) {
  if (R.empty()) throw InputError("", 0, "a percentile needs at least one value");
  if (!(X >= 0 && X <= 1)) throw InputError("", 0, "a percentile is taken at X in [0, 1]");
  std::sort(R.begin(), R.end());
  const double N = static_cast<double>(R.size());
  // Eq. 4.32: p_i = (i - 1/2)/N; Eq. 4.31: k = N X + 1/2 within [p_1, p_N], clamped outside.
  const double p1 = 0.5 / N, pN = (N - 0.5) / N;
  const double k = X <= p1 ? 1.0 : X >= pN ? N : N * X + 0.5;
  // Eq. 4.30 (1-based): R_floor(k) + frac(k) (R_floor(k)+1 - R_floor(k)).
  const auto i = static_cast<std::size_t>(std::floor(k));
  const double f = k - std::floor(k);
  if (i >= R.size()) return R.back();
  return R[i - 1] + f * (R[i] - R[i - 1]);
}

Indicators indicators(const std::vector<double>& E, const std::vector<double>& P) {
  if (E.size() != P.size() || E.empty())
    throw InputError("", 0, "indicators need measured and predicted series of the same, non-zero length (" +
                                std::to_string(E.size()) + " and " + std::to_string(P.size()) + ")");
  for (std::size_t k = 0; k < E.size(); ++k)
    if (!std::isfinite(E[k]) || !std::isfinite(P[k]))
      throw InputError("", 0, "sample " + std::to_string(k + 1) + " is not a finite number");
  Indicators r;
  r.n = static_cast<int>(E.size());
  std::vector<double> res(E.size()), absres(E.size());
  double ss = 0, s_smape = 0;
  for (std::size_t k = 0; k < E.size(); ++k) {
    res[k] = E[k] - P[k];
    absres[k] = std::fabs(res[k]);
    ss += res[k] * res[k];
    if (E[k] != 0 && P[k] != 0) {
      // An under-estimation counts as the equally distant over-estimation (L1261).
      const double p = std::fabs(P[k]) < std::fabs(E[k]) ? E[k] + (E[k] - P[k]) : P[k];
      s_smape += std::fabs(E[k] - p) / (std::fabs(E[k]) + std::fabs(p));
      ++r.smape_samples;
    }
  }
  r.rmse = std::sqrt(ss / r.n);
  r.smape_percent = r.smape_samples ? 100.0 * s_smape / r.smape_samples : 0.0;
  const auto [rmin, rmax] = std::minmax_element(res.begin(), res.end());
  const auto [emin, emax] = std::minmax_element(E.begin(), E.end());
  const double den = *emax + std::fabs(*emin), num = *rmax + std::fabs(*rmin);
  if (den > 0) r.pv_ratio_percent = 100.0 * num / den;
  else r.pv_defined = num == 0;
  r.p99 = hazenPercentile(absres, 0.99);
  return r;
}

}  // namespace probeloop::model
