// Adaptive replay of Thermal Adaptive Learning Control (seed 004 Ch. 6, Tables 6.4-6.7) over a
// campaign whose measurement cycle ran densely (every few minutes, as the thesis did "for
// visualisation", L1776): the replay decides which of those measurements TALC would have taken,
// feeds only those to per-channel ARX models, and scores the compensated residual at every
// dense measurement.
//
// Time base. t0 = the first error time; the dense step D = the median spacing of the error
// times; the prediction grid is t0 + k D (the CP measurement interval, as in the thesis: the
// predictions are made at the CP interval). Measurement j sits at grid index round((t_j-t0)/D)
// (two on one index: the later one feeds back). Inputs are linearly interpolated at the grid
// times (held at the ends); a temperature column (name ending in _C or _K) enters as its
// change since t0; "|name|" selects the absolute value of a column (e.g. "|c_rpm|").
//
// Schedule (all times nominal, a measurement is taken when it is the first dense one at or
// after its nominal time, tolerance D/4; a dense measurement is taken at most once):
// - Calibration phase (CP): every dense measurement with t - t0 <= CP. Compensation is off:
//   the compensated residual equals the measurement. cp_h = 0 asks for the shortest CP ("as
//   short as possible", Table 6.4) that passes both criteria below.
// - The first fit at the CP's end; then post-CP measurements at t0 + CP + i * post interval.
// - After a taken post-CP measurement, each channel's residual (measured - predicted) is
//   compared with its action limit (channels *_um: limit_linear_um, *_urad: limit_angular_urad,
//   1 um/m = 1 urad); any |residual| > limit starts one No-Good (NG) phase: ng_measurements
//   more at t_trigger + i * ng_interval. Exceedances during an NG are logged as ignored.
// - Parameter update (all channels, WLS Eq. 4.20 on everything stored so far) right after
//   the NG phase's last measurement, and periodically: update_interval_h after the previous
//   update of either kind (the timer restarts at every update; one falling due during an NG
//   is folded into the NG's closing update). update_interval_h = 0: never periodically.
//   After an NG the post-CP clock restarts at its last measurement.
// Prediction (simulation mode, Ch. 6): at each grid index the model of the last update
// predicts from the inputs and the stored past outputs; the stored value is the measurement
// where one was taken, the prediction otherwise (state update). A measurement's compensated
// residual is measured - predicted at its grid index: the model never saw it or anything
// later. Uncompensated = the measurement itself (errors.csv is relative to cycle 1).
// Weights (Eq. 4.20): a regression row whose target is a taken measurement weighs 1, one
// whose target is a stored prediction (or, in the CP, a gap filled by interpolation) weighs
// predicted_weight (default 0.1; the thesis gives no number; on three simulated 72 h
// campaigns 0 .. 0.1 scored alike, 1 (trusting the model's own outputs as much as the
// measurements) slowed the adaptation and cost more NG phases); optionally halved every
// weight_half_life_h back from the update time. The orders are given, not selected, so the
// thesis's 60/40 split of the CP (which guards the order choice) has no role here.
// Scores: P99 = Hazen percentile (model/indicators.hpp) of |values| over the compensation
// phase (after the CP; include_cp = true: all), unrounded here, rounded to 0.1 by talcText as
// Tables 6.5/6.7; reduction % = 100 (1 - C/UC) from the unrounded values (the thesis's
// percentages were, notes §7.4). Q_Prod (Eq. 6.1) = 100 (1 - N t_M / t_total), N = taken
// measurements, t_M = cycle_duration_s, t_total = span of the dense measurements + D (each
// measurement owns one dense interval, so taking all gives 1 - t_M/D, the CP's "~75 %").
//
// Contract: replayTalc refuses (InputError, saying what to change)
// - a CP shorter than the thesis's criterion (sum of the orders x interval) or than the
//   full-rank one (max lag + parameters + 1 samples), saying how long it must be; a CP whose
//   data leave a parameter unidentified (rank), saying from which CP length on these data
//   every channel is identifiable (or that the campaign is too short);
// - an input or channel that does not exist (listing those that do), a channel unit other
//   than um / urad, non-positive intervals, ng_measurements < 1, predicted_weight outside
//   [0, 1], fewer than 3 error samples;
// and returns no NaN. An update whose fit fails keeps the previous model (event logged); an
// unstable fit is used as the thesis would, and named in its event.
#pragma once
#include <string>
#include <vector>

