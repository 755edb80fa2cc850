#include "report/sw_report.hpp"

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

json at(const char* scale, const char* f) { return {{"scale", scale}, {"field", f}}; }
json val(const json& v) { return {{"value", v}}; }

struct Series {
  std::string name, label;
  json rows = json::array();  // {x, value, U}
};

// A budget's value and U from the evaluation's JSON (budget_json.hpp).
std::optional<double> budgetValue(const json& s, const char* key) { return number(object(s, key), "value"); }
std::optional<double> budgetU(const json& s, const char* key) { return number(object(s, key), "U"); }

Series componentSeries(const json& eval, const char* key, const char* x_key, const std::string& label) {
  Series s{key, label};
  for (const auto& st : array(eval, "separation")) {
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
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const char* colour = kColours[i % 2];
    spec["marks"].push_back({{"type", "line"}, {"from", {{"data", lines[i].name}}},
                             {"encode", {{"enter", {{"x", at("x", "x")}, {"y", at("y", "value")}, {"stroke", val(colour)},
                                                    {"strokeWidth", val(1)}, {"strokeDash", val(dashed)}}}}}});
    legend.push_back({lines[i].label, "stroke", "transparent", colour, dashed});
  }
  for (std::size_t i = 0; i < series.size(); ++i) {
    const char* colour = kColours[i % 2];
    json x = at("x", "x");
    if (series.size() == 2) x["offset"] = i == 0 ? -3 : 3;  // display only: neither hides the other's bars
    spec["marks"].push_back({{"type", "rule"}, {"name", series[i].name + "_error_bars"}, {"from", {{"data", series[i].name}}},
                             {"encode", {{"enter", {{"x", x}, {"y", at("y", "lo")}, {"y2", at("y", "hi")},
                                                    {"stroke", val(colour)}, {"strokeWidth", val(1.5)}}}}}});
    spec["marks"].push_back({{"type", "symbol"}, {"from", {{"data", series[i].name}}},
                             {"encode", {{"enter", {{"x", x}, {"y", at("y", "value")}, {"shape", val(kShapes[i % 2])},
                                                    {"size", val(45)}, {"fill", val(colour)}}}}}});
    legend.push_back({series[i].label + " \u00b1 U", kShapes[i % 2], colour, colour, solid});
  }
  addLegend(spec, legend);
  spec["legends"][0]["labelLimit"] = 360;
  return spec;
}

