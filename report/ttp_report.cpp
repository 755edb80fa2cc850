#include "report/ttp_report.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
using namespace web;

// ---------------------------------------------------------------------------------------
// The quantities of a thermal test piece and what the R-test shows beside each.

enum class RTestScale { none, same, negated, table_temperature };

struct Quantity {
  const char* id;            // as in the evaluation: "EX_um"
  const char* label;         // "E_X"
  const char* unit;          // display unit
  const char* what;          // heading
  const char* r_test;        // R-test column shown beside it, or nullptr
  const char* r_test_name;   // "E_X0C"
  RTestScale scale;
  const char* r_test_label;  // legend
};

constexpr Quantity kQuantities[] = {
    {"EX_um", "E_X", "\u00b5m", "E_X: thermal error in X (Eq. 7.1)", "EX0C_um", "E_X0C", RTestScale::same,
     "R-test E_X0C (apparent)"},
    {"EY_um", "E_Y", "\u00b5m", "E_Y: thermal error in Y (Eq. 7.2)", "EY0C_um", "E_Y0C", RTestScale::same,
     "R-test E_Y0C (apparent)"},
    {"EZ_um", "E_Z", "\u00b5m", "E_Z: thermal error in Z (Eq. 7.4)", "EZ0T_um", "E_Z0T", RTestScale::same,
     "R-test E_Z0T (apparent)"},
    {"EB_urad", "E_B", "\u00b5rad", "E_B: tilt about Y (Eq. 7.5)", "EB0C_urad", "E_B0C", RTestScale::negated,
     "R-test \u2212E_B0C"},
    {"ETTP_um", "E_TTP", "\u00b5m", "E_TTP: distortion of the test piece (Eq. 7.3)", nullptr, "", RTestScale::none, ""},
    {"dT_K", "\u0394T", "K", "\u0394T: temperature equivalent (Eq. 7.10)", "ER0T_um", "E_R0T", RTestScale::table_temperature,
     "R-test: table \u0394T"},
};

// The values "as printed" and Eq. 7.9 that the evaluation reports beside the quantities.
struct Also {
  const char* key;
  const char* title;
};
constexpr Also kAlso[] = {
    {"EX_printed_um", "E_X, Eq. 7.1 as printed (\u00b5m)"},
    {"EY_printed_um", "E_Y, Eq. 7.2 as printed (\u00b5m)"},
    {"ETTP_7_9_um", "E_TTP, Eq. 7.9 (\u00b5m)"},
};

const Quantity* findQuantity(const std::string& id) {
  for (const auto& q : kQuantities)
    if (id == q.id) return &q;
  return nullptr;
}

// Label and unit of any quantity id, known or not ("XYZ_um" -> "XYZ", "µm").
std::pair<std::string, std::string> labelAndUnit(const std::string& id, const std::string& unit_field) {
  if (const Quantity* q = findQuantity(id)) return {q->label, q->unit};
  std::string label = id, unit = unit_field;
  const std::size_t us = id.rfind('_');
  if (us != std::string::npos && us > 0) {
    if (unit.empty()) unit = id.substr(us + 1);
    if (id.substr(us + 1) == unit) label = id.substr(0, us);
  }
  return {label, displayUnit(unit)};
}

// "EX0C_um" -> "E_X0C", "µm".
std::pair<std::string, std::string> rTestLabelAndUnit(const std::string& column) {
  for (const auto& q : kQuantities)
    if (q.r_test != nullptr && column == q.r_test)
      return {q.r_test_name, displayUnit(column.substr(column.rfind('_') + 1))};
  return labelAndUnit(column, "");
}

std::string columnTitle(const std::string& label, const std::string& unit, const std::string& middle = "") {
  return label + middle + (unit.empty() ? "" : " (" + unit + ")");
}

// ---------------------------------------------------------------------------------------
// Routes (one or two evaluations) and the R-test.

const char* kRouteColours[] = {"#1f5f9f", "#d9822b"};
const char* kRouteShapes[] = {"circle", "square"};
const char* kRTestColour = "#c0392b";
const char* kRTestBand = "#f3cbc5";
const char* kWarmUpFill = "#f2a33a";

struct Route {
  const json* eval = nullptr;
  std::string file;   // as shown
  std::string label;  // "CMM"
  int index = 0;      // 0, 1
};

std::string routeName(const std::string& route) {
  if (route == "cmm") return "CMM";
  if (route == "on_machine") return "on-machine (OM)";
  if (route == "gauge") return "gauge";
  return route.empty() ? "test piece" : route;
}

