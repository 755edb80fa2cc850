#include "model/outputs.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/verdict_strength.hpp"

namespace probeloop::model {
namespace {

std::string g(double v, int sig = 3) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*g", sig, v);
  return b;
}
std::string hours(double s) { return g(s / 3600.0, 4) + " h"; }
std::string smape(const Indicators& i) { return i.smape_samples > 0 ? g(i.smape_percent) : "n/a"; }
std::string pv(const Indicators& i) { return i.pv_defined ? g(i.pv_ratio_percent) : "n/a"; }

std::string effectList(const std::vector<FittedEffect>& effects) {
  std::string s;
  for (const auto& e : effects) s += (s.empty() ? "" : ", ") + e.effect.id() + (e.effect.just_added ? " [just added]" : "");
  return s;
}

std::string parameterText(const Parameter& p) {
  if (p.unit == "s" && p.name == "tau") return g(p.value / 60, 4) + " ± " + g(p.u / 60, 2) + " min";
  return g(p.value, 4) + " ± " + g(p.u, 2) + " " + p.unit;
}

nlohmann::json indicatorsJson(const Indicators& i) {
  nlohmann::json j{{"n", i.n}, {"rmse", i.rmse}, {"p99", i.p99}};
  j["smape_percent"] = i.smape_samples > 0 ? nlohmann::json(i.smape_percent) : nlohmann::json(nullptr);
  j["pv_ratio_percent"] = i.pv_defined ? nlohmann::json(i.pv_ratio_percent) : nlohmann::json(nullptr);
  return j;
}

nlohmann::json effectsJson(const ChannelFit& f) {
  nlohmann::json arr = nlohmann::json::array();
  for (const auto& fe : f.effects) {
    nlohmann::json e{{"id", fe.effect.id()}, {"kind", kindName(fe.effect.kind)}, {"just_added", fe.effect.just_added}};
    e["input"] = fe.effect.input.empty() ? nlohmann::json(nullptr) : nlohmann::json(fe.effect.input);
    nlohmann::json ps = nlohmann::json::array();
    for (const auto& p : fe.parameters) ps.push_back({{"name", p.name}, {"value", p.value}, {"u", p.u}, {"unit", p.unit}});
    e["parameters"] = ps;
    arr.push_back(e);
  }
  return arr;
}

nlohmann::json spanJson(const Campaign& c, int from, int to) {
  if (to <= from) return nullptr;
  return {{"from_s", c.errors.t_s[from]}, {"to_s", c.errors.t_s[to - 1]}, {"samples", to - from}};
}

std::string indicatorRow(const std::string& label, const Indicators& i, const std::string& unit) {
  char b[256];
  std::snprintf(b, sizeof b, "    %-22s %10s %9s %9s %10s  (%d samples)\n", label.c_str(), (g(i.rmse) + " " + unit).c_str(),
                smape(i).c_str(), pv(i).c_str(),
                (g(i.p99) + " " + unit).c_str(), i.n);
  return b;
}

}  // namespace

void requireDistinctChannels(const Campaign& c, const ErrorModel& m) {
  for (std::size_t i = 0; i < m.channels.size(); ++i)
    for (std::size_t k = 0; k < i; ++k) {
      const int a = c.errors.channel(m.channels[k].channel), b = c.errors.channel(m.channels[i].channel);
      if (a >= 0 && a == b)
        throw InputError(m.file, 0, "channels '" + m.channels[k].channel + "' and '" + m.channels[i].channel +
                                        "' are the same column of " + c.errors.file + " (" +
                                        c.errors.channels[static_cast<std::size_t>(a)] +
                                        "): a channel is fitted once; merge their effects under " +
                                        c.errors.channels[static_cast<std::size_t>(a)]);
    }
}

ModelFit fitModel(const Campaign& c, const ErrorModel& m, double training_fraction) {
  requireDistinctChannels(c, m);
  ModelFit f;
  f.train_end = trainingEnd(c.errors.size(), training_fraction > 0 ? training_fraction : m.training_fraction);
  for (const auto& ch : m.channels) f.after.push_back(fitChannel(c, ch.channel, ch.effects, f.train_end));
  ErrorModel before;
  if (m.before(before))
    for (const auto& ch : before.channels) f.before.push_back(fitChannel(c, ch.channel, ch.effects, f.train_end));
  return f;
}

