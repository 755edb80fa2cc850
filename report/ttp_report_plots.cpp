// The thermal-test-piece report's Vega specs: one plot per quantity (the routes' points with
// ±U bars, the R-test's line and band) and the machine's temperatures and C-axis load, all
// against hours since the reference cut (report/ttp_report_parts.hpp).
#include <algorithm>
#include <cmath>

#include "report/ttp_report_parts.hpp"

namespace probeloop::report::ttp_detail {
namespace {

using namespace web;

const char* kRouteColours[] = {"#1f5f9f", "#d9822b"};
const char* kRouteShapes[] = {"circle", "square"};
const char* kRTestColour = "#c0392b";
const char* kRTestBand = "#f3cbc5";
const char* kWarmUpFill = "#f2a33a";
// Temperatures: one colour per logged column, in the file's order.
const char* kTemperatureColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22"};
const char* kCLoadColour = "#555555";

json seriesData(const Series& s) {
  return {{"name", s.data},
          {"values", s.rows},
          {"transform", json::array({filterTx("isValid(datum.time_s) && isValid(datum.value)"),
                                     formulaTx("t_h", "(datum.time_s - t0_s) / 3600"),
                                     {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}};
}

json uncertaintyData(const Series& s) {
  return {{"name", s.data + "_U"},
          {"source", s.data},
          {"transform", json::array({filterTx("isValid(datum.U)"), formulaTx("lo", "datum.value - datum.U"),
                                     formulaTx("hi", "datum.value + datum.U")})}};
}

json at(const char* scale, const char* f) { return {{"scale", scale}, {"field", f}}; }
json val(const json& v) { return {{"value", v}}; }

// The warm-up hours, shaded behind the marks (the spec's signal t0_s places them).
void addWarmUp(json& spec, const WarmUp& warm_up_s) {
  if (warm_up_s) {
    spec["data"].push_back({{"name", "warm_up"},
                            {"values", json::array({{{"from_s", warm_up_s->first}, {"to_s", warm_up_s->second}}})},
                            {"transform", json::array({formulaTx("from_h", "(datum.from_s - t0_s) / 3600"),
                                                       formulaTx("to_h", "(datum.to_s - t0_s) / 3600")})}});
    spec["marks"].push_back({{"type", "rect"},
                             {"name", "warm_up_phase"},
                             {"from", {{"data", "warm_up"}}},
                             {"clip", true},
                             {"encode", {{"enter", {{"x", at("x", "from_h")}, {"x2", at("x", "to_h")}, {"y", val(0)},
                                                    {"y2", {{"signal", "height"}}}, {"fill", val(kWarmUpFill)},
                                                    {"fillOpacity", val(0.08)}}}}}});
    spec["marks"].push_back({{"type", "text"},
                             {"from", {{"data", "warm_up"}}},
                             {"clip", true},
                             {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "from_h"}, {"offset", 4}}},
                                                    {"y", val(4)}, {"baseline", val("top")}, {"text", val("warm-up")},
                                                    {"fill", val("#8a6a3a")}, {"font", val("sans-serif")},
                                                    {"fontSize", val(10)}}}}}});
  }
}

// Hours since the reference cut, labelled h:mm like the tables.
json timeAxis() {
  return {{"orient", "bottom"}, {"scale", "x"}, {"title", "time since the reference cut (h:mm)"}, {"tickCount", 10},
          {"encode", {{"labels", hoursMinutesAxisLabels()}}}};
}

}  // namespace