void checkEvaluation(const json& j, const std::string& file) {
  const std::string what = "thermal-test-piece report: the evaluation";
  if (!j.is_object())
    throw InputError(file, 0, what + " is not a JSON object (expected the evaluation.json of `probeloop evaluate`)");
  const std::string kind = text(j, "kind");
  if (kind != "thermal_test_piece")
    throw InputError(file, 0,
                     what + (kind.empty() ? " has no \"kind\"" : " has kind \"" + kind + "\"") +
                         ", expected \"thermal_test_piece\" (the evaluation.json of `probeloop evaluate` with a "
                         "thermal-test-piece manifest)");
  const json* cycles = field(j, "cycles");
  if (cycles == nullptr || !cycles->is_array())
    throw InputError(file, 0, what + " has no \"cycles\" array");
}

const json* findValue(const json& cycle, const std::string& quantity) {
  for (const auto& v : array(cycle, "values"))
    if (text(v, "quantity") == quantity) return &v;
  return nullptr;
}

// The reference cut: phase "reference", else the lowest cycle number, else the first cycle.
std::optional<double> referenceTime(const json& eval) {
  const json* best = nullptr;
  for (const auto& c : array(eval, "cycles")) {
    if (!number(c, "time_s")) continue;
    if (text(c, "phase") == "reference") return number(c, "time_s");
    if (best == nullptr || number(c, "cycle").value_or(1e300) < number(*best, "cycle").value_or(1e300)) best = &c;
  }
  return best ? number(*best, "time_s") : std::nullopt;
}

json optionalNumber(const std::optional<double>& x) { return x ? json(*x) : json(nullptr); }

json cycleNumber(const json& c) {
  const auto n = number(c, "cycle");
  return n ? json(*n == std::round(*n) ? json(static_cast<long long>(*n)) : json(*n)) : json(nullptr);
}

// Rows {time_s, cycle, value, U} of one quantity in one route (cycles without it left out).
json routeRows(const json& eval, const std::string& quantity) {
  json rows = json::array();
  for (const auto& c : array(eval, "cycles")) {
    const auto t = number(c, "time_s");
    const json* v = findValue(c, quantity);
    if (!t || v == nullptr || !number(*v, "value")) continue;
    rows.push_back({{"time_s", *t}, {"cycle", cycleNumber(c)}, {"value", *number(*v, "value")},
                    {"U", optionalNumber(number(*v, "U"))}});
  }
  return rows;
}

json alsoRows(const json& eval, const char* key) {
  json rows = json::array();
  for (const auto& c : array(eval, "cycles")) {
    const auto t = number(c, "time_s");
    const auto v = number(object(c, "also"), key);
    if (!t || !v) continue;
    rows.push_back({{"time_s", *t}, {"cycle", cycleNumber(c)}, {"value", *v}, {"U", nullptr}});
  }
  return rows;
}

struct RTest {
  std::string file;
  CsvTable table;
  std::vector<double> time_s;  // per row
  std::optional<double> t0;    // the reference cut, if any
  double alpha = 11.0, radius_mm = 160.0;
};

constexpr const char* kRTestColumns[] = {"EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"};

RTest readRTest(const std::string& text_in, const std::string& file, const TtpReportOptions& o) {
  RTest r;
  r.file = file;
  r.table = parseCsv(text_in, file);
  r.alpha = o.table_alpha_um_per_m_K;
  r.radius_mm = o.r_test_radius_mm;
  const int tc = r.table.column("time_s");
  if (tc < 0)
    throw InputError(file, r.table.header_line,
                     "the R-test error series has no time_s column (expected the errors.csv of `probeloop evaluate` "
                     "for a sphere artifact: time_s,cycle,EX0C_um,...)");
  bool any = false;
  for (const char* c : kRTestColumns) any |= r.table.column(c) >= 0;
  if (!any)
    throw InputError(file, r.table.header_line,
                     "the R-test error series has none of the columns EX0C_um, EY0C_um, EZ0T_um, ER0T_um, EA0C_urad, "
                     "EB0C_urad, EC0C_urad");
  for (const auto& row : r.table.rows) r.time_s.push_back(r.table.number(row, tc));
  if (!(r.alpha > 0) || !(r.radius_mm > 0) || !std::isfinite(r.alpha) || !std::isfinite(r.radius_mm))
    throw InputError(file, 0, "Eq. 7.10 for the table needs alpha > 0 and R > 0");
  return r;
}

