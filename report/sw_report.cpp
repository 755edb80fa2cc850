#include "report/sw_report.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
using namespace web;

constexpr const char* kColours[] = {"#1f5fa8", "#c0492b"};
constexpr const char* kShapes[] = {"circle", "square"};
constexpr const char* kBefore = "#8c8c8c";
constexpr const char* kPromised = "#2e8b57";
// Yaqoob 2017: how the page names seed 000.
constexpr const char* kThesis = "Yaqoob 2017 (MSc thesis, Sabanc\u0131 University)";

json at(const char* scale, const char* f) { return {{"scale", scale}, {"field", f}}; }
json val(const json& v) { return {{"value", v}}; }

// One evaluated part: the plain one, or the one cut with the compensation.
struct Part {
  const json* eval = nullptr;
  std::string file, label;  // label: "" when the page shows one part
  bool open = false;        // drawn with open symbols (the compensated part beside the plain one)
};

struct Series {
  std::string name, label;
  json rows = json::array();  // {x, value, U, step}
  int colour = 0;
  bool open = false;
};

// A budget's value and U from the evaluation's JSON (evaluate/budget_json.hpp).
std::optional<double> budgetValue(const json& s, const char* key) { return number(object(s, key), "value"); }
std::optional<double> budgetU(const json& s, const char* key) { return number(object(s, key), "U"); }

std::string partPrefix(const Part& p) { return p.label.empty() ? "" : p.label + ": "; }

Series componentSeries(const Part& p, const char* key, const char* x_key, const std::string& label, int colour) {
  Series s{std::string(key) + (p.open ? "_compensated" : ""), partPrefix(p) + label, json::array(), colour, p.open};
  for (const auto& st : array(*p.eval, "separation")) {
    const auto x = number(st, x_key);
    const auto v = budgetValue(st, key);
    if (!x || !v) continue;
    s.rows.push_back({{"x", *x}, {"value", *v}, {"U", budgetU(st, key).value_or(0.0)}, {"step", number(st, "step").value_or(0)}});
  }
  return s;
}

