#include "model/talc.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>

#include "core/error.hpp"
#include "model/arx.hpp"
#include "model/indicators.hpp"
#include "model/talc_controller.hpp"
#include "model/talc_detail.hpp"

namespace probeloop::model {
namespace {

using talc_detail::fmt;
using talc_detail::hours;
using talc_detail::joined;

bool isTemperature(const std::string& name) {
  return name.size() > 2 &&
         (name.compare(name.size() - 2, 2, "_C") == 0 || name.compare(name.size() - 2, 2, "_K") == 0);
}

// Linear interpolation of a grid series at time t, held at the ends.
double interpolate(const std::vector<double>& t, const std::vector<double>& v, double x) {
  if (x <= t.front()) return v.front();
  if (x >= t.back()) return v.back();
  const auto it = std::upper_bound(t.begin(), t.end(), x);
  const auto i = static_cast<std::size_t>(it - t.begin());
  const double w = (x - t[i - 1]) / (t[i] - t[i - 1]);
  return v[i - 1] + w * (v[i] - v[i - 1]);
}

}  // namespace

TalcInputColumns resolveTalcInputs(const InputSeries& in, const std::vector<std::string>& asked) {
  std::vector<std::string> names = asked;
  if (names.empty())
    for (const auto& n : in.names)
      if (isTemperature(n)) names.push_back(n);
  if (names.empty())
    throw InputError(
        in.file, 0,
        "no temperature column (*_C, *_K) to use as TALC input; name the inputs (columns: " + joined(in.names) + ")");
  TalcInputColumns out;
  for (const auto& raw : names) {
    std::string n = raw;
    bool absolute = false;
    if (n.size() > 2 && n.front() == '|' && n.back() == '|') {
      absolute = true;
      n = n.substr(1, n.size() - 2);
    }
    const int column = in.column(n);
    if (column < 0)
      throw InputError(in.file, 0,
                       "TALC input '" + raw + "' is not a column of the inputs (columns: " + joined(in.names) +
                           "; '|name|' takes the absolute value)");
    const bool relative = !absolute && isTemperature(n);
    out.column.push_back(column);
    out.absolute.push_back(absolute);
    out.relative.push_back(relative);
    out.labels.push_back(absolute ? raw : relative ? n + " - start" : n);
  }
  return out;
}

std::vector<double> talcInputRow(const TalcInputColumns& c, const InputSeries& in, double t_s, double t0_s) {
  std::vector<double> row;
  for (std::size_t i = 0; i < c.column.size(); ++i) {
    const auto& col = in.columns[static_cast<std::size_t>(c.column[i])];
    double v = interpolate(in.t_s, col, t_s);
    if (c.absolute[i]) v = std::fabs(v);
    if (c.relative[i]) v -= interpolate(in.t_s, col, t0_s);
    row.push_back(v);
  }
  return row;
}

TalcReplay replayTalc(const Campaign& c, const TalcOptions& o) {
  using std::size_t;
  const ErrorSeries& E = c.errors;
  const size_t M = E.t_s.size();

  // --- channels, inputs, time base -------------------------------------------------------
  std::vector<size_t> ch;  // selected channels (indices into E)
  if (o.channels.empty()) {
    for (size_t i = 0; i < E.channels.size(); ++i) ch.push_back(i);
  } else {
    for (const auto& n : o.channels) {
      const int i = E.channel(n);
      if (i < 0)
        throw InputError(E.file, 0, "TALC: no error channel '" + n + "' (channels: " + joined(E.channels) + ")");
      ch.push_back(static_cast<size_t>(i));
    }
  }
  std::vector<std::string> names;
  for (size_t q : ch) names.push_back(E.channels[q]);
  const TalcInputColumns inputs = resolveTalcInputs(c.inputs, o.inputs);
  if (M < 3) {
    TalcController check(o, names, inputs.labels, 1.0, 0.0);  // the options' errors first
    throw InputError(E.file, 0, "TALC needs a dense series of measurements; there are " + std::to_string(M));
  }
  // The dense step D (median spacing) is the prediction grid t0 + k D; measurement j sits at
  // grid index g[j].
  const std::vector<double>& t = E.t_s;
  const double t0 = t.front();
  std::vector<double> d;
  for (size_t j = 1; j < M; ++j) d.push_back(t[j] - t[j - 1]);
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  const double D = d[d.size() / 2];
  const double tol = D / 4;
  auto newController = [&] {
    TalcController tc(o, names, inputs.labels, D, t0);
    for (int k = 0; k <= tc.gridIndex(t.back()); ++k) tc.appendInputRow(talcInputRow(inputs, c.inputs, t0 + k * D, t0));
    return tc;
  };
  TalcController tc = newController();
  const size_t C = ch.size();
  std::vector<int> g(M);
  for (size_t j = 0; j < M; ++j) g[j] = tc.gridIndex(t[j]);
  const int K = g.back() + 1;
  auto values = [&](size_t j) {
    std::vector<double> v;
    for (size_t q : ch) v.push_back(E.values[q][j]);
    return v;
  };

  // --- calibration phase -----------------------------------------------------------------
  const double required_s = tc.cpRequiredS();
  const double span_s = t.back() - t0;
  if (required_s > span_s)
    throw InputError(E.file, 0,
                     "TALC: the campaign (" + hours(span_s) + ") is shorter than the shortest calibration phase for " +
                         tc.ordersText() + " (" + hours(required_s) + "); lower the orders or measure longer");
  // The shortest CP from k on that identifies every channel, on the whole campaign's data.
  auto firstIdentifying = [&](int k, std::string& why) {
    TalcController probe = newController();
    for (size_t j = 0; j < M; ++j) probe.measure(t[j], values(j));
    for (; k < K - 1; ++k)
      if (probe.calibrationFits(k, why)) return k;
    return K - 1;
  };
  size_t j_next = 0;  // first measurement not fed yet
  double cp_s = 0;
  if (o.cp_h == 0) {  // ASAP: the shortest CP on which every channel's fit is full-rank
    std::string why;
    const int k = firstIdentifying(static_cast<int>(std::ceil(required_s / D - 1e-9)), why);
    if (k >= K - 1)
      throw InputError(E.file, 0,
                       "TALC: no calibration phase within the campaign identifies every channel (" + why +
                           "); lower the orders, change the inputs or measure longer");
    for (; j_next < M && g[j_next] <= k; ++j_next) tc.measure(t[j_next], values(j_next));
    cp_s = k * D;
    if (!tc.closeCalibration(k, cp_s, why)) throw std::logic_error("TALC: the ASAP calibration fit failed twice");
  } else {
    cp_s = o.cp_h * 3600.0;
    int sum_orders = tc.orders().na;
    for (int n : tc.orders().nb) sum_orders += n;
    const double thesis_s = sum_orders * D;
    if (cp_s < required_s - tol) {
      std::ostringstream m;
      m << "TALC: a calibration phase of " << hours(cp_s) << " is too short for " << tc.ordersText()
        << ": it must last at least " << hours(required_s) << " (" << std::lround(required_s / D)
        << " intervals of " << fmt(D, 1) << " s: " << tc.orders().maxLag() << " samples of history + "
        << tc.orders().parameterCount() << " parameters + 1, the full-rank criterion; the thesis's sum of the orders x interval gives "
        << hours(thesis_s) << ")";
      throw InputError("", 0, m.str());
    }
    size_t last = 0;
    for (size_t j = 0; j < M; ++j)
      if (t[j] - t0 <= cp_s + tol) last = j;
    if (last == M - 1)
      throw InputError("", 0,
                       "TALC: the calibration phase (" + hours(cp_s) + ") covers the whole campaign (" + hours(span_s) +
                           "): nothing is left to compensate");
    for (; j_next <= last; ++j_next) tc.measure(t[j_next], values(j_next));
    std::string why;
    if (!tc.closeCalibration(g[last], cp_s, why)) {
      std::string why2;
      const int k = firstIdentifying(g[last] + 1, why2);
      const std::string hint = k < K - 1 ? "on these data every channel is identifiable from a CP of " + hours(k * D)
                                         : "no CP within the campaign identifies every channel";
      throw InputError(E.file, 0,
                       "TALC: the calibration phase of " + hours(cp_s) +
                           " does not identify the model (full-rank criterion): " + why + "; " + hint);
    }
  }

  // --- replay ----------------------------------------------------------------------------
  TalcReplay R;
  R.inputs = inputs.labels;
  R.time_s = t;
  R.taken.assign(M, 0);
  R.in_cp.assign(M, 0);
  R.dense_step_s = D;
  R.cp_h = cp_s / 3600.0;
  R.cp_required_h = required_s / 3600.0;
  R.measurements_available = static_cast<int>(M);
  R.channels.resize(C);
  for (size_t q = 0; q < C; ++q) {
    auto& cr = R.channels[q];
    cr.channel = names[q];
    cr.unit = channelUnit(cr.channel);
    cr.limit = tc.limits()[q];
    cr.uncompensated = E.values[ch[q]];
    cr.compensated = cr.uncompensated;  // compensation is off in the CP
  }
  for (size_t j = 0; j < j_next; ++j) R.taken[j] = R.in_cp[j] = 1;
  for (size_t j = j_next; j < M; ++j) {
    const std::vector<double> pred = tc.predict(g[j]);
    for (size_t q = 0; q < C; ++q) R.channels[q].compensated[j] = R.channels[q].uncompensated[j] - pred[q];
    auto beyond = [&](size_t q) { return std::fabs(R.channels[q].compensated[j]) > R.channels[q].limit; };
    if (!tc.wants(t[j])) {
      for (size_t q = 0; q < C; ++q)
        if (beyond(q)) R.channels[q].exceedances_unseen++;
      continue;
    }
    R.taken[j] = 1;
    const bool ng = tc.phase() == TalcPhase::no_good;
    tc.measure(t[j], values(j));
    for (size_t q = 0; q < C; ++q)
      if (beyond(q)) (ng ? R.channels[q].exceedances_ignored : R.channels[q].ng_triggers)++;
  }
  R.events = tc.events();
  R.ng_phases = tc.ngPhases();
  R.updates_after_ng = tc.updatesAfterNg();
  R.updates_periodic = tc.updatesPeriodic();

  // --- scores ----------------------------------------------------------------------------
  for (auto& cr : R.channels) {
    std::vector<double> uc, cc;
    for (size_t j = 0; j < M; ++j)
      if (o.include_cp || !R.in_cp[j]) {
        uc.push_back(std::fabs(cr.uncompensated[j]));
        cc.push_back(std::fabs(cr.compensated[j]));
      }
    cr.p99_uncompensated = hazenPercentile(uc, 0.99);
    cr.p99_compensated = hazenPercentile(cc, 0.99);
    cr.reduction_percent = cr.p99_uncompensated > 0 ? 100.0 * (1.0 - cr.p99_compensated / cr.p99_uncompensated) : 0.0;
  }
  int n_post = 0;
  double t_last_cp = t0;
  for (size_t j = 0; j < M; ++j) {
    if (R.taken[j]) R.measurements_taken++;
    if (R.in_cp[j])
      t_last_cp = t[j];
    else if (R.taken[j])
      n_post++;
  }
  R.q_prod_percent = 100.0 * (1.0 - R.measurements_taken * o.cycle_duration_s / (span_s + D));
  const double post_span = t.back() - t_last_cp;
  R.q_prod_post_cp_percent = post_span > 0 ? 100.0 * (1.0 - n_post * o.cycle_duration_s / post_span) : 0.0;
  return R;
}

std::string talcText(const TalcReplay& r) {
  std::ostringstream s;
  s << "TALC replay (seed 004 Ch. 6): calibration phase " << fmt(r.cp_h, 2) << " h (shortest admissible for the orders "
    << fmt(r.cp_required_h, 2) << " h), prediction grid " << fmt(r.dense_step_s, 1) << " s\n";
  s << "inputs: " << joined(r.inputs) << "\n";
  s << "P99 (Hazen) of |error|, rounded to 0.1 as seed 004 Tables 6.5/6.7; reduction from the unrounded values\n\n";
  std::vector<std::size_t> w;
  s << std::left << std::setw(12) << "";
  for (const auto& c : r.channels) {
    w.push_back(std::max<std::size_t>(c.channel.size(), 11) + 2);
    s << std::right << std::setw(static_cast<int>(w.back())) << c.channel;
  }
  s << "\n";
  auto row = [&](const std::string& label, auto value) {
    s << std::left << std::setw(12) << label;
    for (std::size_t i = 0; i < r.channels.size(); ++i)
      s << std::right << std::setw(static_cast<int>(w[i])) << value(r.channels[i]);
    s << "\n";
  };
  row("P99_UC", [](const TalcChannelResult& c) { return fmt(c.p99_uncompensated, 1) + " " + c.unit; });
  row("P99_C", [](const TalcChannelResult& c) { return fmt(c.p99_compensated, 1) + " " + c.unit; });
  row("Reduction", [](const TalcChannelResult& c) { return fmt(c.reduction_percent, 1) + " %"; });
  row("NG starts", [](const TalcChannelResult& c) { return std::to_string(c.ng_triggers); });
  row("unseen >lim", [](const TalcChannelResult& c) { return std::to_string(c.exceedances_unseen); });
  s << "\nmeasurements taken: " << r.measurements_taken << " of " << r.measurements_available << "; Q_Prod "
    << fmt(r.q_prod_percent, 1) << " % (after the CP " << fmt(r.q_prod_post_cp_percent, 1) << " %)\n";
  s << "NG phases: " << r.ng_phases << "; parameter updates: " << r.updates_after_ng << " after NG, "
    << r.updates_periodic << " periodic\n\nevents:\n";
  s << std::right << std::setw(10) << "t [h]"
    << "  " << std::left << std::setw(12) << "channel" << std::right << std::setw(10) << "residual"
    << "  action\n";
  for (const auto& e : r.events) {
    s << std::right << std::setw(10) << fmt(e.t_s / 3600.0, 3) << "  " << std::left << std::setw(12)
      << (e.channel.empty() ? "-" : e.channel) << std::right << std::setw(10)
      << (e.channel.empty() ? "" : fmt(e.residual, 2)) << "  " << e.action << "\n";
  }
  return s.str();
}

}  // namespace probeloop::model
