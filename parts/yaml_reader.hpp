// Strict reading of YAML mappings. Contract: every accessor either returns a valid value or
// throws InputError("<file>:<line>: <path.key>: <what was expected>"); finish() throws on
// the first key that no accessor asked for, naming the keys that are allowed.
#pragma once
#include <yaml-cpp/yaml.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/units.hpp"

namespace probeloop::parts {

// Syntax errors, keys written twice, keys that are not plain names -> InputError with line.
YAML::Node loadYamlFile(const std::string& path);
YAML::Node loadYamlText(const std::string& text, const std::string& path);  // the same, text already read

class YamlMap {
 public:
  YamlMap(const YAML::Node& node, std::string file, std::string path);

  bool has(const std::string& key) const;
  double quantity(const std::string& key, Dimension dim);
  double quantityOr(const std::string& key, Dimension dim, double fallback);
  double positiveQuantity(const std::string& key, Dimension dim);  // > 0, else "must be positive"
  std::vector<double> quantityList(const std::string& key, Dimension dim);
  double number(const std::string& key);  // a plain finite number (unit in the key's name)
  double numberOr(const std::string& key, double fallback);
  std::vector<double> numberList(const std::string& key);  // a non-empty list of finite numbers
  int integer(const std::string& key);
  int integerOr(const std::string& key, int fallback);
  bool boolean(const std::string& key);
  bool booleanOr(const std::string& key, bool fallback);
  std::string string(const std::string& key);
  std::string stringOr(const std::string& key, const std::string& fallback);
  std::string choice(const std::string& key, const std::vector<std::string>& allowed);
  YamlMap map(const std::string& key);
  std::optional<YamlMap> mapIfPresent(const std::string& key);
  std::vector<YamlMap> mapList(const std::string& key);  // a non-empty list of mappings
  void finish();  // unknown keys -> InputError

  int line() const;                       // 1-based line of this mapping
  int line(const std::string& key) const;  // 1-based line of a key's value
  // 1-based file column where a single-line scalar's text starts (after an opening quote);
  // 0 for block scalars, whose text starts on a later line.
  int textColumn(const std::string& key) const;
  YAML::Node raw(const std::string& key);  // the node itself (for shapes the accessors lack)
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  const std::string& file() const { return file_; }

 private:
  YAML::Node node(const std::string& key);
  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> allowed_;
};

}  // namespace probeloop::parts