// Points with +-U bars for each series, optional extra lines (rows {x, value}) drawn behind.
json pointsSpec(const std::string& description, const std::string& x_title, const std::string& y_title,
                const std::vector<Series>& series, const std::vector<Series>& lines, bool x_zero) {
  json spec = baseSpec(description, 240);
  spec["data"] = json::array();
  spec["marks"] = json::array();
  json x_fields = json::array(), y_fields = json::array();
  json meta = json::array();
  for (const auto& s : series) {
    spec["data"].push_back({{"name", s.name}, {"values", s.rows},
                            {"transform", json::array({formulaTx("lo", "datum.value - datum.U"),
                                                       formulaTx("hi", "datum.value + datum.U")})}});
    x_fields.push_back({{"data", s.name}, {"field", "x"}});
    y_fields.push_back({{"data", s.name}, {"field", "lo"}});
    y_fields.push_back({{"data", s.name}, {"field", "hi"}});
    meta.push_back({{"data", s.name}, {"label", s.label}});
  }
  for (const auto& l : lines) {
    spec["data"].push_back({{"name", l.name}, {"values", l.rows}});
    x_fields.push_back({{"data", l.name}, {"field", "x"}});
    y_fields.push_back({{"data", l.name}, {"field", "value"}});
    meta.push_back({{"data", l.name}, {"label", l.label}});
  }
  spec["usermeta"] = {{"series", meta}};
  spec["scales"] = json::array(
      {{{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", x_zero}, {"nice", true}, {"domain", {{"fields", x_fields}}}},
       {{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true}, {"domain", {{"fields", y_fields}}}}});
  spec["axes"] = json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", x_title}},
                              {{"orient", "left"}, {"scale", "y"}, {"title", y_title}, {"grid", true}, {"minExtent", 40}}});
  std::vector<LegendEntry> legend;
  const json solid = json::array({1, 0}), dashed = json::array({5, 3});
  for (const auto& l : lines) {
    const char* colour = kColours[l.colour % 2];
    const json dash = l.open ? json::array({2, 2}) : dashed;
    spec["marks"].push_back({{"type", "line"}, {"from", {{"data", l.name}}},
                             {"encode", {{"enter", {{"x", at("x", "x")}, {"y", at("y", "value")}, {"stroke", val(colour)},
                                                    {"strokeWidth", val(1)}, {"strokeDash", val(dash)}}}}}});
    legend.push_back({l.label, "stroke", "transparent", colour, dash});
  }
  const double n = static_cast<double>(series.size());
  for (std::size_t i = 0; i < series.size(); ++i) {
    const Series& s = series[i];
    const char* colour = kColours[s.colour % 2];
    const char* shape = kShapes[s.colour % 2];
    json x = at("x", "x");
    // Display only: the series drawn 3 px apart so that none hides another's bars.
    if (series.size() > 1) x["offset"] = 3.0 * (static_cast<double>(i) - (n - 1) / 2.0);
    spec["marks"].push_back({{"type", "rule"}, {"name", s.name + "_error_bars"}, {"from", {{"data", s.name}}},
                             {"encode", {{"enter", {{"x", x}, {"y", at("y", "lo")}, {"y2", at("y", "hi")},
                                                    {"stroke", val(colour)}, {"strokeWidth", val(1.5)}}}}}});
    json point = {{"x", x}, {"y", at("y", "value")}, {"shape", val(shape)}, {"size", val(45)}};
    if (s.open) {
      point["fill"] = val("#ffffff");
      point["stroke"] = val(colour);
      point["strokeWidth"] = val(1.5);
    } else {
      point["fill"] = val(colour);
    }
    spec["marks"].push_back({{"type", "symbol"}, {"from", {{"data", s.name}}}, {"encode", {{"enter", point}}}});
    legend.push_back({s.label + " \u00b1 U", shape, s.open ? "transparent" : colour, colour, solid});
  }
  addLegend(spec, legend);
  spec["legends"][0]["labelLimit"] = 360;
  // Two parts give eight entries: in one row they would widen the plot past the page.
  if (legend.size() > 4) spec["legends"][0]["columns"] = 2;
  return spec;
}

