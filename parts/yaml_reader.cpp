#include "parts/yaml_reader.hpp"

#include "core/csv.hpp"

#include <fstream>
#include <map>
#include <stdexcept>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace probeloop::parts {

namespace {

// yaml-cpp keeps both entries of a key written twice and its look-up returns the first, so a
// hand-edited `diameter: 3000 mm` below `diameter: 30 mm` would be ignored without a word.
// Every mapping is walked once after loading: keys must be plain scalars (not an alias of a
// mapping, not a complex key) and appear once. Aliases are followed, within a budget, so that
// an alias bomb is refused instead of walked for ever.
class KeyCheck {
 public:
  explicit KeyCheck(const std::string& file) : file_(file) {}
  void walk(const YAML::Node& n, int depth) {
    if (++visits_ > kMaxVisits)
      throw InputError(file_, n.Mark().line + 1, "the document expands to more than " + std::to_string(kMaxVisits) +
                                                     " nodes (aliases of aliases?): not read");
    if (depth > kMaxDepth)
      throw InputError(file_, n.Mark().line + 1, "nested more than " + std::to_string(kMaxDepth) + " levels deep: not read");
    if (n.IsSequence()) {
      for (const auto& item : n) walk(item, depth + 1);
      return;
    }
    if (!n.IsMap()) return;
    std::map<std::string, int> seen;
    for (const auto& kv : n) {
      const int line = kv.first.Mark().line + 1;
      if (!kv.first.IsScalar())
        throw InputError(file_, line, "a key must be a plain name; found a " +
                                          std::string(kv.first.IsMap() ? "mapping" : kv.first.IsSequence() ? "list" : "null") +
                                          " (an alias or a complex key?)");
      const auto [it, fresh] = seen.emplace(kv.first.Scalar(), line);
      if (!fresh)
        throw InputError(file_, line, "key '" + kv.first.Scalar() + "' is written twice (lines " + std::to_string(it->second) +
                                          " and " + std::to_string(line) + "); give it once");
      walk(kv.second, depth + 1);
    }
  }

 private:
  static constexpr long kMaxVisits = 1'000'000;
  static constexpr int kMaxDepth = 200;
  const std::string& file_;
  long visits_ = 0;
};

}  // namespace

YAML::Node loadYamlFile(const std::string& path) { return loadYamlText(readFile(path, kYamlInput), path); }

YAML::Node loadYamlText(const std::string& text, const std::string& path) {
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    std::string hint;
    const std::string kind = describeContent(text);
    if (!kind.empty() && kind.find("YAML") == std::string::npos) hint = " (the file looks like " + kind + ", not YAML)";
    throw InputError(path, e.mark.line + 1, "YAML syntax: " + e.msg + hint);
  }
  // Every probeloop description is a mapping; a CSV or a log often parses as a YAML scalar.
  if (!doc.IsMap()) {
    const std::string kind = describeContent(text);
    if (!kind.empty() && kind.find("YAML") == std::string::npos)
      throw InputError(path, 0, "this is " + kind + ", not a YAML description (a mapping with kind: ...)");
  }
  KeyCheck(path).walk(doc, 0);
  return doc;
}

YamlMap::YamlMap(const YAML::Node& node, std::string file, std::string path)
    : node_(node), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap()) {
    throw InputError(file_, node_.Mark().line + 1,
                     (path_.empty() ? std::string("document") : path_) + ": expected a mapping");
  }
}

int YamlMap::line() const { return node_.Mark().line + 1; }

int YamlMap::line(const std::string& key) const {
  const YAML::Node n = node_[key];
  return n ? n.Mark().line + 1 : line();
}

void YamlMap::fail(const std::string& key, const std::string& message) const {
  const std::string where = path_.empty() ? key : path_ + "." + key;
  throw InputError(file_, line(key), where + ": " + message);
}

bool YamlMap::has(const std::string& key) const { return static_cast<bool>(node_[key]); }

YAML::Node YamlMap::node(const std::string& key) {
  allowed_.insert(key);
  const YAML::Node n = node_[key];
  if (!n) {
    const std::string where = path_.empty() ? key : path_ + "." + key;
    throw InputError(file_, line(), "missing key '" + where + "'");
  }
  return n;
}

double YamlMap::positiveQuantity(const std::string& key, Dimension dim) {
  const double v = quantity(key, dim);
  if (!(v > 0)) fail(key, "must be positive");
  return v;
}

double YamlMap::quantity(const std::string& key, Dimension dim) {
  const YAML::Node n = node(key);
  if (!n.IsScalar()) fail(key, std::string("expected ") + acceptedUnits(dim));
  try {
    return parseQuantity(n.Scalar(), dim);
  } catch (const std::invalid_argument& e) {
    fail(key, e.what());
  }
}

double YamlMap::quantityOr(const std::string& key, Dimension dim, double fallback) {
  allowed_.insert(key);
  return has(key) ? quantity(key, dim) : fallback;
}