json plotSpec(const Quantity& q, const std::vector<Series>& series, double t0_s, const WarmUp& warm_up_s) {
  std::string names;
  for (const auto& s : series) names += (names.empty() ? "" : ", ") + s.label;
  json spec = baseSpec(std::string(q.label) + " against hours since the reference cut: " + names, 250);
  json meta_series = json::array();
  for (const auto& s : series) meta_series.push_back({{"data", s.data}, {"label", s.label}, {"kind", s.kind}});
  spec["usermeta"] = {{"quantity", q.id}, {"t0_s", t0_s}, {"series", meta_series}};
  spec["signals"] = json::array({{{"name", "t0_s"}, {"value", t0_s}}});
  spec["data"] = json::array();
  spec["marks"] = json::array();
  spec["scales"] = json::array();
  json x_fields = json::array(), y_fields = json::array();
  for (const auto& s : series) {
    spec["data"].push_back(seriesData(s));
    spec["data"].push_back(uncertaintyData(s));
    x_fields.push_back({{"data", s.data}, {"field", "t_h"}});
    y_fields.push_back({{"data", s.data}, {"field", "value"}});
    y_fields.push_back({{"data", s.data + "_U"}, {"field", "lo"}});
    y_fields.push_back({{"data", s.data + "_U"}, {"field", "hi"}});
  }
  addWarmUp(spec, warm_up_s);
  spec["scales"].push_back({{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false}, {"nice", false},
                            {"domain", {{"fields", x_fields}}}});
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true},
                            {"domain", {{"fields", y_fields}}}});
  spec["axes"] = json::array(
      {timeAxis(),
       {{"orient", "left"}, {"scale", "y"}, {"title", columnTitle(q.label, q.unit)}, {"grid", true}, {"tickCount", 6},
        {"minExtent", 40}}});
  // Zero line.
  spec["marks"].push_back({{"type", "rule"},
                           {"encode", {{"enter", {{"x", val(0)}, {"x2", {{"signal", "width"}}},
                                                  {"y", {{"scale", "y"}, {"value", 0}}}, {"stroke", val("#999999")},
                                                  {"strokeWidth", val(1)}}}}}});

  const json solid = json::array({1, 0}), dashed = json::array({5, 3});
  std::vector<LegendEntry> legend;
  bool two_routes = false;
  for (const auto& s : series) two_routes |= s.route == 1;
  // The R-test first (behind): band and line.
  for (const auto& s : series) {
    if (s.kind != "r_test") continue;
    spec["marks"].push_back(
        {{"type", "area"},
         {"from", {{"data", s.data + "_U"}}},
         {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "lo")}, {"y2", at("y", "hi")},
                                {"fill", val(kRTestBand)}, {"fillOpacity", val(0.7)}}}}}});
    spec["marks"].push_back({{"type", "line"},
                             {"from", {{"data", s.data}}},
                             {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "value")},
                                                    {"stroke", val(kRTestColour)}, {"strokeWidth", val(1.5)}}}}}});
    legend.push_back({s.label, "stroke", "transparent", kRTestColour, solid});
    legend.push_back({s.label + " \u00b1 U", "square", kRTestBand, kRTestBand, solid});
  }
  for (const auto& s : series) {
    if (s.kind == "r_test") continue;
    const char* colour = kRouteColours[s.route % 2];
    // Two routes: drawn 3 px apart so that neither hides the other's error bars (display only).
    json dodgedX = at("x", "t_h");
    if (two_routes) dodgedX["offset"] = s.route % 2 == 0 ? -3 : 3;
    const bool eq79 = s.kind == "eq_7_9";
    json line = {{"x", dodgedX}, {"y", at("y", "value")}, {"stroke", val(colour)}, {"strokeWidth", val(1)},
                 {"strokeOpacity", val(0.6)}};
    if (eq79) line["strokeDash"] = val(dashed);
    spec["marks"].push_back({{"type", "line"}, {"from", {{"data", s.data}}}, {"encode", {{"enter", line}}}});
    spec["marks"].push_back({{"type", "rule"},
                             {"name", s.data + "_error_bars"},
                             {"from", {{"data", s.data + "_U"}}},
                             {"encode", {{"enter", {{"x", dodgedX}, {"y", at("y", "lo")}, {"y2", at("y", "hi")},
                                                    {"stroke", val(colour)}, {"strokeWidth", val(1.5)}}}}}});
    json points = {{"x", dodgedX},
                   {"y", at("y", "value")},
                   {"shape", val(eq79 ? "diamond" : kRouteShapes[s.route % 2])},
                   {"size", val(eq79 ? 50 : 40)}};
    const bool hollow = eq79 || s.route % 2 == 1;  // route 2 open, so route 1 shows through
    if (hollow) {
      points["fill"] = val("#ffffff");
      points["fillOpacity"] = val(eq79 ? 1.0 : 0.0);
      points["stroke"] = val(colour);
      points["strokeWidth"] = val(1.5);
    } else {
      points["fill"] = val(colour);
    }
    spec["marks"].push_back({{"type", "symbol"}, {"from", {{"data", s.data}}}, {"encode", {{"enter", points}}}});
    legend.push_back({s.label, eq79 ? "diamond" : kRouteShapes[s.route % 2], hollow ? "transparent" : colour,
                      hollow ? colour : "transparent", eq79 ? dashed : solid});
  }
  addLegend(spec, legend);
  spec["legends"][0]["labelLimit"] = 360;
  return spec;
}