// Per feature (ordinal): before and after, each +- its U where known, and the promised after
// (before - promised fall) +- U.
json beforeAfterSpec(const json& rows) {
  json spec = baseSpec("CMM error per feature before and after the compensation, each \u00b1 U, with the promised error \u00b1 U",
                       260);
  const auto bars = [](const char* name, const char* value, const char* U) {
    return json{{"name", name}, {"source", "features"},
                {"transform", json::array({filterTx(std::string("isValid(datum.") + U + ")"),
                                           formulaTx("lo", std::string("datum.") + value + " - datum." + U),
                                           formulaTx("hi", std::string("datum.") + value + " + datum." + U)})}};
  };
  spec["data"] = json::array(
      {{{"name", "features"}, {"values", rows},
        {"transform", json::array({formulaTx("expected", "datum.before - datum.promised"),
                                   formulaTx("lo", "datum.before - datum.promised - datum.U"),
                                   formulaTx("hi", "datum.before - datum.promised + datum.U")})}},
       bars("before_U", "before", "U_before"), bars("after_U", "after", "U_after")});
  spec["usermeta"] = {{"series", json::array({{{"data", "features"}, {"label", "before, after, promised"}}})}};
  json y_fields = json::array({{{"data", "features"}, {"field", "before"}}, {{"data", "features"}, {"field", "after"}},
                               {{"data", "features"}, {"field", "lo"}}, {{"data", "features"}, {"field", "hi"}}});
  for (const char* d : {"before_U", "after_U"})
    for (const char* f : {"lo", "hi"}) y_fields.push_back({{"data", d}, {"field", f}});
  spec["scales"] = json::array(
      {{{"name", "x"}, {"type", "point"}, {"range", "width"}, {"padding", 0.5}, {"domain", {{"data", "features"}, {"field", "feature"}}}},
       {{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true}, {"domain", {{"fields", y_fields}}}}});
  spec["axes"] = json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", "feature (step, quantity)"}, {"labelAngle", -40},
                               {"labelAlign", "right"}},
                              {{"orient", "left"}, {"scale", "y"}, {"title", "CMM error (\u00b5m)"}, {"grid", true}, {"minExtent", 40}}});
  const auto dodged = [](double offset) {
    json x = at("x", "feature");
    x["offset"] = offset;
    return x;
  };
  const auto ruleMark = [](const char* name, const char* data, const json& x, const char* colour) {
    return json{{"type", "rule"}, {"name", name}, {"from", {{"data", data}}},
                {"encode", {{"enter", {{"x", x}, {"y", at("y", "lo")}, {"y2", at("y", "hi")}, {"stroke", val(colour)},
                                       {"strokeWidth", val(1.5)}}}}}};
  };
  const auto symbolMark = [](const json& x, const char* field, const char* shape, const char* colour) {
    return json{{"type", "symbol"}, {"from", {{"data", "features"}}},
                {"encode", {{"enter", {{"x", x}, {"y", at("y", field)}, {"shape", val(shape)}, {"size", val(45)},
                                       {"fill", val(colour)}}}}}};
  };
  spec["marks"] = json::array(
      {{{"type", "rule"},
        {"encode", {{"enter", {{"x", val(0)}, {"x2", {{"signal", "width"}}}, {"y", {{"scale", "y"}, {"value", 0}}},
                               {"stroke", val("#999999")}, {"strokeWidth", val(1)}}}}}},
       ruleMark("before_error_bars", "before_U", dodged(-4), kBefore),
       ruleMark("after_error_bars", "after_U", dodged(0), kColours[0]),
       ruleMark("promised_error_bars", "features", dodged(4), kPromised),
       symbolMark(dodged(4), "expected", "diamond", kPromised), symbolMark(dodged(-4), "before", "square", kBefore),
       symbolMark(dodged(0), "after", "circle", kColours[0])});
  const json solid = json::array({1, 0});
  addLegend(spec, {{"before \u00b1 U", "square", kBefore, kBefore, solid},
                   {"after the compensation \u00b1 U", "circle", kColours[0], kColours[0], solid},
                   {"promised (before \u2212 promised fall) \u00b1 U", "diamond", kPromised, kPromised, solid}});
  spec["legends"][0]["labelLimit"] = 360;
  return spec;
}

// ---------------------------------------------------------------------------------------
// The U of a width or depth error in each route (the evaluation gives the CMM's u per step
// and e_pos's budget; evaluate/stepped_workpiece.cpp builds e_pos = CMM − probe from
// uncorrelated lines, so the probe's share is what remains of u_c² after the CMM's).

const char* kQuantities[] = {"width_x", "width_y", "depth"};
const char* kCmmU[] = {"u_cmm_width_x_um", "u_cmm_width_y_um", "u_cmm_depth_um"};
const char* kEPos[] = {"e_pos_x_um", "e_pos_y_um", "e_pos_z_um"};

const json* stepSeparation(const json& eval, int step) {
  for (const auto& s : array(eval, "separation"))
    if (number(s, "step") == static_cast<double>(step)) return &s;
  return nullptr;
}

std::optional<double> errorU(const json& eval, int step, int q, bool cmm) {
  const json* s = stepSeparation(eval, step);
  if (s == nullptr) return std::nullopt;
  const auto u_cmm = number(*s, kCmmU[q]);
  if (!u_cmm) return std::nullopt;
  if (cmm) return 2.0 * *u_cmm;
  const auto u_c = number(object(*s, kEPos[q]), "u_c");
  if (!u_c || *u_c < *u_cmm) return std::nullopt;
  return 2.0 * std::sqrt(*u_c * *u_c - *u_cmm * *u_cmm);
}

