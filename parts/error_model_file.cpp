#include "parts/error_model_file.hpp"

#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

using model::Effect;
using model::EffectKind;

namespace {

Effect readEffect(YamlMap& m) {
  const std::string kind = m.choice("effect", {"drift", "static", "lag", "transient", "expansion"});
  Effect e = model::makeEffect(*model::kindFromName(kind));
  if (e.kind != EffectKind::Drift) e.input = m.string("input");
  if (e.hasTimeConstant()) {
    if (m.has("tau")) {
      e.tau_s = m.quantity("tau", Dimension::Duration);
      if (!(*e.tau_s > 0)) m.fail("tau", "a time constant must be > 0");
    }
    e.tau_fixed = m.booleanOr("tau_fixed", false);
    if (e.tau_fixed && !e.tau_s) m.fail("tau_fixed", "a fixed time constant needs tau");
  }
  if (e.kind == EffectKind::Expansion) {
    e.alpha_um_per_m_K = m.number("alpha_um_per_m_K");
    if (!(e.alpha_um_per_m_K > 0)) m.fail("alpha_um_per_m_K", "must be > 0 (steel 11.5, aluminium 22, cast iron 11)");
    e.length_mm = m.quantity("length", Dimension::Length);
    // Signed: the lever through which the channel reads the part's growth (a piece cut warm
    // and measured cold reads smaller, so its diameter's lever is negative).
    if (!(e.length_mm != 0)) m.fail("length", "must not be 0 (signed lever of the part's growth, mm)");
  }
  if (m.has("lever")) {
    if (e.kind != EffectKind::Static && e.kind != EffectKind::Lag)
      m.fail("lever", "only a static or lag effect acts over a lever (an inputs column it is multiplied by)");
    e.lever = m.string("lever");
  }
  e.just_added = m.booleanOr("just_added", false);
  m.finish();
  return e;
}

// A YAML double-quoted scalar: any path or name survives the round trip.
std::string quoted(const std::string& v) {
  std::string o = "\"";
  for (char ch : v) {
    if (ch == '"' || ch == '\\') o += '\\';
    o += ch;
  }
  return o + "\"";
}

}  // namespace

model::ErrorModel loadErrorModel(const std::string& path) {
  const YAML::Node root_node = loadYamlFile(path);
  YamlMap root(root_node, path, "");
  if (root.string("kind") != "error_model") root.fail("kind", "expected 'error_model'");
  model::ErrorModel m;
  m.file = path;
  if (auto d = root.mapIfPresent("data")) {
    m.inputs_path = d->stringOr("inputs", "");
    m.errors_path = d->stringOr("errors", "");
    d->finish();
  }
  m.training_fraction = root.numberOr("training_fraction", 0.6);
  if (!(m.training_fraction > 0 && m.training_fraction <= 1))
    root.fail("training_fraction", "must be in (0, 1]: the share of the samples the fit is trained on");
  const YAML::Node chans = root.raw("channels");
  if (!chans.IsMap() || chans.size() == 0)
    throw InputError(path, root.line("channels"), "channels: expected a mapping of error channels (e.g. EY0C_um) to effect lists");
  for (const auto& kv : chans) {
    model::ChannelModel cm;
    cm.channel = kv.first.as<std::string>();
    const int line = kv.first.Mark().line + 1;
    if (m.channel(cm.channel)) throw InputError(path, line, "channels." + cm.channel + ": listed twice");
    const YAML::Node list = kv.second;
    if (!(list.IsSequence() || list.IsNull()))
      throw InputError(path, line, "channels." + cm.channel + ": expected a list of effects ([] for the offset only)");
    int i = 0;
    for (const auto& item : list) {
      const std::string where = "channels." + cm.channel + "[" + std::to_string(i++) + "]";
      if (!item.IsMap()) throw InputError(path, item.Mark().line + 1, where + ": expected a mapping {effect: ..., input: ...}");
      YamlMap em(item, path, where);
      Effect e = readEffect(em);
      for (const auto& have : cm.effects)
        if (have.id() == e.id()) throw InputError(path, item.Mark().line + 1, where + ": " + e.id() + " is already in this channel");
      cm.effects.push_back(e);
    }
    m.channels.push_back(cm);
  }
  root.finish();
  return m;
}

std::string errorModelYaml(const model::ErrorModel& m) {
  std::ostringstream o;
  o << "# probeloop error model (docs/model.md, docs/formats.md#error-model)\n"
       "# Every channel has an offset; the list gives the effects on top of it.\n"
       "kind: error_model\n";
  if (!m.inputs_path.empty() || !m.errors_path.empty()) {
    o << "data:\n";
    if (!m.inputs_path.empty()) o << "  inputs: " << quoted(m.inputs_path) << "\n";
    if (!m.errors_path.empty()) o << "  errors: " << quoted(m.errors_path) << "\n";
  }
  o << "training_fraction: " << formatNumber(m.training_fraction) << "\n";
  o << "channels:\n";
  for (const auto& c : m.channels) {
    o << "  " << quoted(c.channel) << ":";
    if (c.effects.empty()) {
      o << " []\n";
      continue;
    }
    o << "\n";
    for (const auto& e : c.effects) {
      o << "    - {effect: " << model::kindName(e.kind);
      if (!e.input.empty()) o << ", input: " << quoted(e.input);
      if (e.tau_s) o << ", tau: " << formatNumber(*e.tau_s) << " s";
      if (e.tau_fixed) o << ", tau_fixed: true";
      if (!e.lever.empty()) o << ", lever: " << quoted(e.lever);
      if (e.kind == EffectKind::Expansion)
        o << ", alpha_um_per_m_K: " << formatNumber(e.alpha_um_per_m_K) << ", length: " << formatNumber(e.length_mm) << " mm";
      if (e.just_added) o << ", just_added: true";
      o << "}\n";
    }
  }
  return o.str();
}

void saveErrorModel(const model::ErrorModel& m, const std::string& path) { writeFileAtomic(path, errorModelYaml(m)); }

}  // namespace probeloop::parts