std::string plotCaption(const Quantity& q, const RTest* r, const RTestChannel* ch, bool has_eq79) {
  std::string c = std::string(q.label) + " of the test piece: points with error bars \u00b1U (k as in the budget)";
  const std::string id = q.id;
  if (id == "ETTP_um" && has_eq79)
    c += "; open diamonds, dashed: the Eq. 7.9 form (the mean of the four one-sided changes, exactly half of Eq. 7.3 "
         "from the same facets, so \u00b1 half its U)";
  if (id == "dT_K")
    c = "\u0394T of the test piece (Eq. 7.10 with E_TTP in its radial Eq. 7.9 form, from the evaluation's dT_K): "
        "points with error bars \u00b1U";
  if (r != nullptr && ch != nullptr) {
    if (id == "EB_urad")
      c += "; line and band: the R-test's \u2212E_B0C \u00b1 U, negated because E_B = \u2212\u0394E_B0C (a table "
           "tilted right-handedly about +Y under a tool moving along X leaves a floor tilted the other way)";
    else if (id == "dT_K")
      c += "; line and band: \u0394T of the machine table from the R-test, E_R0T / (\u03b1 R) with \u03b1 = " +
           sig(r->alpha, 3) + " \u00b5m/(m\u00b7K) and R = " + sig(r->radius_mm, 4) +
           " mm (" + std::string(kThesis) + ", Sec. 7.3, Eq. 7.10), \u00b1 U_R0T / (\u03b1 R)";
    else
      c += std::string("; line and band: the R-test's ") + q.r_test_name + " \u00b1 U (the table's displacement " +
           "relative to the tool as a sphere cycle sees it, apparent; " + q.label + " = +\u0394" + q.r_test_name +
           " \u2212 \u0394tool)";
    c += ch->re_referenced ? "; the R-test is re-referenced to its value at the reference cut"
                           : "; the R-test does not cover the reference cut: drawn relative to its own first cycle";
  }
  return c + ".";
}

namespace {

// The inputs' rows near the errors' hours (one sample period beyond each end); all of them
// when no error has a time.
json inputRows(const InputSeries& s, const std::optional<std::pair<double, double>>& range_s) {
  if (!range_s) return s.rows;
  json out = json::array();
  const json& rows = s.rows;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double t = rows[i]["time_s"].get<double>();
    const bool next_inside = i + 1 < rows.size() && rows[i + 1]["time_s"].get<double>() >= range_s->first;
    const bool prev_inside = i > 0 && rows[i - 1]["time_s"].get<double>() <= range_s->second;
    if ((t >= range_s->first || next_inside) && (t <= range_s->second || prev_inside)) out.push_back(rows[i]);
  }
  return out;
}

// Shared frame of the two input plots: t0 signal, x over the errors' hours (clipped), y.
json inputFrame(const std::string& description, int height, double t0_s, const WarmUp& warm_up_s,
                const std::optional<std::pair<double, double>>& range_s, const json& y_fields, bool y_zero,
                const std::string& y_title) {
  json spec = baseSpec(description, height);
  spec["signals"] = json::array({{{"name", "t0_s"}, {"value", t0_s}}});
  spec["data"] = json::array();
  spec["marks"] = json::array();
  spec["scales"] = json::array();
  addWarmUp(spec, warm_up_s);
  json x = {{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false}, {"nice", false}};
  if (range_s)
    x["domain"] = json::array({(range_s->first - t0_s) / 3600.0, (range_s->second - t0_s) / 3600.0});
  else
    x["domain"] = {{"fields", y_fields.empty() ? json::array() : json::array({{{"data", y_fields[0]["data"]}, {"field", "t_h"}}})}};
  spec["scales"].push_back(x);
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", y_zero}, {"nice", true},
                            {"domain", {{"fields", y_fields}}}});
  spec["axes"] = json::array({timeAxis(), {{"orient", "left"}, {"scale", "y"}, {"title", y_title}, {"grid", true},
                                           {"tickCount", 6}, {"minExtent", 40}}});
  return spec;
}

