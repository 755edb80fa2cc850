#include "model/diagnose.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/outputs.hpp"
#include "model/verdict_strength.hpp"

namespace probeloop::model {
namespace {

bool endsWith(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}
bool isTemperature(const std::string& c) { return endsWith(c, "_C") || endsWith(c, "_K"); }

double rms(const std::vector<double>& r, int from, int to) {
  if (to <= from) return 0;
  double s = 0;
  for (int k = from; k < to; ++k) s += r[k] * r[k];
  return std::sqrt(s / (to - from));
}

std::string fmt(double v, int digits) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(digits);
  o << v;
  return o.str();
}

std::string minutes(double s) {
  const double m = s / 60;
  return m >= 100 ? fmt(m / 60, 1) + " h" : fmt(m, 0) + " min";
}

// The candidates a channel does not have yet.
std::vector<Effect> candidatesFor(const Campaign& c, const ChannelModel& cm, const DiagnoseOptions& opt) {
  std::vector<Effect> out;
  auto add = [&](Effect e) {
    for (const auto& have : cm.effects)
      if (have.id() == e.id()) return;
    out.push_back(e);
  };
  add(makeEffect(EffectKind::Drift));
  // Lengths the channel already reads (a position error over a distance, static(travel_mm)):
  // a heat source's lag may act over them too, a thermal scale error (lag x lever).
  std::vector<std::string> levers;
  for (const auto& have : cm.effects)
    if (have.kind == EffectKind::Static && have.lever.empty() && endsWith(have.input, "_mm")) levers.push_back(have.input);
  for (const auto& name : c.inputs.names) {
    if (isTemperature(name)) {
      add(makeEffect(EffectKind::Static, name));
      add(makeEffect(EffectKind::Lag, name));
      if (opt.levers)
        if (const auto L = opt.levers->lengthFor(cm.channel)) {
          Effect e = makeEffect(EffectKind::Expansion, name);
          e.alpha_um_per_m_K = opt.levers->alpha_um_per_m_K;
          e.length_mm = *L;
          if (e.alpha_um_per_m_K > 0) add(e);
        }
    } else if (isForceInput(name)) {
      add(makeEffect(EffectKind::Force, name));  // a compliance, instead of a static gain on it
    } else if (name == "tool_changes") {
      add(makeEffect(EffectKind::Transient, name));
    } else if (isSpeedInput(name) || endsWith(name, "_on")) {
      add(makeEffect(EffectKind::Lag, name));
      for (const auto& L : levers) {
        Effect e = makeEffect(EffectKind::Lag, name);
        e.lever = L;
        add(e);
      }
      // A feed also loads the cut: the force grows with it at once (seed 000 Eq. 3.16).
      if (name.rfind("feed", 0) == 0) add(makeEffect(EffectKind::Static, name));
    } else {
      add(makeEffect(EffectKind::Static, name));
    }
  }
  return out;
}

std::string physics(const Effect& e, const std::string& what) {
  const std::string& in = e.input;
  switch (e.kind) {
    case EffectKind::Drift:
      return "no effect in the library explains it; a drift term is only a stand-in: look for a slow source that is not logged";
    case EffectKind::Expansion:
      return "the " + what + "'s own thermal expansion is missing (alpha L dT with alpha = " + fmt(e.alpha_um_per_m_K, 1) +
             " um/(m K), L = " + fmt(e.length_mm, 1) + " mm); correct it or keep the " + what + "'s temperature constant";
    case EffectKind::Transient:
      return "the machine settles after each tool change (a cold holder in the warm spindle); model it, or probe after it has settled";
    case EffectKind::Static:
      if (isTemperature(in)) return "the structure near that sensor expands with it, without delay";
      if (in.rfind("feed", 0) == 0)
        return "the cutting force grows with the feed (F = k_c Q / v_c) and deflects the tool and the structure; "
               "finish at a lower feed or compensate the deflection";
      if (in.rfind("transition_feed", 0) == 0)
        return "the moves that join the walls wind the drives up (lost motion held when the axis stops), the control error "
               "of seed 000 Sec. 3.6.2; join them slower, or compensate it per transition feed";
      return "the error moves with " + in + " without delay";
    case EffectKind::Lag:
      if (isSpeedInput(in) && (in.rfind("c_", 0) == 0 || in.find("rotary") != std::string::npos))
        return "a heat source in the rotary (C) axis is missing (bearing and torque motor)";
      if (in.rfind("spindle", 0) == 0) return "spindle heat is missing";
      if (in.rfind("feed", 0) == 0) return "heat from axis motion (ball screws, guides) is missing";
      if (endsWith(in, "_on")) return "the thermal effect of " + in.substr(0, in.size() - 3) + " (fluid on/off) is missing";
      if (in.find("env") != std::string::npos || in.find("hall") != std::string::npos)
        return "the hall temperature reaches the structure with a delay (a door, the day/night cycle): model it as a lag, not a static gain";
      return "the structure takes up the temperature at " + in + " with a delay";
    case EffectKind::Force:
      return "the cutting force " + in + " deflects the structure and the tool (seed 003: the crossbeam's and bed's F/(4k) "
             "and F R/(k S^2) x arm); stiffen the weak unit, lower the force, or compensate the deflection";
    case EffectKind::Offset: break;
  }
  return "";
}

std::string sentence(const Recommendation& r, const std::string& what) {
  std::string chs;
  for (std::size_t i = 0; i < r.channels.size(); ++i)
    chs += (i == 0 ? "" : i + 1 == r.channels.size() ? " and " : ", ") + r.channels[i].channel;
  const std::string verb = r.channels.size() > 1 ? " residuals follow " : " residual follows ";
  const Effect& e = r.effect;
  switch (e.kind) {
    case EffectKind::Drift: return chs + verb + "time as a steady drift: " + physics(e, what) + ".";
    case EffectKind::Expansion: return chs + verb + "the growth of the " + what + " with " + e.input + ": " + physics(e, what) + ".";
    case EffectKind::Transient:
      return chs + verb + "each tool change and settle" + (r.channels.size() > 1 ? "" : "s") + " with tau ~" +
             minutes(*e.tau_s) + ": " + physics(e, what) + ".";
    case EffectKind::Static: return chs + verb + e.input + " with no delay: " + physics(e, what) + ".";
    case EffectKind::Force: return chs + verb + "the force " + e.input + " (a compliance in um/N): " + physics(e, what) + ".";
    case EffectKind::Lag:
      if (!e.lever.empty())
        return chs + verb + (isSpeedInput(e.input) ? e.input + " (its magnitude)" : e.input) + " through a lag of ~" +
               minutes(*e.tau_s) + ", times " + e.lever + ": " + physics(e, what) +
               ", and it acts over the distance: the warmed screws or frame stretch the axis (a thermal scale error).";
      return chs + verb + (isSpeedInput(e.input) ? e.input + " (its magnitude)" : e.input) + " through a lag of ~" +
             minutes(*e.tau_s) + ": " + physics(e, what) + ".";
    case EffectKind::Offset: break;
  }
  return "";
}

std::string command(const Recommendation& r, const DiagnoseOptions& opt) {
  std::string chs;
  for (const auto& c : r.channels) chs += (chs.empty() ? "" : ",") + c.channel;
  std::string cmd = std::string("probeloop model add ") + kindName(r.effect.kind) + " --model " + opt.model_path + " --channels " + chs;
  if (!r.effect.input.empty()) cmd += " --input " + r.effect.input;
  if (!r.effect.lever.empty()) cmd += " --lever " + r.effect.lever;
  if (r.effect.hasTimeConstant() && r.effect.tau_s) cmd += " --tau-s " + fmt(*r.effect.tau_s, 0);
  if (r.effect.kind == EffectKind::Expansion) cmd += " --part " + opt.part_path;
  return cmd;
}

}  // namespace

