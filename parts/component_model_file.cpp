#include "parts/component_model_file.hpp"

#include <cmath>
#include <set>
#include <stdexcept>

#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

const std::vector<std::string>& componentInputs() {
  static const std::vector<std::string> v = {"T_min", "dx_mm", "dy_mm", "dz_mm", "feed_x_mm_per_min", "feed_y_mm_per_min",
                                             "feed_z_mm_per_min", "feed_xy_mm_per_min", "e_prog"};
  return v;
}

const std::vector<std::string>& componentUnits() {
  static const std::vector<std::string> v = {"mm", "slope"};
  return v;
}

const ComponentEquation& ComponentModel::equation(const std::string& id) const {
  for (const auto& e : equations)
    if (e.id == id) return e;
  std::string list;
  for (const auto& e : equations) list += (list.empty() ? "" : ", ") + e.id;
  throw std::out_of_range(file + ": no equation '" + id + "'; the file has: " + list);
}

const ThermalStages& ComponentModel::stages(const std::string& component) const {
  for (const auto& t : thermal)
    if (t.component == component) return t;
  std::string list;
  for (const auto& t : thermal) list += (list.empty() ? "" : ", ") + t.component;
  throw std::out_of_range(file + ": no thermal component '" + component + "'; the file has: " + list);
}

namespace {

ComponentEquation readEquation(YamlMap& m, const std::string& path) {
  ComponentEquation e;
  e.line = m.line();
  e.id = m.string("id");
  e.equation = m.string("equation");
  const std::string fam = m.choice("family", model::familyNames());
  e.function.family = *model::familyFromName(fam);
  e.input = m.choice("input", componentInputs());
  e.unit = m.choice("unit", componentUnits());
  e.reading = m.stringOr("reading", "");
  const YAML::Node coef = m.raw("coefficients");
  if (e.function.family == model::Family::Polynomial) {
    if (!coef.IsSequence()) m.fail("coefficients", "a polynomial lists its coefficients c0, c1, ... as a list");
    e.function.p = m.numberList("coefficients");
  } else {
    if (!coef.IsMap()) m.fail("coefficients", "expected a mapping of the " + fam + " family's parameters");
    YamlMap c(coef, path, "equations." + e.id + ".coefficients");
    for (const auto& name : model::parameterNames(e.function.family)) e.function.p.push_back(c.number(name));
    c.finish();
  }
  m.finish();
  return e;
}

}  // namespace

ComponentModel loadComponentModel(const std::string& path) {
  const YAML::Node root_node = loadYamlFile(path);
  YamlMap root(root_node, path, "");
  if (root.string("kind") != "component_model") root.fail("kind", "expected 'component_model'");
  ComponentModel cm;
  cm.file = path;
  cm.source = root.stringOr("source", "");
  std::set<std::string> ids;
  for (auto& m : root.mapList("equations")) {
    ComponentEquation e = readEquation(m, path);
    if (!ids.insert(e.id).second) throw InputError(path, e.line, "equations: id '" + e.id + "' is listed twice");
    cm.equations.push_back(std::move(e));
  }
  if (root.has("thermal")) {
    std::set<std::string> comps;
    for (auto& m : root.mapList("thermal")) {
      ThermalStages t;
      t.component = m.string("component");
      t.equations = m.string("equations");
      for (auto [key, field] : {std::pair{"stage_1000_rpm", &t.stage_1000_rpm}, std::pair{"stage_3500_rpm", &t.stage_3500_rpm},
                                std::pair{"stage_5500_rpm", &t.stage_5500_rpm}}) {
        *field = m.string(key);
        if (!ids.count(*field)) m.fail(key, "no equation with id '" + *field + "' in this file");
        if (cm.equation(*field).input != "T_min")
          m.fail(key, "'" + *field + "' has input " + cm.equation(*field).input + "; a thermal stage function is of T_min");
      }
      if (!comps.insert(t.component).second) m.fail("component", "'" + t.component + "' is listed twice");
      m.finish();
      cm.thermal.push_back(std::move(t));
    }
  }
  if (auto c = root.mapIfPresent("control")) {
    cm.control_feed_low_mm_per_min = c->number("feed_low_mm_per_min");
    cm.control_feed_high_mm_per_min = c->number("feed_high_mm_per_min");
    if (!(cm.control_feed_high_mm_per_min > cm.control_feed_low_mm_per_min))
      c->fail("feed_high_mm_per_min", "must be above feed_low_mm_per_min (the feed change the control error was measured over)");
    c->finish();
  }
  root.finish();
  return cm;
}

}  // namespace probeloop::parts
