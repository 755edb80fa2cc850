#include "report/sphere_report_plots.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "core/error.hpp"
#include "report/vega.hpp"

namespace probeloop::report::sphere {

using namespace web;

const ErrorInfo kErrors[7] = {
    {"EX0C_um", "EX0C", "\u00b5m", "position of the C axis in X", "Blaser 2020, Eq. 5.4"},
    {"EY0C_um", "EY0C", "\u00b5m", "position of the C axis in Y", "Blaser 2020, Eq. 5.5"},
    {"EZ0T_um", "EZ0T", "\u00b5m", "height of the table surface (mean sphere-centre Z)", "Blaser 2020, Eq. 5.6"},
    {"ER0T_um", "ER0T", "\u00b5m", "radial growth of the table at d/2", "Blaser 2020, Eq. 5.7"},
    {"EA0C_urad", "EA0C", "\u00b5rad", "tilt of the C axis about X (+Y side rises)", "Blaser 2020, Eq. 5.8"},
    {"EB0C_urad", "EB0C", "\u00b5rad", "tilt of the C axis about Y (\u2212X side rises)", "Blaser 2020, Eq. 5.9"},
    {"EC0C_urad", "EC0C", "\u00b5rad", "angular position of the C axis (table turned clockwise seen from +Z)",
     "Blaser 2020, Eq. 5.10"},
};

namespace {

constexpr const char* kValueColour = "#1f5f9f";
constexpr const char* kBandColour = "#b9d0e8";
constexpr const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e",
                                    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

json at(const char* scale, const std::string& f) { return {{"scale", scale}, {"field", f}}; }
json val(const json& v) { return {{"value", v}}; }

json cycleNumber(const json& c) {
  const auto n = number(c, "cycle");
  if (!n) return nullptr;
  return *n == std::round(*n) ? json(static_cast<long long>(*n)) : json(*n);
}

json timeScale(const Domain& x_h) {
  return {{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false}, {"nice", false},
          {"domain", json::array({x_h.first, x_h.second})}};
}

json timeAxis() {
  return {{"orient", "bottom"}, {"scale", "x"}, {"title", "time (h, the clock of the log and of inputs.csv)"},
          {"tickCount", 10}};
}

}  // namespace

bool isBudgetOf(const json& budget, const ErrorInfo& e) {
  const std::string q = text(budget, "quantity");
  return q == e.label || q == e.id;
}

std::pair<std::optional<double>, std::optional<double>> cycleValue(const json& cycle, const ErrorInfo& e) {
  for (const auto& b : array(cycle, "budgets"))
    if (isBudgetOf(b, e) && number(b, "value")) return {number(b, "value"), number(b, "U")};
  return {number(object(cycle, "least_squares"), e.id), std::nullopt};
}

json errorRows(const json& evaluation, const ErrorInfo& e) {
  json rows = json::array();
  for (const auto& c : array(evaluation, "cycles")) {
    const auto t = number(c, "time_s");
    const auto [v, U] = cycleValue(c, e);
    if (!t || !v) continue;
    rows.push_back({{"time_s", *t}, {"cycle", cycleNumber(c)}, {"value", *v}, {"U", U ? json(*U) : json(nullptr)}});
  }
  return rows;
}

json errorPlotSpec(const ErrorInfo& e, const json& rows, const Domain& x_h) {
  const std::string y_title = std::string(e.label) + " (" + e.unit + ")";
  json spec = baseSpec(std::string(e.label) + " (" + e.what + ") against time, with its U (k = 2)", 220);
  spec["usermeta"] = {{"kind", "error"}, {"error", e.id}, {"label", e.label}, {"unit", e.unit}};
  spec["data"] = json::array(
      {{{"name", "cycles"},
        {"values", rows},
        {"transform", json::array({formulaTx("t_h", "datum.time_s / 3600"),
                                   {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}},
       {{"name", "cycles_U"},
        {"source", "cycles"},
        {"transform", json::array({filterTx("isValid(datum.U)"), formulaTx("lo", "datum.value - datum.U"),
                                   formulaTx("hi", "datum.value + datum.U"),
                                   {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}}});
  spec["scales"] = json::array(
      {timeScale(x_h),
       {{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true},
        {"domain", {{"fields", json::array({{{"data", "cycles"}, {"field", "value"}},
                                            {{"data", "cycles_U"}, {"field", "lo"}},
                                            {{"data", "cycles_U"}, {"field", "hi"}}})}}}}});
  spec["axes"] = json::array({timeAxis(), {{"orient", "left"}, {"scale", "y"}, {"title", y_title}, {"grid", true},
                                           {"tickCount", 6}, {"minExtent", 40}}});
  const bool many = rows.size() > 100;
  spec["marks"] = json::array(
      {{{"type", "rule"},
        {"encode", {{"enter", {{"x", val(0)}, {"x2", {{"signal", "width"}}}, {"y", {{"scale", "y"}, {"value", 0}}},
                               {"stroke", val("#999999")}, {"strokeWidth", val(1)}}}}}},
       {{"type", "area"},
        {"name", "u_band"},
        {"from", {{"data", "cycles_U"}}},
        {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "lo")}, {"y2", at("y", "hi")},
                               {"fill", val(kBandColour)}, {"fillOpacity", val(0.75)},
                               {"interpolate", val("linear")}}}}}},
       {{"type", "line"},
        {"name", "value_line"},
        {"from", {{"data", "cycles"}}},
        {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "value")}, {"stroke", val(kValueColour)},
                               {"strokeWidth", val(1.2)}}}}}},
       {{"type", "symbol"},
        {"name", "values"},
        {"from", {{"data", "cycles"}}},
        {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "value")}, {"shape", val("circle")},
                               {"size", val(many ? 10 : 30)}, {"fill", val(kValueColour)}}}}}}});
  const json solid = json::array({1, 0});
  addLegend(spec, {{std::string(e.label) + " of each cycle", "circle", kValueColour, kValueColour, solid},
                   {"\u00b1 U (k = 2)", "square", kBandColour, kBandColour, solid}});
  return spec;
}