std::string vu(const json& s, const char* key) { return valueU(budgetValue(s, key), budgetU(s, key)); }
std::string stepText(const json& st) { return whole(number(st, "step")); }

// ---------------------------------------------------------------------------------------
// Tables.

std::string componentsTable(const std::vector<Part>& parts) {
  const bool several = parts.size() > 1;
  std::string t = "<table class=\"components\">\n<thead><tr>" + std::string(several ? th("part") : "") + th("step") +
                  th("feed (mm/min)", true) + th("T (min)", true) + th("e_pos_x \u00b1 U (\u00b5m)", true) +
                  th("e_pos_y \u00b1 U (\u00b5m)", true) + th("e_pos_z \u00b1 U (\u00b5m)", true) +
                  th("e_proc_x \u00b1 U (\u00b5m)", true) + th("e_proc_y \u00b1 U (\u00b5m)", true) +
                  th("e_splz \u00b1 U (\u00b5m)", true) + "</tr></thead>\n<tbody>\n";
  for (const auto& p : parts)
    for (const auto& st : array(*p.eval, "separation")) {
      t += "<tr>" + std::string(several ? td(p.label) : "") + td(stepText(st)) + td(sig(number(st, "feed_mm_per_min"), 4), true) +
           td(number(st, "temp_state_min") ? fixed(*number(st, "temp_state_min"), 1) : kDash, true);
      for (const char* key : {"e_pos_x_um", "e_pos_y_um", "e_pos_z_um", "e_proc_x_um", "e_proc_y_um", "e_splz_um"})
        t += tdValueU(budgetValue(st, key), budgetU(st, key));
      t += "</tr>\n";
    }
  return t + "</tbody>\n</table>\n";
}

std::string geometryTable(const std::vector<Part>& parts) {
  const bool several = parts.size() > 1;
  std::string t = "<table class=\"geometry\">\n<thead><tr>" + std::string(several ? th("part") : "") + th("route") + th("step") +
                  th("width X error \u00b1 U (\u00b5m)", true) + th("width Y error \u00b1 U (\u00b5m)", true) +
                  th("depth error \u00b1 U (\u00b5m)", true) + "</tr></thead>\n<tbody>\n";
  for (const auto& p : parts)
    for (const char* route : {"cmm", "on_machine"})
      for (const auto& st : array(object(*p.eval, route), "steps")) {
        const int step = static_cast<int>(number(st, "step").value_or(0));
        t += "<tr>" + std::string(several ? td(p.label) : "") + td(std::string(route) == "cmm" ? "CMM" : "on the machine") +
             td(stepText(st));
        for (int q = 0; q < 3; ++q)
          t += tdValueU(number(st, (std::string(kQuantities[q]) + "_error_um").c_str()),
                        errorU(*p.eval, step, q, std::string(route) == "cmm"));
        t += "</tr>\n";
      }
  return t + "</tbody>\n</table>\n";
}

std::string orientationTable(const std::vector<Part>& parts) {
  const bool several = parts.size() > 1;
  const char* keys[] = {"wall_tilt_x", "wall_tilt_y", "floor_slope_x", "floor_slope_y", "oz"};
  std::string t = "<table class=\"orientations\">\n<thead><tr>" + std::string(several ? th("part") : "") + th("route") +
                  th("step") + th("wall tilt X \u00b1 U (\u00b5rad)", true) + th("wall tilt Y \u00b1 U (\u00b5rad)", true) +
                  th("floor slope X \u00b1 U (\u00b5rad)", true) + th("floor slope Y \u00b1 U (\u00b5rad)", true) +
                  th("Oz, squareness X\u2013Y \u00b1 U (\u00b5rad)", true) + "</tr></thead>\n<tbody>\n";
  for (const auto& p : parts)
    for (const char* route : {"cmm", "on_machine"})
      for (const auto& st : array(object(*p.eval, route), "steps")) {
        t += "<tr>" + std::string(several ? td(p.label) : "") + td(std::string(route) == "cmm" ? "CMM" : "on the machine") +
             td(stepText(st));
        for (const char* k : keys)
          t += tdValueU(number(st, (std::string(k) + "_urad").c_str()), number(st, ("U_" + std::string(k) + "_urad").c_str()),
                        "not resolved");
        t += "</tr>\n";
      }
  return t + "</tbody>\n</table>\n";
}