std::vector<double> YamlMap::quantityList(const std::string& key, Dimension dim) {
  const YAML::Node n = node(key);
  if (!n.IsSequence()) fail(key, std::string("expected a list of values, each ") + acceptedUnits(dim));
  std::vector<double> out;
  for (const auto& item : n) {
    try {
      if (!item.IsScalar()) throw std::invalid_argument("expected a scalar");
      out.push_back(parseQuantity(item.Scalar(), dim));
    } catch (const std::invalid_argument& e) {
      throw InputError(file_, item.Mark().line + 1,
                       (path_.empty() ? key : path_ + "." + key) + "[" +
                           std::to_string(out.size()) + "]: " + e.what());
    }
  }
  return out;
}

double YamlMap::number(const std::string& key) {
  const YAML::Node n = node(key);
  double v = 0;
  if (!n.IsScalar() || !parseFiniteNumber(n.Scalar(), v))
    fail(key, "expected a finite number, found '" + (n.IsScalar() ? n.Scalar() : "non-scalar") + "'");
  return v;
}

std::vector<double> YamlMap::numberList(const std::string& key) {
  const YAML::Node n = node(key);
  if (!n.IsSequence() || n.size() == 0) fail(key, "expected a non-empty list of numbers");
  std::vector<double> out;
  for (const auto& item : n) {
    double v = 0;
    if (!item.IsScalar() || !parseFiniteNumber(item.Scalar(), v))
      throw InputError(file_, item.Mark().line + 1,
                       (path_.empty() ? key : path_ + "." + key) + "[" + std::to_string(out.size()) +
                           "]: expected a finite number");
    out.push_back(v);
  }
  return out;
}

int YamlMap::textColumn(const std::string& key) const {
  const YAML::Node n = node_[key];
  if (!n || !n.IsScalar()) return 0;
  if (n.Scalar().find('\n') != std::string::npos) return 0;
  // yaml-cpp tags quoted scalars "!" and plain ones "?"; the mark is at the quote.
  return n.Mark().column + 1 + (n.Tag() == "!" ? 1 : 0);
}

YAML::Node YamlMap::raw(const std::string& key) { return node(key); }

double YamlMap::numberOr(const std::string& key, double fallback) {
  allowed_.insert(key);
  return has(key) ? number(key) : fallback;
}

int YamlMap::integer(const std::string& key) {
  const YAML::Node n = node(key);
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    fail(key, "expected an integer, found '" + (n.IsScalar() ? n.Scalar() : "non-scalar") + "'");
  }
}

int YamlMap::integerOr(const std::string& key, int fallback) {
  allowed_.insert(key);
  return has(key) ? integer(key) : fallback;
}

bool YamlMap::boolean(const std::string& key) {
  const YAML::Node n = node(key);
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "expected true or false");
  }
}

bool YamlMap::booleanOr(const std::string& key, bool fallback) {
  allowed_.insert(key);
  return has(key) ? boolean(key) : fallback;
}

std::string YamlMap::string(const std::string& key) {
  const YAML::Node n = node(key);
  if (!n.IsScalar()) fail(key, "expected a string");
  return n.Scalar();
}

std::string YamlMap::stringOr(const std::string& key, const std::string& fallback) {
  allowed_.insert(key);
  return has(key) ? string(key) : fallback;
}

std::string YamlMap::choice(const std::string& key, const std::vector<std::string>& allowed) {
  const std::string v = string(key);
  for (const auto& a : allowed)
    if (a == v) return v;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
  fail(key, "'" + v + "' is not one of: " + list);
}

YamlMap YamlMap::map(const std::string& key) {
  return YamlMap(node(key), file_, path_.empty() ? key : path_ + "." + key);
}

std::optional<YamlMap> YamlMap::mapIfPresent(const std::string& key) {
  allowed_.insert(key);
  if (!has(key)) return std::nullopt;
  return map(key);
}

std::vector<YamlMap> YamlMap::mapList(const std::string& key) {
  const YAML::Node n = node(key);
  if (!n.IsSequence() || n.size() == 0) fail(key, "expected a non-empty list of mappings");
  std::vector<YamlMap> out;
  const std::string base = path_.empty() ? key : path_ + "." + key;
  for (size_t i = 0; i < n.size(); ++i)
    out.emplace_back(n[i], file_, base + "[" + std::to_string(i) + "]");
  return out;
}

void YamlMap::finish() {
  for (const auto& kv : node_) {
    const std::string k = kv.first.as<std::string>();
    if (!allowed_.count(k)) {
      std::string list;
      for (const auto& a : allowed_) list += (list.empty() ? "" : ", ") + a;
      const std::string where = path_.empty() ? k : path_ + "." + k;
      throw InputError(file_, kv.first.Mark().line + 1,
                       "unknown key '" + where + "'; allowed here: " + list);
    }
  }
}

}  // namespace probeloop::parts