// ---------------------------------------------------------------------------------------
// inputs.csv

std::string unitOfColumn(const std::string& name) {
  std::vector<std::string> t;
  for (std::size_t a = 0;;) {
    const std::size_t b = name.find('_', a);
    t.push_back(name.substr(a, b == std::string::npos ? std::string::npos : b - a));
    if (b == std::string::npos) break;
    a = b + 1;
  }
  if (t.size() < 2) return "";
  static const std::map<std::string, std::string> kUnits = {
      {"C", "\u00b0C"}, {"K", "K"},       {"rpm", "rpm"},   {"W", "W"},     {"kW", "kW"},     {"pct", "%"},
      {"percent", "%"}, {"Nm", "N\u00b7m"}, {"N", "N"},     {"A", "A"},     {"V", "V"},       {"bar", "bar"},
      {"Pa", "Pa"},     {"um", "\u00b5m"}, {"mm", "mm"},   {"m", "m"},     {"s", "s"},       {"min", "min"},
      {"h", "h"},       {"Hz", "Hz"},     {"deg", "\u00b0"}, {"urad", "\u00b5rad"}, {"lpm", "l/min"}};
  const auto unit = [](const std::string& w) {
    const auto it = kUnits.find(w);
    return it == kUnits.end() ? std::string() : it->second;
  };
  // "<x>_<a>_per_<b>" -> "a/b".
  if (t.size() >= 4 && t[t.size() - 2] == "per") {
    const std::string a = unit(t[t.size() - 3]), b = unit(t.back());
    if (!a.empty() && !b.empty()) return a + "/" + b;
  }
  return unit(t.back());
}

