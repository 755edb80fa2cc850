#include "parts/error_model_file.hpp"

#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

using model::Effect;
using model::EffectKind;

namespace {

Effect readEffect(YamlMap& m) {
  const std::string kind = m.choice("effect", {"drift", "static", "lag", "transient", "expansion", "force"});
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

model::ErrorModel loadErrorModel(const std::string& path) { return errorModelFromText(readFile(path, kYamlInput), path); }

model::ErrorModel errorModelFromText(const std::string& text, const std::string& path) {
  const YAML::Node root_node = loadYamlText(text, path);
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

namespace {

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t b = 0;
  while (b < text.size()) {
    const std::size_t e = text.find('\n', b);
    lines.push_back(text.substr(b, e == std::string::npos ? std::string::npos : e - b));
    if (e == std::string::npos) break;
    b = e + 1;
  }
  return lines;
}

std::size_t indentOf(const std::string& line) { return line.find_first_not_of(' '); }
bool isContent(const std::string& line) {
  const auto i = line.find_first_not_of(" \t\r");
  return i != std::string::npos && line[i] != '#';
}

// The canonical one-line form of an effect (as errorModelYaml writes it, without the indent).
std::string effectLine(const Effect& e) {
  model::ErrorModel one;
  one.channels.push_back({"c", {e}});
  const std::string y = errorModelYaml(one);
  const auto b = y.find("- {");
  return y.substr(b, y.find('\n', b) - b);
}

// The last line (index) of the block that starts at `key`: the last content line indented more.
std::size_t blockEnd(const std::vector<std::string>& lines, std::size_t key) {
  const std::size_t ind = indentOf(lines[key]);
  std::size_t last = key;
  for (std::size_t i = key + 1; i < lines.size(); ++i) {
    if (!isContent(lines[i])) continue;
    if (indentOf(lines[i]) <= ind) break;
    last = i;
  }
  return last;
}

}  // namespace

std::optional<std::string> patchErrorModelText(const std::string& text, const model::ErrorModel& updated) {
  const model::ErrorModel old = errorModelFromText(text, updated.file);
  if (old.inputs_path != updated.inputs_path || old.errors_path != updated.errors_path ||
      old.training_fraction != updated.training_fraction)
    return std::nullopt;
  const YAML::Node root = YAML::Load(text);
  std::vector<std::string> lines = splitLines(text);
  const YAML::Node chans = root["channels"];
  if (!chans.IsMap() || chans.Style() == YAML::EmitterStyle::Flow) return std::nullopt;
  std::map<std::size_t, std::vector<std::string>> insert_after;  // line index -> lines
  std::size_t channels_end = 0, channel_indent = std::string::npos;
  for (const auto& kv : chans) {
    const std::string name = kv.first.as<std::string>();
    const std::size_t key = static_cast<std::size_t>(kv.first.Mark().line);
    if (key >= lines.size()) return std::nullopt;
    channel_indent = indentOf(lines[key]);
    channels_end = std::max(channels_end, blockEnd(lines, key));
    const model::ChannelModel* was = old.channel(name);
    const model::ChannelModel* now = updated.channel(name);
    if (!was || !now || now->effects.size() < was->effects.size()) return std::nullopt;
    const YAML::Node list = kv.second;
    // just_added cleared on effects that had it: only in a flow map on one line.
    for (std::size_t k = 0; k < was->effects.size(); ++k) {
      if (was->effects[k].id() != now->effects[k].id()) return std::nullopt;
      if (was->effects[k].just_added == now->effects[k].just_added) continue;
      if (now->effects[k].just_added || list[k].Style() != YAML::EmitterStyle::Flow) return std::nullopt;
      std::string& line = lines[static_cast<std::size_t>(list[k].Mark().line)];
      static const std::regex flag(R"(,\s*just_added\s*:\s*true\b|\bjust_added\s*:\s*true\s*,\s*)");
      const std::string cleared = std::regex_replace(line, flag, "", std::regex_constants::format_first_only);
      if (cleared == line) return std::nullopt;
      line = cleared;
    }
    if (now->effects.size() == was->effects.size()) continue;
    std::string items;
    for (std::size_t k = was->effects.size(); k < now->effects.size(); ++k)
      items += (items.empty() ? "" : ", ") + effectLine(now->effects[k]).substr(2);
    if (list.IsSequence() && list.Style() == YAML::EmitterStyle::Flow) {
      // `EY0C_um: [{...}]  # comment` on the key line: the new maps go before its last ']'.
      std::string& k = lines[key];
      static const std::regex comment(R"(\s#)");
      std::smatch c;
      const std::size_t code_end = std::regex_search(k, c, comment) ? static_cast<std::size_t>(c.position(0)) : k.size();
      const std::size_t close = k.rfind(']', code_end);
      if (close == std::string::npos || k.find('[') > close) return std::nullopt;
      k.insert(close, (list.size() == 0 ? "" : ", ") + items);
      continue;
    }
    // A block list: the new effects go after the channel's last item, indented like its first.
    std::string indent;
    if (list.IsSequence() && list.size() > 0) {
      const std::string& first = lines[static_cast<std::size_t>(list[0].Mark().line)];
      const auto dash = first.find('-');
      if (dash == std::string::npos) return std::nullopt;
      indent = first.substr(0, dash);
    } else {
      indent = std::string(indentOf(lines[key]) + 2, ' ');  // `EX0C_um:` with nothing after it
    }
    auto& add = insert_after[blockEnd(lines, key)];
    for (std::size_t k = was->effects.size(); k < now->effects.size(); ++k)
      add.push_back(indent + effectLine(now->effects[k]));
  }
  // New channels go after the last one.
  for (const auto& c : updated.channels) {
    if (old.channel(c.channel)) continue;
    if (channel_indent == std::string::npos) return std::nullopt;
    auto& add = insert_after[channels_end];
    const std::string ind(channel_indent, ' ');
    add.push_back(ind + quoted(c.channel) + (c.effects.empty() ? ": []" : ":"));
    for (const auto& e : c.effects) add.push_back(ind + "  " + effectLine(e));
  }
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    out += lines[i] + "\n";
    if (auto it = insert_after.find(i); it != insert_after.end())
      for (const auto& l : it->second) out += l + "\n";
  }
  if (!text.empty() && text.back() != '\n') out.pop_back();
  // The patch must mean exactly the updated model; otherwise the caller writes the canonical form.
  try {
    model::ErrorModel check = errorModelFromText(out, updated.file);
    if (errorModelYaml(check) != errorModelYaml(updated)) return std::nullopt;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  return out;
}

}  // namespace probeloop::parts