std::optional<double> cell(const CsvTable& t, const CsvRow& row, int col) {
  double v = 0;
  if (!t.tryNumber(row, col, v)) return std::nullopt;
  return v;
}

struct RTestChannel {
  json rows = json::array();
  bool re_referenced = false;
  double offset = 0;  // subtracted, in the column's unit (before the scale)
  double scale = 1;   // value shown = scale * (input - offset)
};

// One R-test column as drawn beside a quantity: re-referenced to the reference cut when the
// series covers it, then scaled (negated for -E_B0C, 1/(alpha R) for the table's ΔT).
RTestChannel rTestChannel(const RTest& r, const char* column, RTestScale scale) {
  RTestChannel ch;
  const int col = r.table.column(column);
  const int uc = r.table.column(std::string("U_") + column);
  const int cc = r.table.column("cycle");
  if (col < 0) return ch;
  switch (scale) {
    case RTestScale::negated: ch.scale = -1; break;
    case RTestScale::table_temperature: ch.scale = 1.0 / (r.alpha * r.radius_mm * 1e-3); break;
    default: ch.scale = 1;
  }
  struct P {
    double t, v;
    std::optional<double> U, cycle;
  };
  std::vector<P> points;
  for (std::size_t i = 0; i < r.table.rows.size(); ++i) {
    const auto v = cell(r.table, r.table.rows[i], col);
    if (!v) continue;
    points.push_back({r.time_s[i], *v, cell(r.table, r.table.rows[i], uc), cell(r.table, r.table.rows[i], cc)});
  }
  std::stable_sort(points.begin(), points.end(), [](const P& a, const P& b) { return a.t < b.t; });
  if (r.t0 && !points.empty() && *r.t0 >= points.front().t && *r.t0 <= points.back().t) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (points[i].t == *r.t0) {
        ch.offset = points[i].v;
        break;
      }
      if (i + 1 < points.size() && points[i].t < *r.t0 && *r.t0 < points[i + 1].t) {
        const double w = (*r.t0 - points[i].t) / (points[i + 1].t - points[i].t);
        ch.offset = points[i].v + w * (points[i + 1].v - points[i].v);
        break;
      }
    }
    ch.re_referenced = true;
  }
  for (const auto& p : points) {
    json cycle = nullptr;
    if (p.cycle) cycle = *p.cycle == std::round(*p.cycle) ? json(static_cast<long long>(*p.cycle)) : json(*p.cycle);
    ch.rows.push_back({{"time_s", p.t},
                       {"cycle", cycle},
                       {"input", p.v},
                       {"value", ch.scale * (p.v - ch.offset)},
                       {"U", p.U ? json(std::abs(ch.scale) * *p.U) : json(nullptr)}});
  }
  return ch;
}

// ---------------------------------------------------------------------------------------
// Vega specs: one per quantity.

struct Series {
  std::string data, label, kind;  // kind: route | eq_7_9 | r_test
  int route = -1;
  json rows;
};

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