// Per feature (ordinal): before, after, and the promised after (before - promised fall) +- U.
json beforeAfterSpec(const json& rows) {
  json spec = baseSpec("CMM error per feature before and after the compensation, with the promised error \u00b1 U", 260);
  spec["data"] = json::array(
      {{{"name", "features"}, {"values", rows},
        {"transform", json::array({formulaTx("expected", "datum.before - datum.promised"),
                                   formulaTx("lo", "datum.before - datum.promised - datum.U"),
                                   formulaTx("hi", "datum.before - datum.promised + datum.U")})}}});
  spec["usermeta"] = {{"series", json::array({{{"data", "features"}, {"label", "before, after, promised"}}})}};
  spec["scales"] = json::array(
      {{{"name", "x"}, {"type", "point"}, {"range", "width"}, {"padding", 0.5}, {"domain", {{"data", "features"}, {"field", "feature"}}}},
       {{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true},
        {"domain", {{"fields", json::array({{{"data", "features"}, {"field", "before"}}, {{"data", "features"}, {"field", "after"}},
                                            {{"data", "features"}, {"field", "lo"}}, {{"data", "features"}, {"field", "hi"}}})}}}}});
  spec["axes"] = json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", "feature (step, quantity)"}, {"labelAngle", -40},
                               {"labelAlign", "right"}},
                              {{"orient", "left"}, {"scale", "y"}, {"title", "CMM error (\u00b5m)"}, {"grid", true}, {"minExtent", 40}}});
  json promised_x = at("x", "feature");
  promised_x["offset"] = 4;
  spec["marks"] = json::array(
      {{{"type", "rule"},
        {"encode", {{"enter", {{"x", val(0)}, {"x2", {{"signal", "width"}}}, {"y", {{"scale", "y"}, {"value", 0}}},
                               {"stroke", val("#999999")}, {"strokeWidth", val(1)}}}}}},
       {{"type", "rule"}, {"name", "promised_error_bars"}, {"from", {{"data", "features"}}},
        {"encode", {{"enter", {{"x", promised_x}, {"y", at("y", "lo")}, {"y2", at("y", "hi")}, {"stroke", val(kPromised)},
                               {"strokeWidth", val(1.5)}}}}}},
       {{"type", "symbol"}, {"from", {{"data", "features"}}},
        {"encode", {{"enter", {{"x", promised_x}, {"y", at("y", "expected")}, {"shape", val("diamond")}, {"size", val(40)},
                               {"fill", val(kPromised)}}}}}},
       {{"type", "symbol"}, {"from", {{"data", "features"}}},
        {"encode", {{"enter", {{"x", at("x", "feature")}, {"y", at("y", "before")}, {"shape", val("square")}, {"size", val(45)},
                               {"fill", val(kBefore)}}}}}},
       {{"type", "symbol"}, {"from", {{"data", "features"}}},
        {"encode", {{"enter", {{"x", at("x", "feature")}, {"y", at("y", "after")}, {"shape", val("circle")}, {"size", val(45)},
                               {"fill", val(kColours[0])}}}}}}});
  const json solid = json::array({1, 0});
  addLegend(spec, {{"before", "square", kBefore, kBefore, solid},
                   {"after the compensation", "circle", kColours[0], kColours[0], solid},
                   {"promised (before \u2212 promised fall) \u00b1 U", "diamond", kPromised, kPromised, solid}});
  spec["legends"][0]["labelLimit"] = 360;
  return spec;
}

std::string vu(const json& s, const char* key) { return valueU(budgetValue(s, key), budgetU(s, key)); }

}  // namespace

