#include "report/ttp_report.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "report/ttp_report_parts.hpp"

namespace probeloop::report {

using nlohmann::json;
using namespace web;
using namespace ttp_detail;

namespace {

// Every table of the page's sections but the inputs (class "meta") in a scroll container, so
// that a wide one (six quantities ± U, two routes) scrolls instead of running past the page.
std::string wrapTables(const std::string& html) {
  const std::string open = "<div class=\"table-wrap\">\n";
  std::string out;
  std::size_t pos = 0;
  for (std::size_t t = html.find("<table", pos); t != std::string::npos; t = html.find("<table", pos)) {
    const std::size_t end = html.find("</table>\n", t);
    const bool wrapped = t >= open.size() && html.compare(t - open.size(), open.size(), open) == 0;
    if (end == std::string::npos || wrapped || html.compare(t, 19, "<table class=\"meta\"") == 0) {
      out += html.substr(pos, t + 6 - pos);
      pos = t + 6;
      continue;
    }
    out += html.substr(pos, t - pos) + open + html.substr(t, end + 9 - t) + "</div>\n";
    pos = end + 9;
  }
  return out + html.substr(pos);
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
  std::optional<MachineInputs> inputs;
  if (options.inputs_csv_text) inputs = readMachineInputs(*options.inputs_csv_text, options.inputs_file);
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
  WarmUp warm_up;
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
  // The errors' first and last time: the machine's inputs are drawn over the same hours.
  TimeRange range_s;
  for (const auto& e : plots)
    for (const auto& s : e.series)
      for (const auto& row : s.rows)
        if (const auto t = number(row, "time_s"))
          range_s = range_s ? std::make_pair(std::min(range_s->first, *t), std::max(range_s->second, *t))
                            : std::make_pair(*t, *t);
  if (range_s && !(range_s->second > range_s->first)) range_s.reset();

  std::string title = "Thermal test piece: ";
  for (std::size_t i = 0; i < routes.size(); ++i) title += (i ? " and " : "") + routes[i].label;
  if (r_test) title += ", with the R-test";

  Page page;
  page.html += "<header>\n<h1>" + esc(title) + "</h1>\n<p class=\"note\">" + std::string(kThesis) +
               ", Ch. 7 (the journal version: Wiessner et al., Precision Engineering 52 (2018) 407\u2013417); the test "
               "piece's features, frames and signs: probeloop's docs/thermal-test-piece.md. Every error is the change "
               "of the cycle's surfaces against the reference cut; time runs from the reference cut, in hours and "
               "minutes (h:mm). U is expanded with the coverage factor k of each budget (k \u2248 2, 95 %).</p>\n";
  inputsTable(page, routes, r_test ? &*r_test : nullptr, inputs ? &*inputs : nullptr, t0_s, channels);
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

  // ISO 230-3 shows the load and the temperatures beside the displacements: from the machine's log.
  if (inputs) {
    page.html += "<section class=\"machine-inputs\">\n<h2>Load and temperatures</h2>\n";
    if (!inputs->temperatures.empty()) {
      page.html += "<h3>Temperatures</h3>\n";
      page.plot(temperatureSpec(*inputs, t0_s, warm_up, range_s),
                "Temperatures logged by the machine (" + (inputs->file.empty() ? std::string("inputs") : inputs->file) + "; one line per sensor column, \u00b0C as "
                "logged), against the same hours since the reference cut as the errors." +
                    (warm_up ? " Shaded: the warm-up hours." : ""));
    }
    if (inputs->c_rpm) {
      page.html += "<h3>C-axis load</h3>\n";
      page.plot(cLoadSpec(*inputs, t0_s, warm_up, range_s),
                "The C axis's speed as logged (c_rpm, rpm; a step line between samples): the thermal load of the "
                "test (the warm-up turns C, the hold stops it); same hours as the errors." +
                    std::string(warm_up ? " Shaded: the warm-up hours." : ""));
    }
    page.html += "</section>\n";
  }

  page.html += "<section class=\"values\">\n<h2>Values per cycle</h2>\n" + std::string(kNotSignificantNote) + "\n";
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
  const bool printed = hasPrintedForms(routes);
  if (printed) printedFormsNote(page, routes);
  page.html += "</section>\n";
  page.html += inputWarningsSection(evaluation);
  if (second_route != nullptr) page.html += inputWarningsSection(*second_route);
  if (printed) printedFormsAppendix(page, routes, t0_s);

  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
      "content=\"probeloop\">\n<title>" +
      esc(title) + "</title>\n<style>" + kStyle +
      kMarkStyle + "th.group { text-align: center; }\n</style>\n</head>\n<body>\n";
  out += wrapTables(page.html);
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report