std::string fitText(const Campaign& c, const ErrorModel& m, const ModelFit& f) {
  std::ostringstream o;
  const int N = c.errors.size(), n = f.train_end;
  o << "Error model " << m.file << " on " << N << " cycles (" << c.inputs.file << ", " << c.errors.file << ")\n"
    << "  training: " << hours(c.errors.t_s[0]) << " .. " << hours(c.errors.t_s[n - 1]) << " (" << n << " cycles)";
  if (n < N) o << "; validation, predicted from the inputs alone: " << hours(c.errors.t_s[n]) << " .. " << hours(c.errors.t_s[N - 1]) << " (" << N - n << ")";
  o << "\n";
  for (std::size_t i = 0; i < f.after.size(); ++i) {
    const ChannelFit& a = f.after[i];
    // The residual a reader compares with u: the validation span's RMSE, else the training span's.
    const double judged = a.has_validation ? a.validation.rmse : a.training.rmse;
    o << "\n" << a.channel << "  (measurement u = " << g(a.u_measurement) << " " << a.unit << "; residual sigma " << g(a.sigma) << " " << a.unit
      << "; u / " << (a.has_validation ? "validation" : "training") << " RMSE = " << ratioText(uOverResidual(a.u_measurement, judged))
      << ")\n";
    if (const std::string weak = weakVerdictSentence(a.u_measurement, judged, a.unit); !weak.empty())
      o << "  note: " << weak << "\n";
    o << "  effects: " << effectList(a.effects) << "\n";
    for (const auto& fe : a.effects)
      for (const auto& p : fe.parameters) {
        char b[256];
        std::snprintf(b, sizeof b, "    %-5s %-28s %s\n", p.name.c_str(), fe.effect.id().c_str(), parameterText(p).c_str());
        o << b;
      }
    char h[256];
    std::snprintf(h, sizeof h, "    %-22s %10s %9s %9s %10s\n", "indicators", "RMSE", "SMAPE %", "PV %", "P99");
    o << h << indicatorRow("training", a.training, a.unit);
    if (a.has_validation) o << indicatorRow("validation", a.validation, a.unit);
    if (!f.before.empty() && f.before[i].has_validation) o << indicatorRow("validation, before", f.before[i].validation, a.unit);
  }
  if (!f.before.empty()) {
    o << "\nBefore -> after the effects just added (validation span):\n";
    char h[256];
    std::snprintf(h, sizeof h, "  %-11s %-24s %-24s %s\n", "channel", "RMSE before -> after", "P99 before -> after", "SMAPE % before -> after");
    o << h;
    for (std::size_t i = 0; i < f.after.size(); ++i) {
      const auto& a = f.after[i];
      const auto& b = f.before[i];
      const Indicators& ia = a.has_validation ? a.validation : a.training;
      const Indicators& ib = b.has_validation ? b.validation : b.training;
      char r[256];
      std::snprintf(r, sizeof r, "  %-11s %-24s %-24s %s\n", a.channel.c_str(),
                    (g(ib.rmse) + " -> " + g(ia.rmse) + " " + a.unit).c_str(), (g(ib.p99) + " -> " + g(ia.p99) + " " + a.unit).c_str(),
                    (smape(ib) + " -> " + smape(ia)).c_str());
      o << r;
    }
  }
  return o.str();
}

nlohmann::json fitJson(const Campaign& c, const ErrorModel& m, const ModelFit& f) {
  const int N = c.errors.size(), n = f.train_end;
  nlohmann::json j{{"kind", "probeloop model fit"}, {"model", m.file}, {"inputs", c.inputs.file}, {"errors", c.errors.file}};
  j["training"] = spanJson(c, 0, n);
  j["validation"] = spanJson(c, n, N);
  nlohmann::json chans = nlohmann::json::array();
  for (std::size_t i = 0; i < f.after.size(); ++i) {
    const ChannelFit& a = f.after[i];
    const int ch = c.errors.channel(a.channel);
    nlohmann::json x{{"channel", a.channel}, {"unit", a.unit}, {"u_measurement", a.u_measurement}, {"sigma", a.sigma},
                     {"mdl", a.mdl}, {"parameters_count", a.parameters}};
    x["effects"] = effectsJson(a);
    x["indicators"] = {{"training", indicatorsJson(a.training)},
                       {"validation", a.has_validation ? indicatorsJson(a.validation) : nlohmann::json(nullptr)}};
    nlohmann::json series{{"time_s", c.errors.t_s}, {"measured", c.errors.values[ch]}, {"predicted", a.predicted}, {"U", c.errors.U[ch]}};
    if (!f.before.empty()) {
      const ChannelFit& b = f.before[i];
      nlohmann::json ids = nlohmann::json::array();
      for (const auto& fe : b.effects) ids.push_back(fe.effect.id());
      x["before"] = {{"effects", ids},
                     {"indicators", {{"training", indicatorsJson(b.training)},
                                     {"validation", b.has_validation ? indicatorsJson(b.validation) : nlohmann::json(nullptr)}}}};
      series["predicted_before"] = b.predicted;
    } else {
      x["before"] = nullptr;
      series["predicted_before"] = nullptr;
    }
    x["series"] = series;
    chans.push_back(x);
  }
  j["channels"] = chans;
  return j;
}