// Before/after rows: the compensated part's before_after, the before's U from the plain part
// (when given), the after's from the compensated part itself.
json beforeAfterRows(const json& compensated, const json* plain) {
  json rows = json::array();
  for (const auto& x : array(compensated, "before_after")) {
    const auto b = number(x, "before_um"), a = number(x, "after_um"), p = number(x, "promised_um");
    if (!b || !a || !p) continue;
    const std::string q = text(x, "quantity");
    const int step = static_cast<int>(number(x, "step").value_or(0));
    const int qi = q == "width_x" ? 0 : q == "width_y" ? 1 : q == "depth" ? 2 : -1;
    const auto U_after = qi >= 0 ? errorU(compensated, step, qi, true) : std::nullopt;
    const auto U_before = qi >= 0 && plain != nullptr ? errorU(*plain, step, qi, true) : std::nullopt;
    rows.push_back({{"feature", "S" + whole(number(x, "step")) + " " + q}, {"before", *b}, {"after", *a}, {"promised", *p},
                    {"U", number(x, "U_promised_um").value_or(0.0)}, {"U_before", U_before ? json(*U_before) : json(nullptr)},
                    {"U_after", U_after ? json(*U_after) : json(nullptr)}});
  }
  return rows;
}

std::optional<double> optionalNumber(const json& o, const char* key) { return number(o, key); }

std::string beforeAfterTable(const json& rows) {
  std::string t = "<table class=\"before-after\">\n<thead><tr>" + th("feature") + th("before \u00b1 U (\u00b5m)", true) +
                  th("after \u00b1 U (\u00b5m)", true) + th("fall \u00b1 U (\u00b5m)", true) +
                  th("promised fall \u00b1 U (\u00b5m)", true) + "</tr></thead>\n<tbody>\n";
  for (const auto& r : rows) {
    const double b = r["before"].get<double>(), a = r["after"].get<double>();
    const auto Ub = optionalNumber(r, "U_before"), Ua = optionalNumber(r, "U_after");
    const std::optional<double> Uf = Ub && Ua ? std::optional<double>(std::hypot(*Ub, *Ua)) : std::nullopt;
    t += "<tr>" + td(r["feature"].get<std::string>()) + tdValueU(b, Ub) + tdValueU(a, Ua) + tdValueU(b - a, Uf) +
         tdValueU(r["promised"].get<double>(), r["U"].get<double>()) + "</tr>\n";
  }
  return t + "</tbody>\n</table>\n";
}

std::string budgetTable(const Part& p) {
  const auto& seps = array(*p.eval, "separation");
  if (seps.empty()) return "";
  std::string t = "<table class=\"budgets\">\n<thead><tr>" + th("component") + th("value \u00b1 U (\u00b5m)", true) +
                  th("largest contribution") + th("its u (\u00b5m)", true) + th("basis") + "</tr></thead>\n<tbody>\n";
  const auto& last = seps.back();
  for (const char* key : {"e_pos_x_um", "e_pos_y_um", "e_pos_z_um", "e_proc_x_um", "e_proc_y_um", "e_splz_um"}) {
    const auto& b = object(last, key);
    const json* c0 = nullptr;
    for (const auto& c : array(b, "contributions"))
      if (number(c, "u") && (c0 == nullptr || std::abs(*number(c, "u")) > std::abs(*number(*c0, "u")))) c0 = &c;
    static const json kNone = json::object();
    const json& c = c0 ? *c0 : kNone;
    t += "<tr>" + td(key) + tdValueU(budgetValue(last, key), budgetU(last, key)) + td(text(c, "input").empty() ? kDash : text(c, "input")) +
         td(sig(number(c, "u"), 3), true) + td(text(c, "basis").empty() ? kDash : text(c, "basis")) + "</tr>\n";
  }
  return t + "</tbody>\n</table>\n";
}