#include "model/dataset.hpp"

namespace probeloop::model {

struct TalcOptions {
  double cp_h = 24;  // 0 = as short as possible (ASAP)
  double post_interval_h = 2;
  double ng_interval_min = 10;
  int ng_measurements = 12;
  double update_interval_h = 24;  // 0 = no periodic update
  double limit_linear_um = 5;
  double limit_angular_urad = 15;  // 15 um/m
  int na = 1;
  int nb = 5;                     // per input
  std::vector<int> nb_per_input;  // overrides nb when not empty (one per input)
  bool instantaneous = true;      // b_i0 u_i[k] (seed 004 Eq. 4.3)
  bool intercept = false;
  double predicted_weight = 0.1;      // WLS weight of rows whose target is a prediction (measured: 1)
  double weight_half_life_h = 0;      // 0 = no forgetting
  double cycle_duration_s = 95;       // t_M of Eq. 6.1 (L1642)
  bool include_cp = false;            // P99 over the whole campaign instead of after the CP
  std::vector<std::string> inputs;    // default: every temperature column (*_C, *_K)
  std::vector<std::string> channels;  // default: every error channel
};

struct TalcChannelResult {
  std::string channel, unit;
  double limit = 0;
  double p99_uncompensated = 0, p99_compensated = 0, reduction_percent = 0;
  int ng_triggers = 0;                             // NG phases this channel's residual started
  int exceedances_ignored = 0;                     // taken during an NG, beyond the limit
  int exceedances_unseen = 0;                      // beyond the limit at a dense measurement TALC did not take
  std::vector<double> uncompensated, compensated;  // at every dense measurement
};

struct TalcEvent {
  double t_s = 0;
  std::string channel;  // empty for an update
  double residual = 0;  // measured - predicted (0 for an update)
  std::string action;   // "NG start", "ignored (NG active)", "first fit", "update after NG",
                        // "periodic update", "update failed, previous model kept: <why>";
                        // a fit with a pole |z| >= 1 (diverges between measurements) appends
                        // "; unstable: <channel> (|pole| x)"
};

struct TalcReplay {
  std::vector<TalcChannelResult> channels;
  std::vector<TalcEvent> events;
  std::vector<std::string> inputs;  // as used ("T_env_C - start", "|c_rpm|")
  std::vector<double> time_s;       // dense measurement times
  std::vector<char> taken;          // per dense measurement: TALC took it
  std::vector<char> in_cp;          // per dense measurement: within the CP
  double dense_step_s = 0;          // D, also the prediction grid
  double cp_h = 0;                  // as used (the ASAP length when asked for)
  double cp_required_h = 0;         // shortest CP the orders admit (both criteria); the data may need more
  int ng_phases = 0, updates_after_ng = 0, updates_periodic = 0;
  int measurements_taken = 0, measurements_available = 0;
  double q_prod_percent = 0;          // over the whole campaign
  double q_prod_post_cp_percent = 0;  // after the CP
};

TalcReplay replayTalc(const Campaign& c, const TalcOptions& o);

// The input columns TALC uses (TalcOptions::inputs, default every temperature column) and one
// row of them at time t: linearly interpolated, held at the ends, a temperature as its change
// since t0, "|name|" as the absolute value. InputError for a name that is not a column.
struct TalcInputColumns {
  std::vector<std::string> labels;  // "T_env_C - start", "|c_rpm|"
  std::vector<int> column;
  std::vector<char> absolute, relative;
};
TalcInputColumns resolveTalcInputs(const InputSeries& in, const std::vector<std::string>& asked);
std::vector<double> talcInputRow(const TalcInputColumns& c, const InputSeries& in, double t_s, double t0_s);

// Table 6.5/6.7 layout: one column per channel, rows P99 UC, P99 C (0.1 in the channel's
// unit), reduction % (0.1); then the schedule summary and the event list.
std::string talcText(const TalcReplay& r);

}  // namespace probeloop::model