std::string compareText(const Campaign& c, const std::vector<ErrorModel>& models, const std::vector<ModelFit>& fits) {
  std::ostringstream o;
  o << "Validation indicators of " << models.size() << " models on " << c.errors.file
    << " (one split for all: the first model's training fraction " << formatNumber(models.front().training_fraction) << ")\n";
  for (std::size_t k = 0; k < models.size(); ++k) o << "  [" << k + 1 << "] " << models[k].file << "\n";
  for (const auto& ch0 : models.front().channels) {
    o << "\n  " << ch0.channel << "\n";
    for (std::size_t k = 0; k < models.size(); ++k) {
      for (const auto& a : fits[k].after)
        if (a.channel == ch0.channel) {
          const Indicators& i = a.has_validation ? a.validation : a.training;
          char r[256];
          std::snprintf(r, sizeof r, "    [%zu] RMSE %-10s P99 %-10s SMAPE %-8s PV %-8s  %s\n", k + 1, (g(i.rmse) + " " + a.unit).c_str(),
                        (g(i.p99) + " " + a.unit).c_str(), (smape(i) + "%").c_str(), (pv(i) + "%").c_str(),
                        effectList(a.effects).c_str());
          o << r;
        }
    }
  }
  return o.str();
}

nlohmann::json compareJson(const Campaign& c, const std::vector<ErrorModel>& models, const std::vector<ModelFit>& fits) {
  nlohmann::json j{{"kind", "probeloop model compare"}, {"inputs", c.inputs.file}, {"errors", c.errors.file}};
  nlohmann::json arr = nlohmann::json::array();
  for (std::size_t k = 0; k < models.size(); ++k) arr.push_back(fitJson(c, models[k], fits[k]));
  j["models"] = arr;
  return j;
}

std::string diagnosisText(const Campaign& c, const ErrorModel& m, const Diagnosis& d) {
  std::ostringstream o;
  o << "Diagnosis of " << m.file << " on " << c.errors.size() << " cycles (" << d.candidates_tried << " candidate fits)\n\n";
  char h[256];
  std::snprintf(h, sizeof h, "  %-11s %-22s %-37s %-24s %s\n", "channel", "RMS train / valid", "vs u of measurement", "whiteness (Ljung-Box)",
                "largest cross-correlation");
  o << h;
  for (const auto& cd : d.channels) {
    std::string cc = "none";
    if (!cd.cross.empty())
      cc = cd.cross.front().input + " r = " + g(cd.cross.front().r, 2) + " at lag " + g(cd.cross.front().lag_s / 60, 3) + " min" +
           (cd.cross.front().significant ? "" : " (not significant)");
    char r[512];
    std::snprintf(r, sizeof r, "  %-11s %-22s %-37s %-24s %s\n", cd.channel.c_str(),
                  (g(cd.rms_training) + " / " + (cd.has_validation ? g(cd.rms_validation) : std::string("-")) + " " + cd.unit).c_str(),
                  ((cd.within ? "within 1.5u (u = " : "beyond 1.5u (u = ") + g(cd.u_measurement) + ", " +
                   "u/RMS = " + ratioText(uOverResidual(cd.u_measurement, cd.rms_judged())) + ")").c_str(),
                  ((cd.white ? "white, " : "NOT white, ") + pValueClause(cd.ljung_box_p)).c_str(), cc.c_str());
    o << r;
    if (const std::string weak = weakVerdictSentence(cd.u_measurement, cd.rms_judged(), cd.unit); !weak.empty())
      o << "      note: " << weak << "\n";
    for (const auto& w : cd.windows)
      o << "      |residual| > U from " << hours(w.from_s) << " to " << hours(w.to_s) << " (" << w.samples << " cycles, peak "
        << g(w.peak) << " " << cd.unit << ")\n";
  }
  o << "\n";
  if (d.ranked.empty()) {
    o << d.message << "\n";
    return o.str();
  }
  o << "Missing effects, ranked by the validation error they explain (in units of u^2):\n";
  for (std::size_t k = 0; k < d.ranked.size(); ++k) {
    const auto& r = d.ranked[k];
    o << "\n" << k + 1 << ". " << r.effect.id() << "  (score " << g(r.score) << ")\n   " << r.sentence << "\n";
    for (const auto& cc : r.channels) {
      std::string params;
      for (const auto& fe : cc.fit.effects)
        if (fe.effect.id() == r.effect.id())
          for (const auto& p : fe.parameters) params += (params.empty() ? "" : ", ") + p.name + " = " + parameterText(p);
      o << "   " << cc.channel << ": validation RMSE " << g(cc.rmse_before) << " -> " << g(cc.rmse_after) << " " << cc.fit.unit
        << "; " << params << "\n";
    }
    o << "   add it: " << r.command << "\n";
  }
  return o.str();
}

