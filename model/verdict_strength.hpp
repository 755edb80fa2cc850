// How much a diagnosis can say: the words the terminal (model/outputs.cpp, model/diagnose.cpp)
// and the HTML report (report/model_report.cpp) share, so the two never disagree.
//
// Contract:
// - pValueText(p): a p-value as printed: "< 1e-4" below 1e-4 (a chi-squared tail that small is
//   "far below any threshold"; "0" would read as certainty), else 2 significant digits in
//   plain notation ("0.012", "0.5", "1"); "n/a" when p is not a finite number.
//   pValueClause(p): "p = 0.012" or "p < 1e-4".
// - uOverResidual(u, rms): u / rms, the strength of "the residual is within 1.5 u": the larger,
//   the less the verdict says. +inf when rms = 0 < u; NaN when u or rms is not a finite
//   number >= 0, or both are 0.
// - ratioText(r): "3.1" (one decimal below 10), "12" (whole from 10), "> 1000", "n/a".
// - weakVerdictSentence(u, rms, unit): when u >= kWeakVerdictRatio x rms, the sentence
//   "the measurement's uncertainty (u = 1.1 um) is 3.1× the residual (RMS 0.35 um): the model
//   cannot be judged finer than u."; otherwise "". `unit` is written as given (the terminal
//   says um, the page µm).
#pragma once
#include <string>

namespace probeloop::model {

// At u >= 2 x the residual RMS, "within 1.5 u" would also pass a residual 3x the one seen:
// the measurement, not the model, sets what can be judged.
constexpr double kWeakVerdictRatio = 2.0;

std::string pValueText(double p);
std::string pValueClause(double p);
double uOverResidual(double u, double rms);
std::string ratioText(double r);
std::string weakVerdictSentence(double u, double rms, const std::string& unit);

}  // namespace probeloop::model
