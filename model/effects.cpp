#include "model/effects.hpp"

#include <cmath>

#include "core/error.hpp"

namespace probeloop::model {

std::optional<double> ExpansionLevers::lengthFor(const std::string& channel) const {
  const auto it = length_mm.find(channel.substr(0, channel.find('_')));
  if (it == length_mm.end()) return std::nullopt;
  return it->second;
}

double lagStep(double x, double u, double dt_s, double tau_s) {
  // x(t + dt) = u + (x - u) e^{-dt/tau}; expm1 keeps the small-step limit exact.
  return x - (x - u) * -std::expm1(-dt_s / tau_s);
}

double decayStep(double s, double dt_s, double tau_s) { return s * std::exp(-dt_s / tau_s); }

double expansion_um(double alpha_um_per_m_K, double length_mm, double dT_K) {
  return alpha_um_per_m_K * length_mm * 1e-3 * dT_K;
}

Effect makeEffect(EffectKind kind, const std::string& input) {
  Effect e;
  e.kind = kind;
  e.input = input;
  return e;
}

const char* kindName(EffectKind k) {
  switch (k) {
    case EffectKind::Offset: return "offset";
    case EffectKind::Drift: return "drift";
    case EffectKind::Static: return "static";
    case EffectKind::Lag: return "lag";
    case EffectKind::Transient: return "transient";
    case EffectKind::Expansion: return "expansion";
    case EffectKind::Force: return "force";
  }
  return "?";
}

std::optional<EffectKind> kindFromName(const std::string& name) {
  for (EffectKind k : {EffectKind::Offset, EffectKind::Drift, EffectKind::Static, EffectKind::Lag,
                       EffectKind::Transient, EffectKind::Expansion, EffectKind::Force})
    if (name == kindName(k)) return k;
  return std::nullopt;
}

std::string Effect::id() const {
  if (kind == EffectKind::Offset || kind == EffectKind::Drift) return kindName(kind);
  return std::string(kindName(kind)) + "(" + input + ")" + (lever.empty() ? "" : "*" + lever);
}

bool isSpeedInput(const std::string& c) {
  auto ends = [&](const std::string& s) { return c.size() >= s.size() && c.compare(c.size() - s.size(), s.size(), s) == 0; };
  return ends("_rpm") || c.rfind("feed", 0) == 0;
}

bool isForceInput(const std::string& c) { return c.size() > 2 && c.compare(c.size() - 2, 2, "_N") == 0; }

std::vector<double> regressor(const Effect& e, const std::vector<double>& t, const std::vector<double>& u,
                              double tau_s) {
  const std::size_t n = t.size();
  std::vector<double> r(n, 0.0);
  if (n == 0) return r;
  switch (e.kind) {
    case EffectKind::Offset:
      std::fill(r.begin(), r.end(), 1.0);
      break;
    case EffectKind::Drift:
      for (std::size_t k = 0; k < n; ++k) r[k] = (t[k] - t[0]) / 3600.0;  // per hour
      break;
    case EffectKind::Static:
      for (std::size_t k = 0; k < n; ++k) r[k] = u[k] - u[0];
      break;
    case EffectKind::Force:  // seed 003 eqs. 28, 29: deflection = compliance x F
      r = u;
      break;
    case EffectKind::Expansion:
      for (std::size_t k = 0; k < n; ++k) r[k] = expansion_um(e.alpha_um_per_m_K, e.length_mm, u[k] - u[0]);
      break;
    case EffectKind::Lag: {
      // Zero-order hold: the value logged at t_k is held until t_{k+1}.
      const bool mag = isSpeedInput(e.input);
      auto g = [&](std::size_t k) { return mag ? std::fabs(u[k]) : u[k]; };
      double x = g(0);
      r[0] = 0;
      for (std::size_t k = 1; k < n; ++k) {
        x = lagStep(x, g(k - 1), t[k] - t[k - 1], tau_s);
        r[k] = x - g(0);
      }
      break;
    }
    case EffectKind::Transient: {
      double s = 0;
      for (std::size_t k = 1; k < n; ++k) {
        const double h = t[k] - t[k - 1];
        s = decayStep(s, h, tau_s) + u[k] * std::exp(-0.5 * h / tau_s);
        r[k] = s;
      }
      break;
    }
  }
  return r;
}

}  // namespace probeloop::model
