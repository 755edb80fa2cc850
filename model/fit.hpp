// Identification of an error model on a campaign (seed 004 Ch. 4; docs/architecture.md#what-probeloop-is).
//
// Per channel: y = c + sum_j k_j r_j(t; tau_j) + fixed(t), where r_j is the regressor of a
// fitted effect (model/effects.hpp) interpolated at the error times and fixed(t) the known
// predictions (expansion). Gains and offset are linear: ordinary least squares on the
// training span (the first `training_fraction` of the samples). Time constants are not:
// variable projection — each tau is started on a logarithmic grid (one at a time), then all
// are refined together by Ceres on ln tau with the linear part solved inside. Parameter
// uncertainties come from sigma^2 (J^T J)^-1 with J the full Jacobian (gains and ln tau),
// sigma^2 = SSR / (n - p). The prediction of the validation span uses the inputs only (the
// effects have no output feedback: simulation mode by construction).
//
// Contract: fitChannel refuses, with the channel and the effect named,
// - an input column that does not exist (listing those that do), or that is constant over
//   the training span ("it cannot explain anything");
// - too few training samples for the parameters (Ch. 6's full-rank criterion: how many
//   more samples, and how many hours of campaign that is);
// - a parameter that cannot be identified (a regressor collinear with others or with no
//   excitation: condition number);
// and never returns a NaN.
#pragma once
#include <string>
#include <vector>

#include "model/dataset.hpp"
#include "model/effects.hpp"
#include "model/indicators.hpp"

namespace probeloop::model {

struct Parameter {
  std::string name, unit;
  double value = 0, u = 0;
};

struct FittedEffect {
  Effect effect;  // tau_s holds the fitted value
  std::vector<Parameter> parameters;
};

struct ChannelFit {
  std::string channel, unit;
  std::vector<FittedEffect> effects;  // the offset first
  int n_train = 0, parameters = 0;
  double sigma = 0;                   // residual standard deviation (training)
  double mdl = 0;                     // Rissanen MDL on the training span (seed 004 Eq. 4.23, penalised)
  double u_measurement = 0;           // median U/2 of the channel's samples with U > 0
  std::vector<double> predicted;      // at every error time
  Indicators training, validation;
  bool has_validation = false;
};

// Index of the first validation sample for a training fraction in (0, 1].
int trainingEnd(int samples, double fraction);

ChannelFit fitChannel(const Campaign& c, const std::string& channel, const std::vector<Effect>& effects, int train_end);

// The unit of an effect's gain for a channel ("um/K", "urad/rpm", ...).
std::string inputUnit(const std::string& column);

}  // namespace probeloop::model