void checkEvaluation(const json& eval, const std::string& file) {
  if (!eval.is_object() || text(eval, "kind") != "stepped_workpiece" || !eval.contains("separation") ||
      !eval.at("separation").is_array() || !eval.contains("cmm"))
    throw InputError(file, 0, "expected the evaluation.json of a stepped workpiece (kind \"stepped_workpiece\" with "
                              "\"separation\" and \"cmm\"), from probeloop evaluate … --probe-log");
}

// The compensated part's before values must be the plain part's CMM errors: otherwise it was
// compared with another part, and the page would put two different "befores" side by side.
void checkPair(const json& plain, const std::string& plain_file, const json& compensated, const std::string& file) {
  const json& before_after = array(compensated, "before_after");
  if (before_after.empty())
    throw InputError(file, 0, "the compensated part's evaluation has no before/after: evaluate it with --compare " +
                                  (plain_file.empty() ? std::string("<the plain part's evaluation.json>") : plain_file));
  for (const auto& x : before_after) {
    const std::string key = text(x, "quantity") + "_error_um";
    const auto before = number(x, "before_um");
    bool found = false;
    for (const auto& st : array(object(plain, "cmm"), "steps"))
      if (number(st, "step") == number(x, "step") && number(st, key.c_str()) && before &&
          std::abs(*number(st, key.c_str()) - *before) <= 1e-6)
        found = true;
    if (!found)
      throw InputError(file, 0, "its before/after (compared with " + text(compensated, "compared_with") + ") does not hold " +
                                    (plain_file.empty() ? std::string("the plain part") : plain_file) +
                                    "'s CMM errors (step " + whole(number(x, "step")) + " " + text(x, "quantity") +
                                    "): give the part it was compared with");
  }
}

}  // namespace