json inputData(const std::string& name, const json& rows) {
  return {{"name", name},
          {"values", rows},
          {"transform", json::array({formulaTx("t_h", "(datum.time_s - t0_s) / 3600"),
                                     {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}};
}

}  // namespace

json temperatureSpec(const MachineInputs& in, double t0_s, const WarmUp& warm_up_s,
                     const std::optional<std::pair<double, double>>& range_s) {
  json y_fields = json::array(), meta = json::array();
  for (std::size_t i = 0; i < in.temperatures.size(); ++i) {
    const std::string name = "temperature_" + std::to_string(i + 1);
    y_fields.push_back({{"data", name}, {"field", "value"}});
  }
  json spec = inputFrame("temperatures logged by the machine against hours since the reference cut", 220, t0_s,
                         warm_up_s, range_s, y_fields, false, "temperature (\u00b0C)");
  std::vector<LegendEntry> legend;
  const json solid = json::array({1, 0});
  for (std::size_t i = 0; i < in.temperatures.size(); ++i) {
    const auto& s = in.temperatures[i];
    const std::string name = "temperature_" + std::to_string(i + 1);
    const char* colour = kTemperatureColours[i % (sizeof kTemperatureColours / sizeof *kTemperatureColours)];
    spec["data"].push_back(inputData(name, inputRows(s, range_s)));
    spec["marks"].push_back({{"type", "line"},
                             {"name", name + "_line"},
                             {"from", {{"data", name}}},
                             {"clip", true},
                             {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "value")}, {"stroke", val(colour)},
                                                    {"strokeWidth", val(1.5)}}}}}});
    meta.push_back({{"data", name}, {"label", s.column}, {"column", s.column}, {"kind", "temperature"}});
    legend.push_back({s.column, "stroke", "transparent", colour, solid});
  }
  spec["usermeta"] = {{"inputs", "temperatures"}, {"file", in.file}, {"t0_s", t0_s}, {"series", meta}};
  addLegend(spec, legend);
  spec["legends"][0]["labelLimit"] = 360;
  return spec;
}

json cLoadSpec(const MachineInputs& in, double t0_s, const WarmUp& warm_up_s,
               const std::optional<std::pair<double, double>>& range_s) {
  const json y_fields = json::array({{{"data", "c_rpm"}, {"field", "value"}}});
  json spec = inputFrame("the C axis's speed logged by the machine against hours since the reference cut", 160, t0_s,
                         warm_up_s, range_s, y_fields, true, "C-axis speed (rpm)");
  if (in.c_rpm) {
    spec["data"].push_back(inputData("c_rpm", inputRows(*in.c_rpm, range_s)));
    spec["marks"].push_back({{"type", "line"},
                             {"name", "c_rpm_line"},
                             {"from", {{"data", "c_rpm"}}},
                             {"clip", true},
                             {"encode", {{"enter", {{"x", at("x", "t_h")}, {"y", at("y", "value")},
                                                    {"stroke", val(kCLoadColour)}, {"strokeWidth", val(1.2)},
                                                    {"interpolate", val("step-after")}}}}}});
  }
  spec["usermeta"] = {{"inputs", "c_load"}, {"file", in.file}, {"t0_s", t0_s},
                      {"series", in.c_rpm ? json::array({{{"data", "c_rpm"}, {"label", "c_rpm"}, {"column", "c_rpm"},
                                                          {"kind", "c_load"}}})
                                          : json::array()}};
  return spec;
}

}  // namespace probeloop::report::ttp_detail
