// The regression families of seed 000 (Yaqoob 2017, Sec. 3.8–3.9 and Ch. 5; notes/seed000.md
// §7.1): named function forms of one variable, their fit to data by least squares, and the
// thesis's model selection by backward prediction (Sec. 5.7, Table 5.8).
//
// Families (parameters in this order; x is the input, e.g. Temp state in min or a feed):
//   polynomial              c0 + c1 x + ... + cd x^d          (Eq. 5.1–5.3, 5.8, 5.10, 5.45, 5.52, 5.56)
//   saturating_exponential  a - b exp(-c x)                   (Eq. 5.4, 5.6, 5.9, 5.13, 5.14, 5.16, 5.48)
//   gompertz                a exp(-exp(b - c x))              (Eq. 5.13 e_tt2x, e_spd2x)
//   log_logistic            a - b / (1 + exp(p ln(x / x0)))   (Eq. 5.5)
//   hill                    a - a / (1 + exp(p ln(x / x0)))   (Eq. 5.47, 5.49, 5.50, 5.53, e_pfx)
//   hyperbolic              a x / (b + x)                     (Eq. 5.11, 5.15, 5.46, 5.51)
//   weibull                 a + b exp(-k x^p)                 (Eq. 5.12 e_pt2y, printed c + (a-b) exp(-k T^p))
//   power                   a x^p                             (Eq. 5.7, read with "^")
// exp(p ln(x/x0)) is (x/x0)^p: at x = 0 it is taken by continuity (0 for p > 0), so the
// thesis's T = 0 (machine start) is a valid input; x < 0 is refused for the forms with x^p.
//
// Contract: evaluate() and fit() never return a NaN: an input outside a form's domain, a
// non-finite input or result, fewer points than parameters, unequal lengths, parameters that
// the data cannot identify, or a fit that does not converge throw GeometryError (the project's
// "ill-posed estimation" error) with a sentence that says which and why.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace probeloop::model {

enum class Family { Polynomial, SaturatingExponential, Gompertz, LogLogistic, Hill, Hyperbolic, Weibull, Power };

const char* familyName(Family f);                          // "saturating_exponential", ...
std::optional<Family> familyFromName(const std::string& name);
std::vector<std::string> familyNames();                    // for error messages
// Parameter names in order; a polynomial of degree d has c0..cd.
std::vector<std::string> parameterNames(Family f, int degree = 0);

struct RegressionFunction {
  Family family = Family::Polynomial;
  std::vector<double> p;  // parameters in parameterNames() order (a polynomial: c0 first)

  int degree() const { return family == Family::Polynomial ? static_cast<int>(p.size()) - 1 : 0; }
  double evaluate(double x) const;  // GeometryError outside the domain (see the header comment)
  std::string formula() const;     // "0.012 - 0.0104453*exp(-0.01862*x)", for reports
};

// One candidate of a model selection: a family and, for a polynomial, its degree.
// through_origin: polynomial only, c0 fixed at 0 (Eq. 5.1/5.2 have no intercept).
struct Candidate {
  Family family = Family::Polynomial;
  int degree = 1;
  bool through_origin = false;
  std::string label() const;  // "polynomial(2)", "hill", ...
};

struct FamilyFit {
  RegressionFunction function;
  std::vector<std::string> names;
  std::vector<double> u;  // standard uncertainties sigma * sqrt(diag (J^T J)^-1); empty when dof = 0
  int n = 0, parameters = 0, dof = 0;
  double ssr = 0;    // sum of squared residuals
  double sigma = 0;  // sqrt(ssr / dof), 0 when dof = 0 (an exact fit says nothing about scatter)
  int iterations = 0;
};

// Least squares of one candidate: linear families by QR, the others by Levenberg–Marquardt
// (analytic Jacobian, Marquardt scaling) started from the best point of a grid over the
// nonlinear parameters with the linear ones solved exactly at each grid point (variable
// projection start), so no starting values are needed.
FamilyFit fit(const Candidate& c, const std::vector<double>& x, const std::vector<double>& y);

// The thesis's backward prediction (Sec. 5.7, L944): the model at the measured points minus the
// measurement. percent = 100 |diff| / |measured|, undefined (has_percent = false) where the
// measurement is 0 (Table 5.8's T = 0 point).
struct BackwardPoint {
  double x = 0, measured = 0, predicted = 0, diff = 0;  // diff = |predicted - measured| (Table 5.8)
  bool has_percent = false;
  double percent = 0;
};
struct BackwardPrediction {
  std::vector<BackwardPoint> points;
  double sum_abs_diff = 0;
  int with_percent = 0;           // points whose % is defined
  double share_within_5 = 0;      // of those, the share with % < 5 (L1798)
  double share_within_10 = 0;     // and with % < 10
  bool meets_thesis_criteria = false;  // > 80 % of points within 5 % and all within 10 % (L1798)
};
BackwardPrediction backwardPrediction(const std::vector<double>& x, const std::vector<double>& measured,
                                      const std::vector<double>& predicted);

// Model selection: every candidate fitted to all points (its backward prediction, as the
// thesis reports it) and, because a fit judged on its own training points always favours the
// candidate with more parameters, also by leave-one-out: each point predicted by the fit to the
// others. The best candidate has the smallest leave-one-out RMS; candidates that cannot be fitted
// (too few points, not identifiable) are reported with the reason and not ranked.
struct CandidateReport {
  Candidate candidate;
  bool fitted = false;
  std::string refusal;  // why not, when !fitted or when leave-one-out is unavailable
  FamilyFit fit;
  BackwardPrediction backward;
  bool has_loo = false;
  double loo_rms = 0;
};
struct Selection {
  std::vector<CandidateReport> candidates;  // in the order given
  int best = -1;                            // index into candidates, -1 if none could be ranked
  std::string sentence;                     // what was chosen and why, with the numbers
};
Selection selectByBackwardPrediction(const std::vector<double>& x, const std::vector<double>& y,
                                     const std::vector<Candidate>& candidates);

}  // namespace probeloop::model