json plotSpec(const Quantity& q, const std::vector<Series>& series, double t0_s,
              const std::optional<std::pair<double, double>>& warm_up_s) {
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
  spec["scales"].push_back({{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false}, {"nice", false},
                            {"domain", {{"fields", x_fields}}}});
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true},
                            {"domain", {{"fields", y_fields}}}});
  spec["axes"] = json::array(
      {{{"orient", "bottom"}, {"scale", "x"}, {"title", "time since the reference cut (h)"}, {"tickCount", 10}},
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
    c += "; open diamonds, dashed: the Eq. 7.9 form (the mean of the four one-sided changes, half of Eq. 7.3; no U "
         "in the evaluation)";
  if (id == "dT_K")
    c = "\u0394T of the test piece (Eq. 7.10 with E_TTP in its radial Eq. 7.9 form, from the evaluation's dT_K): "
        "points with error bars \u00b1U";
  if (r != nullptr && ch != nullptr) {
    if (id == "EB_urad")
      c += "; line and band: the R-test's \u2212E_B0C \u00b1 U, negated because E_B = \u2212\u0394E_B0C (a table "
           "tilted right-handedly about +Y under a tool moving along X leaves a floor tilted the other way; "
           "docs/thermal-test-piece.md \u00a74)";
    else if (id == "dT_K")
      c += "; line and band: \u0394T of the machine table from the R-test, E_R0T / (\u03b1 R) with \u03b1 = " +
           sig(r->alpha, 3) + " \u00b5m/(m\u00b7K) and R = " + sig(r->radius_mm, 4) +
           " mm (seed 004 L2177), \u00b1 U_R0T / (\u03b1 R)";
    else
      c += std::string("; line and band: the R-test's ") + q.r_test_name + " \u00b1 U (the table's displacement " +
           "relative to the tool as a sphere cycle sees it, apparent; " + q.label + " = +\u0394" + q.r_test_name +
           " \u2212 \u0394tool)";
    c += ch->re_referenced ? "; the R-test is re-referenced to its value at the reference cut"
                           : "; the R-test does not cover the reference cut: drawn relative to its own first cycle";
  }
  return c + ".";
}

// ---------------------------------------------------------------------------------------
// Tables.

std::string twoDecimals(const std::optional<double>& x) { return x ? fixed(*x, 2) : kDash; }

std::string phaseText(const std::string& phase) {
  if (phase == "warm_up") return "warm-up";
  return phase.empty() ? kDash : phase;
}

std::string cycleHours(const json& c, double t0_s) {
  const auto t = number(c, "time_s");
  return t ? fixed((*t - t0_s) / 3600.0, 2) : kDash;
}

// Quantities present in a route, known ones first in their order, then others as they come.
std::vector<std::pair<std::string, std::string>> routeQuantities(const json& eval) {
  std::vector<std::pair<std::string, std::string>> out;  // id, unit field
  const auto add = [&out](const std::string& id, const std::string& unit) {
    for (const auto& o : out)
      if (o.first == id) return;
    out.emplace_back(id, unit);
  };
  for (const auto& q : kQuantities)
    for (const auto& c : array(eval, "cycles"))
      if (const json* v = findValue(c, q.id); v && number(*v, "value")) {
        add(q.id, text(*v, "unit"));
        break;
      }
  for (const auto& c : array(eval, "cycles"))
    for (const auto& v : array(c, "values"))
      if (!text(v, "quantity").empty() && number(v, "value")) add(text(v, "quantity"), text(v, "unit"));
  return out;
}

std::string listText(const json& a) {
  std::string s;
  for (const auto& x : a) s += (s.empty() ? "" : ", ") + (x.is_string() ? x.get<std::string>() : x.dump());
  return s;
}

void cycleTable(Page& page, const Route& r, double t0_s) {
  const json& eval = *r.eval;
  const auto quantities = routeQuantities(eval);
  const json& cycles = array(eval, "cycles");
  page.html += "<h3>" + esc(r.label) + ": values per cycle (value \u00b1 U; t = hours since the reference cut)</h3>\n";
  if (cycles.empty()) {
    page.html += "<p class=\"note\">No cycles in the evaluation.</p>\n";
    return;
  }
  bool any_missing = false;
  for (const auto& c : cycles) any_missing |= !array(c, "missing").empty();
  page.html += "<table class=\"cycles\">\n<thead><tr>" + th("cycle", true) + th("phase") +
               th("t (h)", true);
  for (const auto& [id, unit] : quantities) {
    const auto [label, u] = labelAndUnit(id, unit);
    page.html += th(columnTitle(label, u, " \u00b1 U"), true);
  }
  if (any_missing) page.html += th("missing");
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& c : cycles) {
    page.html += "<tr>" + td(whole(number(c, "cycle")), true) + td(phaseText(text(c, "phase"))) +
                 td(cycleHours(c, t0_s), true);
    for (const auto& [id, unit] : quantities) {
      const json* v = findValue(c, id);
      page.html += td(v ? valueU(number(*v, "value"), number(*v, "U")) : kDash, true);
    }
    if (any_missing) {
      const std::string m = listText(array(c, "missing"));
      page.html += td(m.empty() ? kDash : m);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";

  std::vector<const Also*> also;
  for (const auto& a : kAlso)
    for (const auto& c : cycles)
      if (number(object(c, "also"), a.key)) {
        also.push_back(&a);
        break;
      }
  if (also.empty()) return;
  page.html += "<h3>" + esc(r.label) +
               ": reported beside them (Eqs. 7.1 and 7.2 exactly as printed in seed 004; Eq. 7.9)</h3>\n"
               "<table class=\"also\">\n<thead><tr>" +
               th("cycle", true) + th("t (h)", true);
  for (const auto* a : also) page.html += th(a->title, true);
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& c : cycles) {
    page.html += "<tr>" + td(whole(number(c, "cycle")), true) + td(cycleHours(c, t0_s), true);
    for (const auto* a : also) page.html += td(twoDecimals(number(object(c, "also"), a->key)), true);
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

std::string periodText(const json& row) {
  std::string s = withUnit(whole(number(row, "period_h")), "h");
  const json& cyc = array(row, "cycles");
  if (cyc.size() == 2 && number(&cyc[0]) && number(&cyc[1]))
    s += " (cycles " + whole(number(&cyc[0])) + "\u2013" + whole(number(&cyc[1])) + ")";
  return s;
}

// Table 7.2's layout: one row per period, one column (group) per quantity.
void spanTable(Page& page, const Route& r) {
  const json& spans = array(*r.eval, "spans");
  page.html += "<h3>" + esc(r.label) + ": spans of the changes (Table 7.2 layout)</h3>\n";
  if (spans.empty()) {
    page.html += "<p class=\"note\">No spans in the evaluation.</p>\n";
    return;
  }
  std::vector<std::string> ids;
  for (const auto& q : kQuantities)
    for (const auto& s : spans)
      for (const auto& v : array(s, "values"))
        if (text(v, "quantity") == q.id && std::find(ids.begin(), ids.end(), q.id) == ids.end()) ids.push_back(q.id);
  for (const auto& s : spans)
    for (const auto& v : array(s, "values"))
      if (const std::string id = text(v, "quantity"); !id.empty() && std::find(ids.begin(), ids.end(), id) == ids.end())
        ids.push_back(id);
  page.html += "<table class=\"spans\">\n<thead><tr>" + th("period");
  for (const auto& id : ids) {
    const auto [label, unit] = labelAndUnit(id, "");
    page.html += th(columnTitle(label, unit, " span \u00b1 U"), true);
  }
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& s : spans) {
    page.html += "<tr>" + th(periodText(s));
    for (const auto& id : ids) {
      const json* found = nullptr;
      for (const auto& v : array(s, "values"))
        if (text(v, "quantity") == id) found = &v;
      page.html += td(found ? valueU(number(*found, "span"), number(*found, "U")) : kDash, true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

void comparisonTable(Page& page, const Route& r) {
  const json* cmp = field(*r.eval, "comparison");
  if (cmp == nullptr || !cmp->is_object()) return;
  const json& rows = array(*cmp, "rows");
  const std::string against = text(*cmp, "against");
  page.html += "<h3>" + esc(r.label) + ": spans compared (Table 7.2 layout)</h3>\n<p class=\"note\">this: " +
               esc(r.file.empty() ? r.label : r.file) + "; against: " + esc(against.empty() ? kDash : against) +
               "; reduction = (this \u2212 against) / this, this run taken as the uncompensated one (UC) and the other as "
               "the compensated one (C), as in seed 004 Table 7.2.</p>\n";
  if (rows.empty()) {
    page.html += "<p class=\"note\">No rows in the comparison.</p>\n";
    return;
  }
  std::vector<double> periods;
  std::vector<std::string> ids;
  for (const auto& q : kQuantities)
    for (const auto& row : rows)
      if (text(row, "quantity") == q.id && std::find(ids.begin(), ids.end(), q.id) == ids.end()) ids.push_back(q.id);
  for (const auto& row : rows) {
    if (const std::string id = text(row, "quantity"); !id.empty() && std::find(ids.begin(), ids.end(), id) == ids.end())
      ids.push_back(id);
    if (const auto p = number(row, "period_h"); p && std::find(periods.begin(), periods.end(), *p) == periods.end())
      periods.push_back(*p);
  }
  page.html += "<table class=\"comparison\">\n<thead><tr><th rowspan=\"2\">period</th>";
  for (const auto& id : ids) {
    const auto [label, unit] = labelAndUnit(id, "");
    page.html += "<th colspan=\"3\" class=\"group\">" + esc(columnTitle(label, unit)) + "</th>";
  }
  page.html += "</tr>\n<tr>";
  for (std::size_t i = 0; i < ids.size(); ++i)
    page.html += th("this", true) + th("against", true) + th("reduction (%)", true);
  page.html += "</tr></thead>\n<tbody>\n";
  for (const double p : periods) {
    page.html += "<tr>" + th(withUnit(whole(p), "h"));
    for (const auto& id : ids) {
      const json* found = nullptr;
      for (const auto& row : rows)
        if (text(row, "quantity") == id && number(row, "period_h") == p) found = &row;
      if (found == nullptr) {
        page.html += td(kDash, true) + td(kDash, true) + td(kDash, true);
        continue;
      }
      page.html += td(sig(number(*found, "this"), 3), true) + td(sig(number(*found, "other"), 3), true) +
                   td(number(*found, "reduction_percent") ? fixed(*number(*found, "reduction_percent"), 1) : kDash, true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

// Per quantity, the largest contribution (by |u|) in the last cycle that has the quantity.
void budgetTable(Page& page, const Route& r) {
  const auto quantities = routeQuantities(*r.eval);
  const json& cycles = array(*r.eval, "cycles");
  std::string rows;
  for (const auto& [id, unit_field] : quantities) {
    const json* cycle = nullptr;
    const json* value = nullptr;
    for (const auto& c : cycles)
      if (const json* v = findValue(c, id); v && number(*v, "value")) cycle = &c, value = v;
    if (value == nullptr) continue;
    const auto [label, unit] = labelAndUnit(id, unit_field);
    const json* largest = nullptr;
    for (const auto& k : array(*value, "contributions"))
      if (number(k, "u") && (largest == nullptr || std::abs(*number(k, "u")) > std::abs(*number(*largest, "u"))))
        largest = &k;
    rows += "<tr>" + th(columnTitle(label, unit)) + td(whole(number(*cycle, "cycle")), true) +
            td(valueU(number(*value, "value"), number(*value, "U")), true) + td(sig(number(*value, "u_c"), 2), true) +
            td(sig(number(*value, "nu_eff"), 3), true) + td(sig(number(*value, "k"), 3), true);
    if (largest == nullptr) {
      rows += td(kDash) + td(kDash) + td(kDash) + td(kDash, true) + td(kDash, true) + td(kDash) + "</tr>\n";
      continue;
    }
    const std::string input = text(*largest, "input");
    rows += td(input.empty() ? kDash : input) + td(text(*largest, "type").empty() ? kDash : text(*largest, "type")) +
            td(text(*largest, "distribution").empty() ? kDash : text(*largest, "distribution")) +
            td(withUnit(sig(number(*largest, "u"), 2), unit), true) + td(sig(number(*largest, "dof"), 3), true) +
            td(text(*largest, "basis").empty() ? kDash : text(*largest, "basis")) + "</tr>\n";
  }
  page.html += "<h3>" + esc(r.label) + ": largest budget contribution per quantity (last cycle that has it)</h3>\n";
  if (rows.empty()) {
    page.html += "<p class=\"note\">No budgets in the evaluation.</p>\n";
    return;
  }
  page.html += "<table class=\"budget\">\n<thead><tr>" + th("quantity") + th("cycle", true) + th("value \u00b1 U", true) +
               th("u_c", true) + th("\u03bd_eff", true) + th("k", true) + th("largest input") + th("type") +
               th("distribution") + th("u", true) + th("dof", true) + th("basis") + "</tr></thead>\n<tbody>\n" + rows +
               "</tbody>\n</table>\n";
}

void formulaTable(Page& page, const json& formulas, const std::string& heading) {
  page.html += "<h3>" + esc(heading) + "</h3>\n";
  if (formulas.empty()) {
    page.html += "<p class=\"note\">No formulas in the evaluation.</p>\n";
    return;
  }
  page.html += "<table class=\"formulas\">\n<thead><tr>" + th("output") + th("formula") + th("source") + th("features") +
               "</tr></thead>\n<tbody>\n";
  for (const auto& f : formulas) {
    const auto cellText = [&f](const char* k) {
      const std::string s = text(f, k);
      return s.empty() ? kDash : s;
    };
    page.html += "<tr>" + td(cellText("output")) + td(cellText("formula")) + td(cellText("source")) +
                 td(cellText("features")) + "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

void inputsTable(Page& page, const std::vector<Route>& routes, const RTest* r, double t0_s,
                 const std::vector<std::pair<std::string, RTestChannel>>& channels) {
  page.html += "<table class=\"meta\">\n";
  const auto row = [&page](const std::string& name, const std::string& value) {
    page.html += "<tr>" + th(name) + td(value.empty() ? kDash : value) + "</tr>\n";
  };
  for (const auto& rt : routes) {
    const json& in = object(*rt.eval, "input");
    const std::string prefix = routes.size() > 1 ? "route " + std::to_string(rt.index + 1) + " " : "";
    row(prefix + "evaluation", rt.file);
    std::string what = rt.label;
    const std::string file = text(in, "file"), format = text(in, "format"), by = text(in, "assigned_by");
    if (!file.empty()) what += ": " + file;
    std::string facts;
    if (!format.empty()) facts += "format " + format;
    if (const auto n = number(in, "points")) facts += (facts.empty() ? "" : ", ") + whole(*n) + " points";
    if (!by.empty()) facts += (facts.empty() ? "" : ", ") + std::string("assigned by ") + by;
    if (!facts.empty()) what += " (" + facts + ")";
    row(prefix + "measured", what);
    row(prefix + "manifest", text(*rt.eval, "manifest"));
    const json& scatter = object(*rt.eval, "point_scatter");
    if (number(scatter, "type_a_sigma_um") || number(scatter, "type_b_sigma_um"))
      row(prefix + "point scatter", "type A \u03c3 = " + withUnit(sig(number(scatter, "type_a_sigma_um"), 2), "\u00b5m") +
                                        " (\u03bd = " + whole(number(scatter, "type_a_dof")) + "), type B \u03c3 = " +
                                        withUnit(sig(number(scatter, "type_b_sigma_um"), 2), "\u00b5m") + "; used: " +
                                        (text(scatter, "used").empty() ? kDash : text(scatter, "used")));
    if (rt.index > 0) {
      const auto t = referenceTime(*rt.eval);
      if (t && std::abs(*t - t0_s) > 1.0)
        row(prefix + "reference cut", "at " + withUnit(sig(*t, 7), "s") + ", not at the first route's " +
                                          withUnit(sig(t0_s, 7), "s") + ": its points are drawn on the common clock");
    }
  }
  row("reference cut (time_s on the common clock)", withUnit(sig(t0_s, 7), "s"));
  if (r != nullptr) {
    std::string span;
    if (!r->time_s.empty()) {
      const auto [lo, hi] = std::minmax_element(r->time_s.begin(), r->time_s.end());
      span = ", " + fixed((*lo - t0_s) / 3600.0, 2) + " \u2013 " + fixed((*hi - t0_s) / 3600.0, 2) + " h";
    }
    row("R-test", (r->file.empty() ? std::string("R-test error series") : r->file) + " (" +
                      std::to_string(r->table.rows.size()) + " cycles" + span + ")");
    std::string ref;
    for (const auto& [column, ch] : channels) {
      if (ch.rows.empty()) continue;
      const auto [label, unit] = rTestLabelAndUnit(column);
      ref += (ref.empty() ? "" : "; ") + label + ": " +
             (ch.re_referenced ? withUnit(sig(ch.offset, 3), unit) : std::string("not covered, as given"));
    }
    row("R-test value at the reference cut, subtracted", ref);
    row("Eq. 7.10 for the table", "\u03b1 = " + sig(r->alpha, 3) + " \u00b5m/(m\u00b7K), R = " + sig(r->radius_mm, 4) +
                                      " mm: \u0394T = E_R0T / (\u03b1 R)");
  }
  page.html += "</table>\n";
}

}  // namespace

std::string thermalTestPieceReportHtml(const json& evaluation, const json* second_route,
                                       const std::string* r_test_errors_csv_text, const std::string& vega_js_path,
                                       const TtpReportOptions& options) {
  const std::string first_file = options.evaluation_file.empty() ? "evaluation" : options.evaluation_file;
  const std::string second_file = options.second_file.empty() ? "second evaluation" : options.second_file;
  checkEvaluation(evaluation, options.evaluation_file);
  if (second_route != nullptr) checkEvaluation(*second_route, options.second_file);
  std::optional<RTest> r_test;
  if (r_test_errors_csv_text != nullptr)
    r_test = readRTest(*r_test_errors_csv_text, options.r_test_file, options);
  const std::string vega = vegaRuntime(vega_js_path);  // a missing runtime is an error whatever the data

  std::vector<Route> routes;
  routes.push_back({&evaluation, first_file, routeName(text(object(evaluation, "input"), "route")), 0});
  if (second_route != nullptr)
    routes.push_back({second_route, second_file, routeName(text(object(*second_route, "input"), "route")), 1});
  if (routes.size() == 2 && routes[0].label == routes[1].label) {
    routes[0].label += " #1";
    routes[1].label += " #2";
  }
  const std::optional<double> t0_opt = referenceTime(evaluation);
  const double t0_s = t0_opt.value_or(0.0);
  if (r_test) r_test->t0 = t0_opt;

  // The warm-up hours: from the reference cut to the last warm-up cycle of the first route.
  std::optional<std::pair<double, double>> warm_up;
  for (const auto& c : array(evaluation, "cycles"))
    if (text(c, "phase") == "warm_up" && number(c, "time_s")) {
      const double t = *number(c, "time_s");
      warm_up = {t0_s, warm_up ? std::max(warm_up->second, t) : t};
    }
  if (warm_up && !(warm_up->second > warm_up->first)) warm_up.reset();

  // Per quantity present in a route: its series (the R-test first, drawn behind).
  struct PlotEntry {
    const Quantity* q;
    std::vector<Series> series;
    std::optional<RTestChannel> r_test;
    bool has_eq79 = false;
  };
  std::vector<PlotEntry> plots;
  std::vector<std::pair<std::string, RTestChannel>> channels;  // R-test columns drawn
  for (const auto& q : kQuantities) {
    PlotEntry e{&q, {}, std::nullopt, false};
    for (const auto& rt : routes) {
      json rows = routeRows(*rt.eval, q.id);
      if (!rows.empty())
        e.series.push_back({"route" + std::to_string(rt.index + 1), rt.label, "route", rt.index, std::move(rows)});
      if (std::string(q.id) == "ETTP_um") {
        json r79 = alsoRows(*rt.eval, "ETTP_7_9_um");
        if (!r79.empty()) {
          e.series.push_back({"route" + std::to_string(rt.index + 1) + "_eq_7_9", rt.label + ", Eq. 7.9", "eq_7_9",
                              rt.index, std::move(r79)});
          e.has_eq79 = true;
        }
      }
    }
    if (e.series.empty()) continue;  // the quantity is in no route: no plot
    if (r_test && q.r_test != nullptr) {
      RTestChannel ch = rTestChannel(*r_test, q.r_test, q.scale);
      if (!ch.rows.empty()) {
        e.series.insert(e.series.begin(), {"r_test", q.r_test_label, "r_test", -1, ch.rows});
        channels.emplace_back(q.r_test, ch);
        e.r_test = std::move(ch);
      }
    }
    plots.push_back(std::move(e));
  }

  std::string title = "Thermal test piece: ";
  for (std::size_t i = 0; i < routes.size(); ++i) title += (i ? " and " : "") + routes[i].label;
  if (r_test) title += ", with the R-test";

  Page page;
  page.html += "<header>\n<h1>" + esc(title) + "</h1>\n<p class=\"note\">Seed 004 Ch. 7 (Wiessner et al., Precision "
               "Engineering 52 (2018)); the test piece's features, frames and signs: docs/thermal-test-piece.md. "
               "Every error is the change of the cycle's surfaces against the reference cut; time runs from the "
               "reference cut.</p>\n";
  inputsTable(page, routes, r_test ? &*r_test : nullptr, t0_s, channels);
  page.html += "</header>\n<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" +
               std::string(kErrorHook) + "</script>\n";

  page.html += "<section class=\"plots\">\n<h2>Thermal errors against time</h2>\n";
  for (const auto& e : plots) {
    page.html += "<h3>" + esc(e.q->what) + "</h3>\n";
    page.plot(plotSpec(*e.q, e.series, t0_s, warm_up),
              plotCaption(*e.q, r_test ? &*r_test : nullptr, e.r_test ? &*e.r_test : nullptr, e.has_eq79) +
                  (warm_up ? " Shaded: the warm-up hours." : ""));
  }
  if (plots.empty()) page.html += "<p class=\"note\">No values in the evaluation: nothing to plot.</p>\n";
  page.html += "</section>\n";

  page.html += "<section class=\"values\">\n<h2>Values per cycle</h2>\n";
  for (const auto& rt : routes) cycleTable(page, rt, t0_s);
  page.html += "</section>\n<section class=\"spans\">\n<h2>Spans</h2>\n";
  for (const auto& rt : routes) {
    spanTable(page, rt);
    comparisonTable(page, rt);
  }
  page.html += "</section>\n<section class=\"budgets\">\n<h2>Uncertainty budgets</h2>\n";
  for (const auto& rt : routes) budgetTable(page, rt);
  page.html += "</section>\n<section class=\"formulas\">\n<h2>Formulas</h2>\n";
  formulaTable(page, array(evaluation, "formulas"), routes[0].label + ": which features give which error");
  if (second_route != nullptr && array(*second_route, "formulas") != array(evaluation, "formulas"))
    formulaTable(page, array(*second_route, "formulas"), routes[1].label + ": which features give which error");
  page.html += "</section>\n";

  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
      "content=\"probeloop\">\n<title>" +
      esc(title) + "</title>\n<style>" + kStyle +
      "th.group { text-align: center; }\n</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report