void ljungBox(const std::vector<double>& x, int h, double& Q, double& p) {
  const int n = static_cast<int>(x.size());
  Q = 0;
  p = 1;
  if (n < 3 || h < 1) return;
  double mean = 0;
  for (double v : x) mean += v;
  mean /= n;
  double c0 = 0;
  for (double v : x) c0 += (v - mean) * (v - mean);
  if (!(c0 > 0)) return;
  for (int k = 1; k <= h; ++k) {
    double ck = 0;
    for (int t = k; t < n; ++t) ck += (x[t] - mean) * (x[t - k] - mean);
    const double rho = ck / c0;
    Q += rho * rho / (n - k);
  }
  Q *= n * (n + 2.0);
  p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(h), Q));
}

Diagnosis diagnose(const Campaign& c, const ErrorModel& m, const DiagnoseOptions& opt) {
  requireDistinctChannels(c, m);
  Diagnosis d;
  const int N = c.errors.size();
  const int n = trainingEnd(N, m.training_fraction);
  const double dt = N > 1 ? (c.errors.t_s.back() - c.errors.t_s.front()) / (N - 1) : 0;
  std::map<std::string, Recommendation> groups;
  for (const auto& cm : m.channels) {
    const ChannelFit base = fitChannel(c, cm.channel, cm.effects, n);
    const int ch = c.errors.channel(cm.channel);
    const auto& y = c.errors.values[ch];
    std::vector<double> res(N);
    for (int k = 0; k < N; ++k) res[k] = y[k] - base.predicted[k];

    if (!(base.u_measurement > 0))
      throw InputError(c.errors.file, 0,
                       cm.channel + ": no expanded uncertainty (a column U_" + c.errors.channels[ch] +
                           " with values > 0): the diagnosis weighs residuals and candidates against the measurement's u");
    ChannelDiagnosis cd;
    cd.channel = base.channel;
    cd.unit = base.unit;
    cd.u_measurement = base.u_measurement;
    cd.rms_training = rms(res, 0, n);
    cd.rms_validation = rms(res, n, N);
    cd.has_validation = n < N;
    cd.ljung_box_lags = std::max(1, std::min(20, n / 4));
    ljungBox({res.begin(), res.begin() + n}, cd.ljung_box_lags, cd.ljung_box_Q, cd.ljung_box_p);
    cd.white = cd.ljung_box_p >= 0.01;
    cd.within = cd.rms_judged() <= 1.5 * cd.u_measurement;
    // Windows where |residual| exceeds the sample's U.
    for (int k = 0; k < N;) {
      const double U = c.errors.U[ch][k];
      if (!(U > 0 && std::fabs(res[k]) > U)) {
        ++k;
        continue;
      }
      ResidualWindow w{c.errors.t_s[k], c.errors.t_s[k], 0, 0};
      while (k < N && c.errors.U[ch][k] > 0 && std::fabs(res[k]) > c.errors.U[ch][k]) {
        w.to_s = c.errors.t_s[k];
        if (std::fabs(res[k]) > std::fabs(w.peak)) w.peak = res[k];
        ++w.samples;
        ++k;
      }
      cd.windows.push_back(w);
    }
    std::stable_sort(cd.windows.begin(), cd.windows.end(),
                     [](const ResidualWindow& a, const ResidualWindow& b) { return std::fabs(a.peak) > std::fabs(b.peak); });
    if (cd.windows.size() > 8) cd.windows.resize(8);
    std::sort(cd.windows.begin(), cd.windows.end(), [](const ResidualWindow& a, const ResidualWindow& b) { return a.from_s < b.from_s; });
    // Cross-correlation with every input, the input leading the residual by 0..K samples.
    const int K = dt > 0 ? static_cast<int>(std::min(N / 4.0, 6 * 3600 / dt)) : 0;
    double rm = 0;
    for (double v : res) rm += v;
    rm /= N;
    double rs = 0;
    for (double v : res) rs += (v - rm) * (v - rm);
    for (std::size_t i = 0; i < c.inputs.names.size(); ++i) {
      std::vector<double> g = c.inputs.columns[i];
      if (isSpeedInput(c.inputs.names[i]))
        for (double& v : g) v = std::fabs(v);
      const auto u = c.atErrorTimes(g);
      double um = 0;
      for (double v : u) um += v;
      um /= N;
      double us = 0;
      for (double v : u) us += (v - um) * (v - um);
      CrossCorrelation cc{c.inputs.names[i]};
      if (us > 0 && rs > 0)
        for (int lag = 0; lag <= K; ++lag) {
          double s = 0;
          for (int t = lag; t < N; ++t) s += (res[t] - rm) * (u[t - lag] - um);
          const double r = s / std::sqrt(rs * us);
          if (std::fabs(r) > std::fabs(cc.r)) cc.r = r, cc.lag_s = lag * dt;
        }
      cc.significant = std::fabs(cc.r) > 2 / std::sqrt(static_cast<double>(N));
      cd.cross.push_back(cc);
    }
    std::stable_sort(cd.cross.begin(), cd.cross.end(),
                     [](const CrossCorrelation& a, const CrossCorrelation& b) { return std::fabs(a.r) > std::fabs(b.r); });

    // Every candidate on top of the channel's model. Candidates reading the same input
    // (static, lag, expansion of one sensor) are rival descriptions of one heat path.
    const double u = std::max(cd.u_measurement, 1e-12);
    std::vector<std::pair<Effect, CandidateOnChannel>> accepted;
    for (const Effect& cand : candidatesFor(c, cm, opt)) {
      ++d.candidates_tried;
      std::vector<Effect> effects = cm.effects;
      effects.push_back(cand);
      ChannelFit f;
      try {
        f = fitChannel(c, cm.channel, effects, n);
      } catch (const InputError&) {
        continue;  // a constant input or an unidentifiable combination: not a candidate here
      }
      const double before = base.has_validation ? base.validation.rmse : base.training.rmse;
      const double after = f.has_validation ? f.validation.rmse : f.training.rmse;
      const double explained = (before * before - after * after) / (u * u);
      if (!(after < 0.9 * before && f.mdl < base.mdl && explained >= 0.25)) continue;
      Effect key = cand;
      for (const auto& fe : f.effects)
        if (fe.effect.id() == cand.id()) key.tau_s = fe.effect.tau_s;
      accepted.push_back({key, CandidateOnChannel{cm.channel, before, after, base.mdl, f.mdl, explained, f}});
    }
    // Parsimony at the noise floor: of the candidates within 10 % of the best validation
    // RMSE, the one with the fewest parameters is the channel's preferred explanation; of
    // those reading one input (rival descriptions of one heat path), the channel keeps only
    // its best by the same rule.
    auto preferred = [](const std::vector<const std::pair<Effect, CandidateOnChannel>*>& xs) {
      double best = xs.front()->second.rmse_after;
      for (const auto* x : xs) best = std::min(best, x->second.rmse_after);
      const std::pair<Effect, CandidateOnChannel>* pick = nullptr;
      for (const auto* x : xs) {
        if (x->second.rmse_after > 1.1 * best) continue;
        if (!pick || x->second.fit.parameters < pick->second.fit.parameters ||
            (x->second.fit.parameters == pick->second.fit.parameters && x->second.rmse_after < pick->second.rmse_after))
          pick = x;
      }
      return pick;
    };
    std::map<std::string, std::vector<const std::pair<Effect, CandidateOnChannel>*>> by_input;
    for (const auto& a : accepted) by_input[a.first.input.empty() ? a.first.id() : a.first.input].push_back(&a);
    // Each input's winner first; the channel's preferred explanation is one of them.
    std::vector<const std::pair<Effect, CandidateOnChannel>*> winners;
    for (auto& [path, xs] : by_input) winners.push_back(preferred(xs));
    const auto* channel_pick = winners.empty() ? nullptr : preferred(winners);
    for (const auto* kc : winners) {
      auto& g = groups[kc->first.id()];
      if (g.channels.empty()) g.effect = kc->first;
      if (kc == channel_pick) g.score += kc->second.explained;
      g.total += kc->second.explained;
      g.parameters = kc->second.fit.parameters - base.parameters;
      g.channels.push_back(kc->second);
    }
    d.fits.push_back(base);
    d.channels.push_back(cd);
  }

  for (auto& [id, g] : groups) {
    // One time constant to start from: the median over the channels.
    if (g.effect.hasTimeConstant()) {
      std::vector<double> taus;
      for (const auto& cc : g.channels)
        for (const auto& fe : cc.fit.effects)
          if (fe.effect.id() == id && fe.effect.tau_s) taus.push_back(*fe.effect.tau_s);
      std::sort(taus.begin(), taus.end());
      if (!taus.empty()) g.effect.tau_s = taus[taus.size() / 2];
    }
    g.sentence = sentence(g, opt.levers ? opt.levers->what : "artifact");
    g.command = command(g, opt);
    d.ranked.push_back(g);
  }
  std::stable_sort(d.ranked.begin(), d.ranked.end(), [](const Recommendation& a, const Recommendation& b) {
    return a.score != b.score ? a.score > b.score : a.total > b.total;
  });

  bool all_fine = true;
  std::string worst;
  for (const auto& cd : d.channels)
    if (!cd.white || !cd.within) {
      all_fine = false;
      if (worst.empty())
        worst = cd.channel + " (residual RMS " + fmt(cd.rms_judged(), 2) + " " + cd.unit + " against u = " +
                fmt(cd.u_measurement, 2) + ", Ljung-Box " + pValueClause(cd.ljung_box_p) + ")";
    }
  // "Within 1.5 u" says little where u dwarfs the residual: name those channels.
  std::string weak;
  for (const auto& cd : d.channels)
    if (cd.within && uOverResidual(cd.u_measurement, cd.rms_judged()) >= kWeakVerdictRatio)
      weak += (weak.empty() ? "" : ", ") + cd.channel + " (u = " + ratioText(uOverResidual(cd.u_measurement, cd.rms_judged())) +
              "\u00d7 the residual)";
  const std::string weak_note =
      weak.empty() ? "" : " The verdict is weak on " + weak + ": the model cannot be judged finer than u there.";
  if (!d.ranked.empty()) {
    d.verdict = "missing";
    d.message = d.ranked.front().sentence + " Add it with: " + d.ranked.front().command;
  } else if (all_fine) {
    d.verdict = "nothing_missing";
    d.message = "Nothing is missing: every residual is white (Ljung-Box p >= 0.01) and within 1.5 u of the measurement, "
                "and none of the " + std::to_string(d.candidates_tried) + " candidates lowers the validation error beyond chance." +
                weak_note;
  } else if (std::all_of(d.channels.begin(), d.channels.end(), [](const ChannelDiagnosis& x) { return x.within; })) {
    d.verdict = "unexplained";
    d.message = "Every residual is within 1.5 u of the measurement, but " + worst +
                " is not white: a small systematic effect remains that none of the " + std::to_string(d.candidates_tried) +
                " candidates explains beyond chance. Nothing in the library is worth adding; log more inputs if it matters." +
                weak_note;
  } else {
    d.verdict = "unexplained";
    d.message = "The model fails on " + worst + ", but none of the " + std::to_string(d.candidates_tried) +
                " candidate effects in the library explains it: look at the residual windows and cross-correlations, "
                "or log the input that drives it.";
  }
  return d;
}

}  // namespace probeloop::model