Inputs readInputs(const std::string& text_in, const std::string& file) {
  Inputs in;
  in.file = file;
  in.table = parseCsv(text_in, file);
  const CsvTable& t = in.table;
  const int tc = t.column("time_s");
  if (tc < 0)
    throw InputError(file, t.header_line,
                     "the inputs have no time_s column (expected the run's inputs.csv of `probeloop simulate` or a "
                     "logger: time_s, then one column per signal with its unit, e.g. T_env_C, c_rpm)");
  if (t.column("cycle") >= 0)
    for (const auto& e : kErrors)
      if (t.column(e.id) >= 0)
        throw InputError(file, t.header_line,
                         std::string("the inputs are an error series (columns cycle and ") + e.id +
                             ": an errors.csv), expected the run's inputs.csv (time_s, then one column per signal)");
  for (int c = 0; c < static_cast<int>(t.header.size()); ++c)
    if (c != tc) in.columns.push_back({t.header[c], unitOfColumn(t.header[c]), c});
  if (in.columns.empty())
    throw InputError(file, t.header_line,
                     "the inputs have no signal column besides time_s (expected one column per signal with its "
                     "unit, e.g. T_env_C, c_rpm)");
  for (const auto& row : t.rows) in.time_s.push_back(t.number(row, tc));

  // Groups by unit: temperatures, speeds, then the others as they come, unitless last.
  const auto group = [&in](const std::string& unit) -> InputGroup& {
    for (auto& g : in.groups)
      if (g.unit == unit) return g;
    InputGroup g;
    g.unit = unit;
    if (unit == "\u00b0C") g.title = "Temperatures", g.axis = "temperature (\u00b0C)";
    else if (unit == "rpm") g.title = "Speeds: the C axis's and the spindle's load", g.axis = "speed (rpm)";
    else if (unit == "%") g.title = "Loads", g.axis = "load (%)";
    else if (unit.empty()) g.title = "States and counts", g.axis = "state (0/1) or count (no unit)";
    else g.title = "Signals in " + unit, g.axis = "(" + unit + ")";
    g.steps = unit.empty();
    in.groups.push_back(g);
    return in.groups.back();
  };
  for (const char* first : {"\u00b0C", "rpm"})
    for (const auto& c : in.columns)
      if (c.unit == first) {
        group(first);
        break;
      }
  for (std::size_t i = 0; i < in.columns.size(); ++i)
    if (!in.columns[i].unit.empty()) group(in.columns[i].unit).columns.push_back(static_cast<int>(i));
  for (std::size_t i = 0; i < in.columns.size(); ++i)
    if (in.columns[i].unit.empty()) group("").columns.push_back(static_cast<int>(i));
  return in;
}

json inputsPlotSpec(const Inputs& in, const InputGroup& g, const Domain& x_h) {
  std::string names;
  for (const int i : g.columns) names += (names.empty() ? "" : ", ") + in.columns[i].name;
  json spec = baseSpec(g.title + " against time: " + names, 200);
  // Generic field names (v0, v1, ...): a column's name could hold '.', '[' or quotes, which a
  // Vega field reference or expression would read as syntax.
  json rows = json::array();
  for (std::size_t r = 0; r < in.table.rows.size(); ++r) {
    json row = {{"time_s", in.time_s[r]}};
    for (std::size_t k = 0; k < g.columns.size(); ++k) {
      double v = 0;
      row["v" + std::to_string(k)] =
          in.table.tryNumber(in.table.rows[r], in.columns[g.columns[k]].col, v) ? json(v) : json(nullptr);
    }
    rows.push_back(std::move(row));
  }
  json meta_columns = json::array(), y_fields = json::array();
  for (std::size_t k = 0; k < g.columns.size(); ++k) {
    meta_columns.push_back({{"field", "v" + std::to_string(k)}, {"column", in.columns[g.columns[k]].name}});
    y_fields.push_back({{"data", "inputs"}, {"field", "v" + std::to_string(k)}});
  }
  spec["usermeta"] = {{"kind", "inputs"}, {"group", g.title}, {"unit", g.unit}, {"columns", meta_columns}};
  spec["data"] = json::array({{{"name", "inputs"},
                               {"values", rows},
                               {"transform", json::array({formulaTx("t_h", "datum.time_s / 3600"),
                                                          {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}}});
  spec["scales"] = json::array({timeScale(x_h),
                                {{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", g.unit != "\u00b0C"},
                                 {"nice", true}, {"domain", {{"fields", y_fields}}}}});
  spec["axes"] = json::array({timeAxis(), {{"orient", "left"}, {"scale", "y"}, {"title", g.axis}, {"grid", true},
                                           {"tickCount", 6}, {"minExtent", 40}}});
  spec["marks"] = json::array();
  std::vector<LegendEntry> legend;
  const json solid = json::array({1, 0});
  for (std::size_t k = 0; k < g.columns.size(); ++k) {
    const std::string f = "v" + std::to_string(k);
    const char* colour = kPalette[k % (sizeof kPalette / sizeof kPalette[0])];
    spec["marks"].push_back(
        {{"type", "line"},
         {"name", "input_" + std::to_string(k)},
         {"from", {{"data", "inputs"}}},
         {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", f)}, {"stroke", val(colour)},
                                {"strokeWidth", val(1.3)}, {"interpolate", val(g.steps ? "step-after" : "linear")},
                                {"defined", {{"signal", "isValid(datum." + f + ")"}}}}}}}});
    legend.push_back({in.columns[g.columns[k]].name, "stroke", "transparent", colour, solid});
  }
  addLegend(spec, legend);
  spec["legends"][0]["labelLimit"] = 300;
  return spec;
}

}  // namespace probeloop::report::sphere