nlohmann::json diagnosisJson(const Campaign& c, const ErrorModel& m, const Diagnosis& d) {
  nlohmann::json j{{"kind", "probeloop model diagnose"}, {"model", m.file}, {"inputs", c.inputs.file}, {"errors", c.errors.file},
                   {"verdict", d.verdict}, {"message", d.message}, {"candidates_tried", d.candidates_tried}};
  nlohmann::json chans = nlohmann::json::array();
  for (const auto& cd : d.channels) {
    nlohmann::json x{{"channel", cd.channel}, {"unit", cd.unit}, {"u_measurement", cd.u_measurement},
                     {"rms_residual", {{"training", cd.rms_training},
                                       {"validation", cd.has_validation ? nlohmann::json(cd.rms_validation) : nlohmann::json(nullptr)}}},
                     {"ljung_box", {{"Q", cd.ljung_box_Q}, {"lags", cd.ljung_box_lags}, {"p", cd.ljung_box_p}}},
                     {"white", cd.white}, {"within", cd.within}};
    nlohmann::json w = nlohmann::json::array();
    for (const auto& v : cd.windows) w.push_back({{"from_s", v.from_s}, {"to_s", v.to_s}, {"peak", v.peak}, {"samples", v.samples}});
    x["windows"] = w;
    nlohmann::json cc = nlohmann::json::array();
    for (const auto& v : cd.cross) cc.push_back({{"input", v.input}, {"lag_s", v.lag_s}, {"r", v.r}, {"significant", v.significant}});
    x["cross_correlation"] = cc;
    chans.push_back(x);
  }
  j["channels"] = chans;
  nlohmann::json cands = nlohmann::json::array();
  for (std::size_t k = 0; k < d.ranked.size(); ++k) {
    const auto& r = d.ranked[k];
    nlohmann::json x{{"rank", k + 1}, {"effect", kindName(r.effect.kind)}, {"id", r.effect.id()}, {"score", r.score},
                     {"sentence", r.sentence}, {"command", r.command}};
    x["input"] = r.effect.input.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.effect.input);
    nlohmann::json chs = nlohmann::json::array();
    for (const auto& cc : r.channels) {
      nlohmann::json ps = nlohmann::json::array();
      for (const auto& fe : cc.fit.effects)
        if (fe.effect.id() == r.effect.id())
          for (const auto& p : fe.parameters) ps.push_back({{"name", p.name}, {"value", p.value}, {"u", p.u}, {"unit", p.unit}});
      chs.push_back({{"channel", cc.channel}, {"validation_rmse_before", cc.rmse_before}, {"validation_rmse_after", cc.rmse_after},
                     {"mdl_before", cc.mdl_before}, {"mdl_after", cc.mdl_after}, {"parameters", ps}});
    }
    x["channels"] = chs;
    cands.push_back(x);
  }
  j["candidates"] = cands;
  return j;
}

}  // namespace probeloop::model