std::string steppedWorkpieceReportHtml(const json& eval, const std::string& file, const std::string& vega_js_path,
                                       const json* compensated, const std::string& compensated_file) {
  checkEvaluation(eval, file);
  if (compensated != nullptr) {
    checkEvaluation(*compensated, compensated_file);
    checkPair(eval, file, *compensated, compensated_file);
  }
  const std::string vega = vegaRuntime(vega_js_path);
  std::vector<Part> parts;
  if (compensated != nullptr) {
    parts.push_back({&eval, file, "uncompensated", false});
    parts.push_back({compensated, compensated_file, "compensated", true});
  } else {
    parts.push_back({&eval, file, "", false});
  }
  const json* ba_source = compensated != nullptr ? compensated : eval.contains("before_after") ? &eval : nullptr;
  const json ba_rows = ba_source ? beforeAfterRows(*ba_source, compensated != nullptr ? &eval : nullptr) : json::array();

  const std::string experiment = text(eval, "experiment");
  const std::string title = "Stepped workpiece " + experiment + ": separated errors" +
                            (compensated != nullptr ? " of the part cut plain and of the part cut compensated"
                             : ba_source       ? " and the compensation"
                                               : "");
  std::string files;
  for (const auto& p : parts) files += (files.empty() ? "" : "; ") + partPrefix(p) + p.file;
  Page page;
  page.html += "<header>\n<h1>" + esc(title) + "</h1>\n<p class=\"note\">" + esc(std::string(kThesis)) +
               ", Ch. 5 and 6, from one workpiece: its CMM export and its on-machine probe log evaluated together (" +
               esc(files) + "); definitions and choices in probeloop's docs/stepped-workpiece.md \u00a76\u20137. U with "
               "k = 2 (95 %).</p>\n";
  if (compensated != nullptr)
    page.html += "<p class=\"note\">Two parts of the same experiment side by side: the part cut plain (uncompensated, "
                 "filled symbols, first in every table: the numbers probeloop evaluate printed for it) and the part "
                 "cut again with its predicted errors taken out of the finishing path (compensated, open symbols; its "
                 "e_proc and e_splz are against what was commanded).</p>\n";
  page.html += "</header>\n<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" + std::string(kErrorHook) +
               "</script>\n";

  // Plot 1: e_pos against the probe's travel, with the fitted lines.
  page.html += "<section class=\"plots\">\n<h2>Separated components</h2>\n";
  std::vector<Series> lines;
  for (const auto& p : parts)
    for (int a = 0; a < 2; ++a) {
      const char* axis = a == 0 ? "x" : "y";
      const std::string kkey = std::string("k_pos_") + axis + "_um_per_mm";
      const auto k = number(object(*p.eval, kkey.c_str()), "value");
      if (!k) continue;
      Series l{std::string("line_") + axis + (p.open ? "_compensated" : ""),
               partPrefix(p) + "k_" + axis + " L = " + fixed(*k, 4) + " \u00b5m/mm \u00d7 L", json::array(), a, p.open};
      double L_max = 0;
      for (const auto& st : array(*p.eval, "separation")) L_max = std::max(L_max, number(st, "travel_probe_mm").value_or(0.0));
      l.rows = json::array({{{"x", 0.0}, {"value", 0.0}}, {{"x", L_max}, {"value", *k * L_max}}});
      lines.push_back(l);
    }
  const auto seriesOf = [&parts](const char* key_x, const char* key_y, const char* x_key, const char* label_x,
                                 const char* label_y) {
    std::vector<Series> s;
    for (const auto& p : parts) {
      s.push_back(componentSeries(p, key_x, x_key, label_x, 0));
      if (key_y != nullptr) s.push_back(componentSeries(p, key_y, x_key, label_y, 1));
    }
    return s;
  };
  page.html += "<h3>e_pos: CMM \u2212 probe against the probe's travel</h3>\n";
  page.plot(pointsSpec("e_pos_x and e_pos_y against the probe's travel", "probe centre's travel between the walls (mm)",
                       "e_pos (\u00b5m)", seriesOf("e_pos_x_um", "e_pos_y_um", "travel_probe_mm", "e_pos_x", "e_pos_y"), lines,
                       true),
            "Position error per step (" + std::string(kThesis) + ", Ch. 3: CMM width \u2212 probed width, the machine's "
            "own position error, which the machine cannot see when it probes), error bars \u00b1U; dashed: the weighted "
            "line through 0 (k per axis).");
  page.html += "<h3>e_proc: process error (two walls) against the feed</h3>\n";
  page.plot(pointsSpec("e_proc_x and e_proc_y against the feed", "feed (mm/min)", "e_proc, two walls (\u00b5m)",
                       seriesOf("e_proc_x_um", "e_proc_y_um", "feed_mm_per_min", "e_proc_x", "e_proc_y"), {}, true),
            "Process error per step (" + std::string(kThesis) + ", Ch. 5: probe width error \u2212 e_pos over the tool's "
            "travel beyond the probe's; the X/Y thermal error of one part taken as 0), the sum of both walls (half per "
            "wall), error bars \u00b1U.");
  page.html += "<h3>e_splz: spindle growth against the Temp state</h3>\n";
  page.plot(pointsSpec("e_splz against the Temp state", "Temp state T (min from the start of step 1)", "e_splz (\u00b5m)",
                       seriesOf("e_splz_um", nullptr, "temp_state_min", "e_splz", ""), {}, true),
            "The floors' depth error from the probe, + when the floor lies shallower (the tool tip rose since the top "
            "was cut), error bars \u00b1U.");
  if (!ba_rows.empty()) {
    page.html += "<h3>Before and after the compensation</h3>\n";
    page.plot(beforeAfterSpec(ba_rows),
              "CMM error of every width and depth before (" + text(*ba_source, "compared_with") +
                  ") and after the compensation, each \u00b1 U (2 u of the CMM's measurement of that width or depth" +
                  (compensated != nullptr ? "" : "; the before's U needs the plain part's evaluation: --evaluation "
                                                 "<plain> --compensated <compensated>") +
                  "); green: the error the compensation promised (before \u2212 the promised fall) \u00b1 its U.");
  }
  page.html += "</section>\n";

  // Tables.
  page.html += "<section class=\"values\">\n<h2>Components per step</h2>\n" + std::string(kNotSignificantNote) + "\n" +
               tableWrap(componentsTable(parts));
  for (const auto& p : parts)
    page.html += "<p>" + esc(partPrefix(p)) + "position error per mm of travel: k_x = " + esc(vu(*p.eval, "k_pos_x_um_per_mm")) +
                 ", k_y = " + esc(vu(*p.eval, "k_pos_y_um_per_mm")) + ", k_z = " + esc(vu(*p.eval, "k_pos_z_um_per_mm")) +
                 " \u00b5m/mm. Probe repeatability (one point, 1\u03c3): " +
                 withUnit(sig(number(*p.eval, "probe_repeatability_um"), 3), "\u00b5m") + " from " +
                 whole(number(*p.eval, "probe_repeat_pairs")) + " repeated points.</p>\n";

  page.html += "<h2>Widths and depths per route</h2>\n<p class=\"note\">The width and depth errors as each route "
               "measured them. U of the CMM's: 2 u of its measurement (its MPE at the length, its planes' residuals, "
               "the part's temperature at the CMM). U on the machine: the probe's own (its repeatability over the "
               "points of both planes, the part's temperature on the machine), not the machine's position error, "
               "which the probe cannot see and which e_pos = CMM \u2212 probe is.</p>\n" +
               tableWrap(geometryTable(parts));
  page.html += "<h2>Orientations per route</h2>\n<p class=\"note\">Wall tilt: the mean slope dx/dz (dy/dz) of a step's "
               "two X (Y) walls. Floor slope: the floor's dz/dx and dz/dy (the table's tilt). <b>Oz</b>: the squareness "
               "of the step in the XY plane: the angle between the X walls' normal and the Y walls' normal minus "
               "90\u00b0, + when it is larger than 90\u00b0 (an out-of-square X and Y axis shows here; " +
               esc(std::string(kThesis)) + ", Table 5.4, gives it in degrees, 90.01\u00b0). "
               "<span class=\"ns\">Grey, marked <span class=\"ns-mark\">not resolved</span></span>: |value| \u2264 U, "
               "the part cannot tell the angle from zero. The walls' tilt rests on 6 points on two levels a few mm "
               "apart, so its U is hundreds of \u00b5rad and a tilt is seldom resolved; the floors and Oz span the "
               "whole step and usually are.</p>\n" +
               tableWrap(orientationTable(parts));

  if (!ba_rows.empty())
    page.html += "<h2>Before and after the compensation (CMM)</h2>\n<p class=\"note\">U of before and after: 2 u of the "
                 "CMM's measurement of each part; of the fall: both combined; of the promised fall: the prediction's.</p>\n" +
                 tableWrap(beforeAfterTable(ba_rows));

  page.html += "<h2>Uncertainty budgets (last step)</h2>\n";
  for (const auto& p : parts) {
    if (parts.size() > 1) page.html += "<h3>" + esc(p.label) + "</h3>\n";
    page.html += tableWrap(budgetTable(p));
  }
  page.html += "<h2>Notes</h2>\n";
  for (const auto& p : parts) {
    if (parts.size() > 1) page.html += "<h3>" + esc(p.label) + "</h3>\n";
    page.html += "<ul>\n";
    for (const auto& n : array(*p.eval, "notes")) page.html += "<li>" + esc(n.is_string() ? n.get<std::string>() : n.dump()) + "</li>\n";
    page.html += "</ul>\n";
  }
  page.html += "</section>\n";
  for (const auto& p : parts) page.html += inputWarningsSection(*p.eval);

  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                    "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
                    "content=\"probeloop\">\n<title>" + esc(title) + "</title>\n<style>" + kStyle + kMarkStyle +
                    "</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report