std::string steppedWorkpieceReportHtml(const json& eval, const std::string& file, const std::string& vega_js_path) {
  if (!eval.is_object() || text(eval, "kind") != "stepped_workpiece" || !eval.contains("separation") ||
      !eval.at("separation").is_array() || !eval.contains("cmm"))
    throw InputError(file, 0, "expected the evaluation.json of a stepped workpiece (kind \"stepped_workpiece\" with "
                              "\"separation\" and \"cmm\"), from probeloop evaluate … --probe-log");
  const std::string vega = vegaRuntime(vega_js_path);
  const std::string experiment = text(eval, "experiment");
  const std::string title = "Stepped workpiece " + experiment + ": separated errors" +
                            (eval.contains("before_after") ? " and the compensation" : "");
  Page page;
  page.html += "<header>\n<h1>" + esc(title) + "</h1>\n<p class=\"note\">Seed 000 (Yaqoob 2017) Ch. 5 and 6 from one "
               "workpiece, its CMM export and its on-machine probe log evaluated together (" + esc(file) +
               "); definitions and choices in docs/stepped-workpiece.md §6–7. U with k = 2.</p>\n</header>\n"
               "<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" + std::string(kErrorHook) + "</script>\n";

  // Plot 1: e_pos against the probe's travel, with the fitted lines.
  page.html += "<section class=\"plots\">\n<h2>Separated components</h2>\n";
  std::vector<Series> lines;
  for (const char* axis : {"x", "y"}) {
    const std::string kkey = std::string("k_pos_") + axis + "_um_per_mm";
    const auto k = number(object(eval, kkey.c_str()), "value");
    if (!k) continue;
    Series l{std::string("line_") + axis, std::string("k_") + axis + " L = " + fixed(*k, 4) + " \u00b5m/mm \u00d7 L"};
    double L_max = 0;
    for (const auto& st : array(eval, "separation")) L_max = std::max(L_max, number(st, "travel_probe_mm").value_or(0.0));
    l.rows = json::array({{{"x", 0.0}, {"value", 0.0}}, {{"x", L_max}, {"value", *k * L_max}}});
    lines.push_back(l);
  }
  page.html += "<h3>e_pos: CMM \u2212 probe against the probe's travel</h3>\n";
  page.plot(pointsSpec("e_pos_x and e_pos_y against the probe's travel", "probe centre's travel between the walls (mm)",
                       "e_pos (\u00b5m)",
                       {componentSeries(eval, "e_pos_x_um", "travel_probe_mm", "e_pos_x"),
                        componentSeries(eval, "e_pos_y_um", "travel_probe_mm", "e_pos_y")},
                       lines, true),
            "Position error per step (seed 000 L761: CMM width \u2212 probed width), error bars \u00b1U; dashed: the "
            "weighted line through 0 (k per axis).");
  page.html += "<h3>e_proc: process error (two walls) against the feed</h3>\n";
  page.plot(pointsSpec("e_proc_x and e_proc_y against the feed", "feed (mm/min)", "e_proc, two walls (\u00b5m)",
                       {componentSeries(eval, "e_proc_x_um", "feed_mm_per_min", "e_proc_x"),
                        componentSeries(eval, "e_proc_y_um", "feed_mm_per_min", "e_proc_y")},
                       {}, true),
            "Process error per step (L1629: probe width error \u2212 e_pos over the tool's travel beyond the probe's; "
            "the X/Y thermal error of one part taken as 0), the sum of both walls (L1639: half per wall).");
  page.html += "<h3>e_splz: spindle growth against the Temp state</h3>\n";
  page.plot(pointsSpec("e_splz against the Temp state", "Temp state T (min from the start of step 1)", "e_splz (\u00b5m)",
                       {componentSeries(eval, "e_splz_um", "temp_state_min", "e_splz")}, {}, true),
            "The floors' depth error from the probe, + when the floor lies shallower (the tool tip rose since the top was cut).");
  json ba_rows = json::array();
  for (const auto& x : array(eval, "before_after")) {
    const auto b = number(x, "before_um"), a = number(x, "after_um"), p = number(x, "promised_um");
    if (!b || !a || !p) continue;
    ba_rows.push_back({{"feature", "S" + whole(number(x, "step")) + " " + text(x, "quantity")}, {"before", *b}, {"after", *a},
                       {"promised", *p}, {"U", number(x, "U_promised_um").value_or(0.0)}});
  }
  if (!ba_rows.empty()) {
    page.html += "<h3>Before and after the compensation</h3>\n";
    page.plot(beforeAfterSpec(ba_rows), "CMM error of every width and depth before (" + text(eval, "compared_with") +
                                            ") and after the compensation; green: the error the compensation promised "
                                            "(before \u2212 the promised fall) \u00b1 its U.");
  }
  page.html += "</section>\n";

  // Tables.
  page.html += "<section class=\"values\">\n<h2>Components per step</h2>\n<table>\n<tr>" + th("step") + th("feed (mm/min)", true) +
               th("T (min)", true) + th("e_pos_x (\u00b5m)", true) + th("e_pos_y (\u00b5m)", true) + th("e_pos_z (\u00b5m)", true) +
               th("e_proc_x (\u00b5m)", true) + th("e_proc_y (\u00b5m)", true) + th("e_splz (\u00b5m)", true) + "</tr>\n";
  for (const auto& st : array(eval, "separation"))
    page.html += "<tr>" + td(whole(number(st, "step"))) + td(sig(number(st, "feed_mm_per_min"), 4), true) +
                 td(fixed(number(st, "temp_state_min").value_or(0.0), 1), true) + td(vu(st, "e_pos_x_um"), true) +
                 td(vu(st, "e_pos_y_um"), true) + td(vu(st, "e_pos_z_um"), true) + td(vu(st, "e_proc_x_um"), true) +
                 td(vu(st, "e_proc_y_um"), true) + td(vu(st, "e_splz_um"), true) + "</tr>\n";
  page.html += "</table>\n";
  page.html += "<p>Position error per mm of travel: k_x = " + esc(vu(eval, "k_pos_x_um_per_mm")) + ", k_y = " +
               esc(vu(eval, "k_pos_y_um_per_mm")) + ", k_z = " + esc(vu(eval, "k_pos_z_um_per_mm")) +
               " \u00b5m/mm. Probe repeatability (one point, 1\u03c3): " + sig(number(eval, "probe_repeatability_um"), 3) +
               " \u00b5m from " + whole(number(eval, "probe_repeat_pairs")) + " repeated points.</p>\n";

  page.html += "<h2>Geometry per route</h2>\n<table>\n<tr>" + th("route") + th("step") + th("width X error (\u00b5m)", true) +
               th("width Y error (\u00b5m)", true) + th("depth error (\u00b5m)", true) + th("wall tilt X (\u00b5rad)", true) +
               th("wall tilt Y (\u00b5rad)", true) + th("floor slope X (\u00b5rad)", true) + th("floor slope Y (\u00b5rad)", true) +
               th("Oz (\u00b5rad)", true) + "</tr>\n";
  for (const char* route : {"cmm", "on_machine"})
    for (const auto& st : array(object(eval, route), "steps")) {
      auto f2 = [&](const char* k) { const auto v = number(st, k); return v ? fixed(*v, 2) : kDash; };
      auto f1 = [&](const char* k) {
        const auto v = number(st, k);
        const auto U = number(st, ("U_" + std::string(k)).c_str());
        return v ? fixed(*v, 1) + (U ? " \u00b1 " + fixed(*U, 1) : std::string()) : kDash;
      };
      page.html += "<tr>" + td(route) + td(whole(number(st, "step"))) + td(f2("width_x_error_um"), true) +
                   td(f2("width_y_error_um"), true) + td(f2("depth_error_um"), true) + td(f1("wall_tilt_x_urad"), true) +
                   td(f1("wall_tilt_y_urad"), true) + td(f1("floor_slope_x_urad"), true) + td(f1("floor_slope_y_urad"), true) +
                   td(f1("oz_urad"), true) + "</tr>\n";
    }
  page.html += "</table>\n";

  if (!ba_rows.empty()) {
    page.html += "<h2>Before and after the compensation (CMM)</h2>\n<table>\n<tr>" + th("feature") + th("before (\u00b5m)", true) +
                 th("after (\u00b5m)", true) + th("fall (\u00b5m)", true) + th("promised fall \u00b1 U (\u00b5m)", true) + "</tr>\n";
    for (const auto& r : ba_rows)
      page.html += "<tr>" + td(r["feature"].get<std::string>()) + td(fixed(r["before"], 2), true) + td(fixed(r["after"], 2), true) +
                   td(fixed(r["before"].get<double>() - r["after"].get<double>(), 2), true) +
                   td(fixed(r["promised"], 2) + " \u00b1 " + fixed(r["U"], 2), true) + "</tr>\n";
    page.html += "</table>\n";
  }

  // The largest budget line of each component in the last step.
  const auto& seps = array(eval, "separation");
  if (!seps.empty()) {
    page.html += "<h2>Uncertainty budgets (last step)</h2>\n<table>\n<tr>" + th("component") + th("U (\u00b5m)", true) +
                 th("largest contribution") + th("its u (\u00b5m)", true) + th("basis") + "</tr>\n";
    const auto& last = seps.back();
    for (const char* key : {"e_pos_x_um", "e_pos_y_um", "e_pos_z_um", "e_proc_x_um", "e_proc_y_um", "e_splz_um"}) {
      const auto& b = object(last, key);
      const auto& cs = array(b, "contributions");
      static const json kNone = json::object();
      const json& c0 = cs.empty() ? kNone : cs.front();
      page.html += "<tr>" + td(key) + td(sig(number(b, "U"), 3), true) + td(text(c0, "input")) + td(sig(number(c0, "u"), 3), true) +
                   td(text(c0, "basis")) + "</tr>\n";
    }
    page.html += "</table>\n";
  }
  page.html += "<h2>Notes</h2>\n<ul>\n";
  for (const auto& n : array(eval, "notes")) page.html += "<li>" + esc(n.is_string() ? n.get<std::string>() : n.dump()) + "</li>\n";
  page.html += "</ul>\n</section>\n";

  std::string out = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                    "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
                    "content=\"probeloop\">\n<title>" + esc(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report
