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

namespace probeloop::model {
namespace {

std::string fmt(double v, int decimals) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(decimals) << v;
  std::string r = s.str();
  if (r == "-0" || r.rfind("-0.", 0) == 0) {  // no "-0.0" for a value that rounds to zero
    bool zero = true;
    for (char ch : r)
      if (ch >= '1' && ch <= '9') zero = false;
    if (zero) r.erase(0, 1);
  }
  return r;
}

std::string hours(double s) { return fmt(s / 3600.0, 2) + " h"; }

bool isTemperature(const std::string& name) {
  return name.size() > 2 &&
         (name.compare(name.size() - 2, 2, "_C") == 0 || name.compare(name.size() - 2, 2, "_K") == 0);
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

struct InputSpec {
  int column = -1;
  bool absolute = false, relative = false;
  std::string label;
};

std::vector<InputSpec> resolveInputs(const InputSeries& in, const std::vector<std::string>& asked) {
  std::vector<std::string> names = asked;
  if (names.empty())
    for (const auto& n : in.names)
      if (isTemperature(n)) names.push_back(n);
  if (names.empty())
    throw InputError(
        in.file, 0,
        "no temperature column (*_C, *_K) to use as TALC input; name the inputs (columns: " + joined(in.names) + ")");
  std::vector<InputSpec> out;
  for (const auto& raw : names) {
    InputSpec s;
    std::string n = raw;
    if (n.size() > 2 && n.front() == '|' && n.back() == '|') {
      s.absolute = true;
      n = n.substr(1, n.size() - 2);
    }
    s.column = in.column(n);
    if (s.column < 0)
      throw InputError(in.file, 0,
                       "TALC input '" + raw + "' is not a column of the inputs (columns: " + joined(in.names) +
                           "; '|name|' takes the absolute value)");
    s.relative = !s.absolute && isTemperature(n);
    s.label = s.absolute ? raw : s.relative ? n + " - start" : n;
    out.push_back(s);
  }
  return out;
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

// A fit that can fail (rank, constant input): the reason instead of an exception.
struct Attempt {
  std::optional<ArxModel> model;
  std::string reason;
};

Attempt tryFit(const Eigen::VectorXd& y, const Eigen::MatrixXd& u, const ArxOrders& o,
               const std::vector<std::string>& names, const Eigen::VectorXd& w) {
  Attempt a;
  try {
    a.model = fitArx(y, u, o, names, &w);
  } catch (const GeometryError& e) {
    a.reason = e.what();
  } catch (const InputError& e) {
    a.reason = e.what();
  }
  return a;
}

// Largest |pole| of A(q) = 1 + a_1 q^-1 + ... (roots of z^na + a_1 z^(na-1) + ... + a_na).
double spectralRadius(const ArxModel& m) {
  const auto n = static_cast<Eigen::Index>(m.a.size());
  if (n == 0) return 0;
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) comp(0, i) = -m.a[static_cast<std::size_t>(i)];
  for (Eigen::Index i = 1; i < n; ++i) comp(i, i - 1) = 1;
  return comp.eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace

TalcReplay replayTalc(const Campaign& c, const TalcOptions& o) {
  using std::size_t;
  // --- options ---------------------------------------------------------------------------
  auto positive = [](double v, const char* what) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError("", 0, std::string("TALC: ") + what + " must be a positive number of the stated unit");
  };
  if (!(o.cp_h >= 0) || !std::isfinite(o.cp_h))
    throw InputError("", 0, "TALC: the calibration phase must be >= 0 h (0 = as short as possible)");
  positive(o.post_interval_h, "the post-CP measurement interval (h)");
  positive(o.ng_interval_min, "the NG measurement interval (min)");
  positive(o.limit_linear_um, "the linear action limit (um)");
  positive(o.limit_angular_urad, "the angular action limit (urad = um/m)");
  if (!(o.cycle_duration_s >= 0) || !std::isfinite(o.cycle_duration_s))
    throw InputError("", 0, "TALC: the cycle duration must be >= 0 s");
  if (!(o.update_interval_h >= 0) || !std::isfinite(o.update_interval_h))
    throw InputError("", 0, "TALC: the parameter update interval must be >= 0 h (0 = no periodic update)");
  if (!(o.weight_half_life_h >= 0) || !std::isfinite(o.weight_half_life_h))
    throw InputError("", 0, "TALC: the weight half-life must be >= 0 h (0 = no forgetting)");
  if (o.ng_measurements < 1) throw InputError("", 0, "TALC: an NG phase needs at least 1 measurement");
  if (!(o.predicted_weight >= 0 && o.predicted_weight <= 1))
    throw InputError("", 0, "TALC: the weight of predicted samples must lie in [0, 1] (measured ones weigh 1)");
  if (o.na < 0) throw InputError("", 0, "TALC: na must be >= 0");

  const ErrorSeries& E = c.errors;
  const size_t M = E.t_s.size();
  if (M < 3) throw InputError(E.file, 0, "TALC needs a dense series of measurements; there are " + std::to_string(M));

  // --- channels, inputs, orders ----------------------------------------------------------
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
  const size_t C = ch.size();
  std::vector<double> limit(C);
  for (size_t q = 0; q < C; ++q) {
    const std::string& name = E.channels[ch[q]];
    const std::string unit = channelUnit(name);
    if (unit == "um")
      limit[q] = o.limit_linear_um;
    else if (unit == "urad")
      limit[q] = o.limit_angular_urad;
    else
      throw InputError(E.file, 0,
                       "TALC: channel " + name + " has unit '" + unit +
                           "'; the action limits are for *_um (linear) and *_urad (angular, 1 urad = 1 um/m)");
  }
  const std::vector<InputSpec> specs = resolveInputs(c.inputs, o.inputs);
  const int r = static_cast<int>(specs.size());
  ArxOrders orders;
  orders.na = o.na;
  orders.instantaneous = o.instantaneous;
  orders.intercept = o.intercept;
  if (o.nb_per_input.empty()) {
    orders.nb.assign(specs.size(), o.nb);
  } else {
    if (o.nb_per_input.size() != specs.size())
      throw InputError(
          "", 0,
          "TALC: " + std::to_string(o.nb_per_input.size()) + " input orders for " + std::to_string(r) + " inputs");
    orders.nb = o.nb_per_input;
  }
  for (int n : orders.nb)
    if (n < 1) throw InputError("", 0, "TALC: every input order nb must be >= 1");
  std::vector<std::string> input_names;
  for (const auto& s : specs) input_names.push_back(s.label);

  // --- time base: dense step D, prediction grid t0 + k D, measurement j at grid index g[j] --
  const std::vector<double>& t = E.t_s;
  const double t0 = t.front();
  std::vector<double> d;
  for (size_t j = 1; j < M; ++j) d.push_back(t[j] - t[j - 1]);
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  const double D = d[d.size() / 2];
  const double tol = D / 4;
  std::vector<int> g(M);
  for (size_t j = 0; j < M; ++j) g[j] = static_cast<int>(std::lround((t[j] - t0) / D));
  const int K = g.back() + 1;
  auto tg = [&](int k) { return t0 + k * D; };

  Eigen::MatrixXd U(K, r);
  for (int i = 0; i < r; ++i) {
    const InputSpec& sp = specs[static_cast<size_t>(i)];
    const auto& col = c.inputs.columns[static_cast<size_t>(sp.column)];
    const double start = interpolate(c.inputs.t_s, col, t0);
    for (int k = 0; k < K; ++k) {
      double v = interpolate(c.inputs.t_s, col, tg(k));
      if (sp.absolute) v = std::fabs(v);
      if (sp.relative) v -= start;
      U(k, i) = v;
    }
  }

  // Measurements on the grid (NaN where none; the later of two on one index).
  std::vector<Eigen::VectorXd> meas(C, Eigen::VectorXd::Constant(K, std::numeric_limits<double>::quiet_NaN()));
  for (size_t q = 0; q < C; ++q)
    for (size_t j = 0; j < M; ++j) meas[q](g[j]) = E.values[ch[q]][j];

  // The CP's stored series up to index kend: measured values, gaps interpolated (weighted as
  // predicted).
  auto cpSeries = [&](size_t q, int kend, Eigen::VectorXd& y, Eigen::VectorXd& w) {
    y.resize(kend + 1);
    w.resize(kend + 1);
    const Eigen::VectorXd& m = meas[q];
    int prev = -1;  // g[0] = 0 holds a measurement
    for (int k = 0; k <= kend; ++k) {
      if (!std::isfinite(m(k))) continue;
      y(k) = m(k);
      w(k) = 1;
      for (int i = prev + 1; i < k; ++i) {
        y(i) = m(prev) + (m(k) - m(prev)) * (i - prev) / double(k - prev);
        w(i) = o.predicted_weight;
      }
      prev = k;
    }
    for (int i = prev + 1; i <= kend; ++i) {
      y(i) = m(prev);
      w(i) = o.predicted_weight;
    }
  };
  auto fitCp = [&](int kend, std::vector<ArxModel>& models, std::string& why) {
    models.clear();
    for (size_t q = 0; q < C; ++q) {
      Eigen::VectorXd y, w;
      cpSeries(q, kend, y, w);
      Attempt a = tryFit(y, U.topRows(kend + 1), orders, input_names, w);
      if (!a.model) {
        why = E.channels[ch[q]] + ": " + a.reason;
        return false;
      }
      models.push_back(*a.model);
    }
    return true;
  };

  // --- calibration phase -----------------------------------------------------------------
  const int L = orders.maxLag(), p = orders.parameterCount();
  int sum_orders = orders.na;
  for (int n : orders.nb) sum_orders += n;
  const double thesis_s = sum_orders * D, rank_s = (L + p) * D;
  const double required_s = std::max(thesis_s, rank_s);
  std::ostringstream orders_text;
  orders_text << "na = " << orders.na << ", nb = ";
  for (size_t i = 0; i < orders.nb.size(); ++i) orders_text << (i ? "/" : "") << orders.nb[i];
  orders_text << " for " << r << " input" << (r == 1 ? "" : "s") << (orders.intercept ? " and an intercept" : "");
  const double span_s = t.back() - t0;
  if (required_s > span_s)
    throw InputError(E.file, 0,
                     "TALC: the campaign (" + hours(span_s) + ") is shorter than the shortest calibration phase for " +
                         orders_text.str() + " (" + hours(required_s) + "); lower the orders or measure longer");

  std::vector<ArxModel> models;
  int k_cp = 0;  // last grid index of the CP
  double cp_s = 0;
  if (o.cp_h == 0) {  // ASAP: the shortest CP on which every channel's fit is full-rank
    std::string why;
    int k = static_cast<int>(std::ceil(required_s / D - 1e-9));
    for (; k < K - 1; ++k)
      if (fitCp(k, models, why)) break;
    if (k >= K - 1)
      throw InputError(E.file, 0,
                       "TALC: no calibration phase within the campaign identifies every channel (" + why +
                           "); lower the orders, change the inputs or measure longer");
    k_cp = k;
    cp_s = k * D;
  } else {
    cp_s = o.cp_h * 3600.0;
    if (cp_s < required_s - tol) {
      std::ostringstream m;
      m << "TALC: a calibration phase of " << hours(cp_s) << " is too short for " << orders_text.str()
        << ": it must last at least " << hours(required_s) << " (" << std::lround(required_s / D) << " intervals of "
        << fmt(D, 1) << " s: " << L << " samples of history + " << p
        << " parameters + 1, the full-rank criterion; the thesis's sum of the orders x interval gives "
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
    k_cp = g[last];
    std::string why;
    if (!fitCp(k_cp, models, why)) {
      std::vector<ArxModel> probe;
      std::string why2;
      int k = k_cp + 1;
      for (; k < K - 1; ++k)
        if (fitCp(k, probe, why2)) break;
      const std::string hint = k < K - 1 ? "on these data every channel is identifiable from a CP of " + hours(k * D)
                                         : "no CP within the campaign identifies every channel";
      throw InputError(E.file, 0,
                       "TALC: the calibration phase of " + hours(cp_s) +
                           " does not identify the model (full-rank criterion): " + why + "; " + hint);
    }
  }

  // --- replay ----------------------------------------------------------------------------
  TalcReplay R;
  R.inputs = input_names;
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
    cr.channel = E.channels[ch[q]];
    cr.unit = channelUnit(cr.channel);
    cr.limit = limit[q];
    cr.uncompensated = E.values[ch[q]];
    cr.compensated = cr.uncompensated;  // compensation is off in the CP
  }

  // Stored series S (measured where taken, predicted otherwise) and which indices were measured.
  std::vector<Eigen::VectorXd> S(C, Eigen::VectorXd::Zero(K));
  std::vector<char> measured(static_cast<size_t>(K), 0);
  for (size_t q = 0; q < C; ++q) {
    Eigen::VectorXd y, w;
    cpSeries(q, k_cp, y, w);
    S[q].head(k_cp + 1) = y;
  }
  for (size_t j = 0; j < M && g[j] <= k_cp; ++j) {
    R.taken[j] = R.in_cp[j] = 1;
    measured[static_cast<size_t>(g[j])] = 1;
  }
  // A fit whose A(q) has a pole on or outside the unit circle diverges between measurements
  // in simulation mode: said in the event, never silently.
  auto stability = [&](const std::vector<ArxModel>& ms) {
    std::string s;
    for (size_t q = 0; q < C; ++q) {
      const double rho = spectralRadius(ms[q]);
      if (rho >= 1) s += (s.empty() ? "; unstable: " : ", ") + R.channels[q].channel + " (|pole| " + fmt(rho, 3) + ")";
    }
    return s;
  };
  R.events.push_back({tg(k_cp), "", 0, "first fit" + stability(models)});

  // Refit every channel on the stored series up to kend (WLS, Eq. 4.20); effective from t_effect.
  auto update = [&](int kend, double t_effect, bool after_ng) {
    Eigen::VectorXd w(kend + 1);
    for (int k = 0; k <= kend; ++k) {
      w(k) = measured[static_cast<size_t>(k)] ? 1.0 : o.predicted_weight;
      if (o.weight_half_life_h > 0) w(k) *= std::exp2(-(tg(kend) - tg(k)) / (o.weight_half_life_h * 3600.0));
    }
    std::vector<ArxModel> next;
    for (size_t q = 0; q < C; ++q) {
      Attempt a = tryFit(S[q].head(kend + 1), U.topRows(kend + 1), orders, input_names, w);
      if (!a.model) {
        R.events.push_back(
            {t_effect, "", 0, "update failed, previous model kept: " + R.channels[q].channel + ": " + a.reason});
        return;
      }
      next.push_back(*a.model);
    }
    models = std::move(next);
    R.events.push_back({t_effect, "", 0, (after_ng ? "update after NG" : "periodic update") + stability(models)});
    (after_ng ? R.updates_after_ng : R.updates_periodic)++;
  };

  std::vector<Eigen::VectorXd> pred(C, Eigen::VectorXd::Zero(K));
  const double post_s = o.post_interval_h * 3600.0, ng_s = o.ng_interval_min * 60.0;
  const double upd_s = o.update_interval_h * 3600.0;
  double last_update = tg(k_cp);
  double next_post = t0 + cp_s + post_s;  // nominal time of the next post-CP measurement
  bool ng = false;
  int ng_count = 0;
  double next_ng = 0;  // nominal time of the next NG measurement
  int done = k_cp;     // predictions exist up to this grid index

  // Predictions up to grid index kto (simulation mode from the stored series), with the
  // periodic updates that fall due on the way.
  auto advance = [&](int kto) {
    for (int k = done + 1; k <= kto; ++k) {
      if (!ng && upd_s > 0 && tg(k) >= last_update + upd_s - tol) {
        update(k - 1, tg(k), false);
        last_update = tg(k);
      }
      const Eigen::MatrixXd window = U.middleRows(k - L, L + 1);
      for (size_t q = 0; q < C; ++q) {
        const double v = simulate(models[q], window, S[q].segment(k - L, L))(L);
        pred[q](k) = S[q](k) = v;
      }
    }
    done = std::max(done, kto);
  };

  std::vector<double> res(C);
  for (size_t j = 0; j < M; ++j) {
    const int k = g[j];
    if (k <= k_cp) continue;
    advance(k);
    const double tj = t[j];
    for (size_t q = 0; q < C; ++q) R.channels[q].compensated[j] = res[q] = R.channels[q].uncompensated[j] - pred[q](k);
    auto beyond = [&](size_t q) { return std::fabs(res[q]) > limit[q]; };
    const bool take = ng ? tj >= next_ng - tol : tj >= next_post - tol;
    if (!take) {
      for (size_t q = 0; q < C; ++q)
        if (beyond(q)) R.channels[q].exceedances_unseen++;
      continue;
    }
    R.taken[j] = 1;
    measured[static_cast<size_t>(k)] = 1;
    for (size_t q = 0; q < C; ++q) S[q](k) = R.channels[q].uncompensated[j];  // state update
    if (ng) {
      for (size_t q = 0; q < C; ++q)
        if (beyond(q)) {
          R.channels[q].exceedances_ignored++;
          R.events.push_back({tj, R.channels[q].channel, res[q], "ignored (NG active)"});
        }
      if (next_ng <= tj + tol) next_ng += ng_s * (std::floor((tj + tol - next_ng) / ng_s) + 1);  // no loop: a tiny interval cannot spin
      if (++ng_count == o.ng_measurements) {
        ng = false;
        update(k, tj, true);
        last_update = tj;
        next_post = tj + post_s;
      }
      continue;
    }
    if (next_post <= tj + tol) next_post += post_s * (std::floor((tj + tol - next_post) / post_s) + 1);
    bool start = false;
    for (size_t q = 0; q < C; ++q)
      if (beyond(q)) {
        start = true;
        R.channels[q].ng_triggers++;
        R.events.push_back({tj, R.channels[q].channel, res[q], "NG start"});
      }
    if (start) {
      ng = true;
      ng_count = 0;
      next_ng = tj + ng_s;
      R.ng_phases++;
    }
  }

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
