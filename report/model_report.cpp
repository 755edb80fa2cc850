#include "report/model_report.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "model/verdict_strength.hpp"
#include "report/vega.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
// The pieces every report shares (escaping, numbers, the Vega runtime, the page): report/vega.hpp.
using namespace web;

std::string beforeAfter(const std::string& before, const std::string& after) {
  return "<span class=\"before\">" + esc(before) + "</span> \u2192 " + esc(after);
}

// ---------------------------------------------------------------------------------------
// Channels.

struct ChannelName {
  std::string id;      // as in the input, "EY0C_um"
  std::string unit;    // display unit, "µm" (empty when unknown)
  std::string label;   // "EY0C"
};

ChannelName channelName(const json& c) {
  ChannelName n;
  n.id = text(c, "channel");
  const std::string raw_unit = text(c, "unit");
  n.unit = displayUnit(raw_unit);
  n.label = n.id;
  const std::string suffix = "_" + raw_unit;
  if (!raw_unit.empty() && n.id.size() > suffix.size() &&
      n.id.compare(n.id.size() - suffix.size(), suffix.size(), suffix) == 0)
    n.label = n.id.substr(0, n.id.size() - suffix.size());
  if (n.label.empty()) n.label = "(unnamed channel)";
  return n;
}

std::string axisTitle(const ChannelName& n, const std::string& prefix) {
  return prefix + n.label + (n.unit.empty() ? "" : " (" + n.unit + ")");
}

// ---------------------------------------------------------------------------------------
// Vega specs (declarative JSON; Vega draws them). Data values are the input's numbers;
// hours, residual and band limits are Vega formulas.

// The model is drawn last, over the points, in a colour no point has (orange against
// near-black) and wider, so hundreds of points cannot hide it.
const char* kMeasuredColour = "#222222";
const char* kErrorBarColour = "#555555";
const char* kModelColour = "#e66100";
const char* kBandColour = "#fbe0c8";
const char* kBeforeColour = "#8a8a8a";
const char* kBeyondColour = "#c0392b";

struct SeriesData {
  json rows = json::array();
  bool has_measured = false, has_predicted = false, has_U = false, has_before = false;
  std::size_t measured = 0;  // rows with a measured value
};

// Above this many points, smaller and translucent points (and fainter error bars) keep the
// model line and the density of the points readable.
constexpr std::size_t kManyPoints = 150;

json finiteOrNull(const json& a, std::size_t i) {
  if (i < a.size() && number(&a[i])) return a[i];
  return nullptr;
}

SeriesData seriesData(const json& series) {
  SeriesData d;
  const json& t = array(series, "time_s");
  const json& m = array(series, "measured");
  const json& p = array(series, "predicted");
  const json& b = array(series, "predicted_before");
  const json& U = array(series, "U");
  const std::optional<double> U_scalar = number(series, "U");  // tolerated: one U for all rows
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!number(&t[i])) continue;
    json row = json::object();
    row["time_s"] = t[i];
    row["measured"] = finiteOrNull(m, i);
    row["predicted"] = finiteOrNull(p, i);
    row["U"] = U_scalar ? json(*U_scalar) : finiteOrNull(U, i);
    d.has_measured |= !row["measured"].is_null();
    d.measured += row["measured"].is_null() ? 0 : 1;
    d.has_predicted |= !row["predicted"].is_null();
    d.has_U |= !row["U"].is_null();
    if (!b.empty()) {
      row["before"] = finiteOrNull(b, i);
      d.has_before |= !row["before"].is_null();
    }
    d.rows.push_back(std::move(row));
  }
  return d;
}

struct Window {
  double from_s = 0, to_s = 0;
};

std::optional<Window> span(const json& fit, const char* key) {
  const json& s = object(fit, key);
  const auto from = number(s, "from_s"), to = number(s, "to_s");
  if (!from || !to || *to < *from) return std::nullopt;
  return Window{*from, *to};
}

json seriesDataset(const SeriesData& d) {
  return {{"name", "series"},
          {"values", d.rows},
          {"transform", json::array({filterTx("isValid(datum.time_s)"), formulaTx("t_h", "datum.time_s / 3600"),
                                     {{"type", "collect"}, {"sort", {{"field", "time_s"}}}}})}};
}

void addValidationWindow(json& spec, const std::optional<Window>& validation) {
  if (!validation) return;
  spec["data"].push_back({{"name", "validation"},
                          {"values", json::array({{{"from_s", validation->from_s}, {"to_s", validation->to_s}}})},
                          {"transform", json::array({formulaTx("from_h", "datum.from_s / 3600"),
                                                     formulaTx("to_h", "datum.to_s / 3600")})}});
  spec["marks"].push_back({{"type", "rect"},
                           {"name", "validation_window"},
                           {"from", {{"data", "validation"}}},
                           {"clip", true},
                           {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "from_h"}}},
                                                  {"x2", {{"scale", "x"}, {"field", "to_h"}}},
                                                  {"y", {{"value", 0}}},
                                                  {"y2", {{"signal", "height"}}},
                                                  {"fill", {{"value", "#000000"}}},
                                                  {"fillOpacity", {{"value", 0.04}}}}}}}});
}

// The window's label, added last so no mark covers it. Centred over the window and never
// clipped: a window at the right edge (or narrower than the word) cannot cut it, and the
// spec's autosize "pad" grows the view to whatever the label needs.
void addValidationLabel(json& spec, const std::optional<Window>& validation) {
  if (!validation) return;
  spec["marks"].push_back({{"type", "text"},
                           {"name", "validation_label"},
                           {"from", {{"data", "validation"}}},
                           {"clip", false},
                           {"encode", {{"enter", {{"x", {{"signal", "(scale('x', datum.from_h) + scale('x', datum.to_h)) / 2"}}},
                                                  {"y", {{"value", 3}}},
                                                  {"align", {{"value", "center"}}},
                                                  {"baseline", {{"value", "top"}}},
                                                  {"text", {{"value", "validation"}}},
                                                  {"fill", {{"value", "#555555"}}},
                                                  {"font", {{"value", "sans-serif"}}},
                                                  {"fontSize", {{"value", 11}}}}}}}});
}

void xScaleAndAxes(json& spec, const std::string& y_title) {
  spec["scales"].push_back({{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false},
                            {"nice", false}, {"domain", {{"data", "series"}, {"field", "t_h"}}}});
  spec["axes"] = json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", "time (h)"}, {"tickCount", 10}},
                              {{"orient", "left"}, {"scale", "y"}, {"title", y_title}, {"grid", true}, {"tickCount", 6},
                               {"minExtent", 40}}});
}

json xy(const char* y_field) {
  return {{"x", {{"scale", "x"}, {"field", "t_h"}}}, {"y", {{"scale", "y"}, {"field", y_field}}}};
}

json linePlotMark(const char* name, const char* data, const char* y_field, const char* colour, double width, bool dashed) {
  json enter = xy(y_field);
  enter["stroke"] = {{"value", colour}};
  enter["strokeWidth"] = {{"value", width}};
  if (dashed) enter["strokeDash"] = {{"value", json::array({6, 4})}};
  return {{"type", "line"}, {"name", name}, {"from", {{"data", data}}}, {"encode", {{"enter", enter}}}};
}

json pointMark(const char* name, const char* data, const char* y_field, const json& fill, std::size_t n) {
  json points = xy(y_field);
  points["shape"] = {{"value", "circle"}};
  points["size"] = {{"value", n > kManyPoints ? 7 : 14}};
  points["fill"] = fill;
  points["fillOpacity"] = {{"value", n > kManyPoints ? 0.45 : 0.85}};
  return {{"type", "symbol"}, {"name", name}, {"from", {{"data", data}}}, {"encode", {{"enter", points}}}};
}

// Each measured value with its U (k = 2) as a vertical bar from value − U to value + U (none
// where U is 0: the reference cycle, exact by definition).
json errorBarMark(const char* data, std::size_t n) {
  return {{"type", "rule"},
          {"name", "error_bar_rules"},
          {"from", {{"data", data}}},
          {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                 {"y", {{"scale", "y"}, {"field", "U_lo"}}},
                                 {"y2", {{"scale", "y"}, {"field", "U_hi"}}},
                                 {"stroke", {{"value", kErrorBarColour}}},
                                 {"strokeWidth", {{"value", 1}}},
                                 {"strokeOpacity", {{"value", n > kManyPoints ? 0.25 : 0.6}}}}}}}};
}

json bandMark(const char* data) {
  return {{"type", "area"},
          {"name", "band_area"},
          {"from", {{"data", data}}},
          {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                 {"y", {{"scale", "y"}, {"field", "lo"}}},
                                 {"y2", {{"scale", "y"}, {"field", "hi"}}},
                                 {"fill", {{"value", kBandColour}}}}}}}};
}

// Plot 1: measured points, model line with its ±U band, "before" dashed, time in hours.
json fitPlotSpec(const ChannelName& n, const SeriesData& d, const std::optional<Window>& validation) {
  json spec = baseSpec(n.id + ": measured, model with its \u00b1U band" +
                           std::string(d.has_before ? ", model before" : "") + ", against time in hours",
                       240);
  spec["data"] = json::array({seriesDataset(d)});
  spec["data"].push_back({{"name", "measured"}, {"source", "series"},
                          {"transform", json::array({filterTx("isValid(datum.measured)")})}});
  spec["data"].push_back({{"name", "model"}, {"source", "series"},
                          {"transform", json::array({filterTx("isValid(datum.predicted)")})}});
  spec["data"].push_back({{"name", "band"}, {"source", "series"},
                          {"transform", json::array({filterTx("isValid(datum.predicted) && isValid(datum.U)"),
                                                     formulaTx("lo", "datum.predicted - datum.U"),
                                                     formulaTx("hi", "datum.predicted + datum.U")})}});
  spec["data"].push_back({{"name", "error_bars"}, {"source", "series"},
                          {"transform", json::array({filterTx("isValid(datum.measured) && isValid(datum.U) && datum.U > 0"),
                                                     formulaTx("U_lo", "datum.measured - datum.U"),
                                                     formulaTx("U_hi", "datum.measured + datum.U")})}});
  if (d.has_before)
    spec["data"].push_back({{"name", "before"}, {"source", "series"},
                            {"transform", json::array({filterTx("isValid(datum.before)")})}});
  spec["marks"] = json::array();
  spec["scales"] = json::array();
  addValidationWindow(spec, validation);

  json y_fields = json::array({{{"data", "measured"}, {"field", "measured"}},
                               {{"data", "model"}, {"field", "predicted"}}});
  if (d.has_U) {
    y_fields.push_back({{"data", "band"}, {"field", "lo"}});
    y_fields.push_back({{"data", "band"}, {"field", "hi"}});
    y_fields.push_back({{"data", "error_bars"}, {"field", "U_lo"}});
    y_fields.push_back({{"data", "error_bars"}, {"field", "U_hi"}});
  }
  if (d.has_before) y_fields.push_back({{"data", "before"}, {"field", "before"}});
  xScaleAndAxes(spec, axisTitle(n, ""));
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", false},
                            {"nice", true}, {"domain", {{"fields", y_fields}}}});

  // Drawing order: band, before, U bars, points, then the model line on top, then the label.
  // Mark names must differ from the data sets' (Vega gives each named mark a data set).
  spec["marks"].push_back(bandMark("band"));
  if (d.has_before) spec["marks"].push_back(linePlotMark("model_before_line", "before", "before", kBeforeColour, 1.5, true));
  if (d.has_U) spec["marks"].push_back(errorBarMark("error_bars", d.measured));
  spec["marks"].push_back(pointMark("measured_points", "measured", "measured", {{"value", kMeasuredColour}}, d.measured));
  spec["marks"].push_back(linePlotMark("model_line", "model", "predicted", kModelColour, 2.5, false));
  addValidationLabel(spec, validation);

  const json solid = json::array({1, 0});
  std::vector<LegendEntry> legend{{d.has_U ? "measured ± U" : "measured", "circle", kMeasuredColour, "transparent", solid},
                                  {"model", "stroke", "transparent", kModelColour, solid}};
  if (d.has_U) legend.push_back({"model \u00b1 U", "square", kBandColour, kBandColour, solid});
  if (d.has_before) legend.push_back({"model before", "stroke", "transparent", kBeforeColour, json::array({6, 4})});
  addLegend(spec, legend);
  return spec;
}

// Plot 2: residual = measured − model, with the ±U band about zero; points beyond U in red.
json residualPlotSpec(const ChannelName& n, const SeriesData& d, const std::optional<Window>& validation) {
  json spec = baseSpec(n.id + ": residual (measured \u2212 model) with the \u00b1U band, against time in hours", 150);
  spec["data"] = json::array({seriesDataset(d)});
  spec["data"].push_back(
      {{"name", "residual"}, {"source", "series"},
       {"transform", json::array({filterTx("isValid(datum.measured) && isValid(datum.predicted)"),
                                  formulaTx("residual", "datum.measured - datum.predicted"),
                                  formulaTx("beyond", "isValid(datum.U) && abs(datum.residual) > datum.U")})}});
  spec["data"].push_back({{"name", "band"}, {"source", "series"},
                          {"transform", json::array({filterTx("isValid(datum.U)"), formulaTx("lo", "-datum.U"),
                                                     formulaTx("hi", "datum.U")})}});
  spec["marks"] = json::array();
  spec["scales"] = json::array();
  addValidationWindow(spec, validation);

  json y_fields = json::array({{{"data", "residual"}, {"field", "residual"}}});
  if (d.has_U) {
    y_fields.push_back({{"data", "band"}, {"field", "lo"}});
    y_fields.push_back({{"data", "band"}, {"field", "hi"}});
  }
  xScaleAndAxes(spec, axisTitle(n, "residual "));
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true},
                            {"nice", true}, {"domain", {{"fields", y_fields}}}});

  spec["marks"].push_back(bandMark("band"));
  spec["marks"].push_back({{"type", "rule"},
                           {"encode", {{"enter", {{"x", {{"value", 0}}},
                                                  {"x2", {{"signal", "width"}}},
                                                  {"y", {{"scale", "y"}, {"value", 0}}},
                                                  {"stroke", {{"value", "#999999"}}},
                                                  {"strokeWidth", {{"value", 1}}}}}}}});
  spec["marks"].push_back(pointMark("residual_points", "residual", "residual",
                                    json::array({{{"test", "datum.beyond"}, {"value", kBeyondColour}}, {{"value", kMeasuredColour}}}),
                                    d.measured));
  addValidationLabel(spec, validation);

  const json solid = json::array({1, 0});
  std::vector<LegendEntry> legend{{"residual", "circle", kMeasuredColour, "transparent", solid}};
  if (d.has_U) {
    legend.push_back({"|residual| > U", "circle", kBeyondColour, "transparent", solid});
    legend.push_back({"\u00b1 U", "square", kBandColour, kBandColour, solid});
  }
  addLegend(spec, legend);
  return spec;
}

std::string spanText(const std::optional<Window>& w, const json& s) {
  if (!w && s.empty()) return kDash;
  std::string t = w ? hours(w->from_s) + " \u2013 " + hours(w->to_s) + " h" : kDash;
  if (const auto n = number(s, "samples")) t += " (" + whole(*n) + " samples)";
  return t;
}

void filesTable(Page& page, const json& fit, const json* diagnosis) {
  page.html += "<table class=\"meta\">\n";
  const auto row = [&page](const std::string& name, const std::string& value) {
    page.html += "<tr>" + th(name) + td(value.empty() ? kDash : value) + "</tr>\n";
  };
  row("model", text(fit, "model"));
  row("inputs", text(fit, "inputs"));
  row("errors", text(fit, "errors"));
  row("training", spanText(span(fit, "training"), object(fit, "training")));
  row("validation", spanText(span(fit, "validation"), object(fit, "validation")));
  if (diagnosis != nullptr) {
    const std::string dm = text(*diagnosis, "model");
    if (!dm.empty() && dm != text(fit, "model")) row("model of the diagnosis", dm);
    if (const auto n = number(*diagnosis, "candidates_tried")) row("candidate fits tried", whole(*n));
  }
  page.html += "</table>\n";
}

struct IndicatorColumn {
  const char* key;
  const char* title;
  bool channel_unit;  // else percent
  int digits;
};
constexpr IndicatorColumn kIndicatorColumns[] = {
    {"rmse", "RMSE", true, 3},
    {"smape_percent", "SMAPE (%)", false, 3},
    {"pv_ratio_percent", "PV ratio (%)", false, 3},
    {"p99", "P99", true, 3},
};

void indicatorTable(Page& page, const json& channel, const ChannelName& n) {
  const json& after = object(channel, "indicators");
  const json* before_obj = field(channel, "before");
  const bool has_before = before_obj != nullptr && before_obj->is_object();
  static const json none = json::object();
  const json& before = has_before ? object(*before_obj, "indicators") : none;
  const std::string unit = n.unit.empty() ? "" : " (" + n.unit + ")";
  std::string rows;
  for (const char* set : {"training", "validation"}) {
    const json& a = object(after, set);
    const json& b = object(before, set);
    if (a.empty() && b.empty()) continue;
    rows += "<tr>" + th(set) + td(whole(number(a, "n")), true);
    for (const auto& c : kIndicatorColumns) {
      const std::string av = sig(number(a, c.key), c.digits);
      rows += has_before ? tdHtml(beforeAfter(sig(number(b, c.key), c.digits), av), true) : td(av, true);
    }
    rows += "</tr>\n";
  }
  page.html += "<h3>Quality indicators" + std::string(has_before ? ", before \u2192 after" : "") + "</h3>\n";
  if (rows.empty()) {
    page.html += "<p class=\"note\">No indicators in the input.</p>\n";
    return;
  }
  page.html += "<table class=\"indicators\">\n<thead><tr>" + th("data") + th("n", true);
  for (const auto& c : kIndicatorColumns)
    page.html += th(std::string(c.title) + (c.channel_unit ? unit : ""), true);
  page.html += "</tr></thead>\n<tbody>\n" + rows + "</tbody>\n</table>\n";
}

void parameterTable(Page& page, const json& channel) {
  const json& effects = array(channel, "effects");
  page.html += "<h3>Effects and parameters</h3>\n";
  if (effects.empty()) {
    page.html += "<p class=\"note\">No effects listed.</p>\n";
    return;
  }
  page.html += "<table class=\"parameters\">\n<thead><tr>" + th("effect") + th("kind") + th("input") + th("parameter") +
               th("value \u00b1 u", true) + th("unit") + "</tr></thead>\n<tbody>\n";
  for (const auto& e : effects) {
    const json& params = array(e, "parameters");
    const std::size_t rows = std::max<std::size_t>(1, params.size());
    const std::string rs = rows > 1 ? " rowspan=\"" + std::to_string(rows) + "\"" : "";
    const bool added = boolean(e, "just_added").value_or(false);
    const std::string input = text(e, "input");
    page.html += "<tr><td" + rs + ">" + esc(text(e, "id")) + (added ? " <span class=\"new\">just added</span>" : "") +
                 "</td><td" + rs + ">" + esc(text(e, "kind")) + "</td><td" + rs + ">" +
                 esc(input.empty() ? kDash : input) + "</td>";
    if (params.empty()) page.html += td(kDash) + td(kDash, true) + td("") + "</tr>\n";
    for (std::size_t i = 0; i < params.size(); ++i) {
      const json& p = params[i];
      if (i > 0) page.html += "<tr>";
      page.html += td(text(p, "name")) + td(valueU(number(p, "value"), number(p, "u")), true) +
                   td(displayUnit(text(p, "unit"))) + "</tr>\n";
    }
  }
  page.html += "</tbody>\n</table>\n";
}

std::string yesNo(const std::optional<bool>& b) { return b ? (*b ? "yes" : "no") : kDash; }

// Where u dwarfs the residual, "within 1.5 u" says little: the page says so in a sentence
// (the same words as the terminal, model/verdict_strength.hpp).
void weakVerdictNote(Page& page, double u, double residual_rms, const std::string& unit) {
  const std::string sentence = model::weakVerdictSentence(u, residual_rms, unit);
  if (!sentence.empty()) page.html += "<p class=\"strength\"><strong>Weak verdict:</strong> " + esc(sentence) + "</p>\n";
}

void channelDiagnosis(Page& page, const json& d, const ChannelName& n) {
  const std::string unit = n.unit.empty() ? "" : " (" + n.unit + ")";
  const json& rms = object(d, "rms_residual");
  const json& lb = object(d, "ljung_box");
  // One quantity per row: the names are long, the values short.
  page.html += "<h3>Diagnosis of the residual</h3>\n<table class=\"diagnosis\">\n<tbody>\n";
  const auto row = [&page](const std::string& name, const std::string& value) {
    page.html += "<tr>" + th(name) + td(value, true) + "</tr>\n";
  };
  row("RMS residual, training" + unit, sig(number(rms, "training"), 3));
  row("RMS residual, validation" + unit, sig(number(rms, "validation"), 3));
  row("standard uncertainty of measurement u" + unit, sig(number(d, "u_measurement"), 3));
  // The verdict judges the validation span's RMS, the training span's when there is none.
  const bool on_validation = number(rms, "validation").has_value();
  const std::optional<double> judged = on_validation ? number(rms, "validation") : number(rms, "training");
  const std::string span_name = on_validation ? "validation" : "training";
  if (boolean(d, "within")) row("RMS residual (" + span_name + ") within 1.5 u", yesNo(boolean(d, "within")));
  const std::optional<double> u = number(d, "u_measurement");
  if (u && judged) row("u / RMS residual (" + span_name + ")", model::ratioText(model::uOverResidual(*u, *judged)));
  row("Ljung\u2013Box Q (" + whole(number(lb, "lags")) + " lags)", sig(number(lb, "Q"), 4));
  const std::optional<double> p = number(lb, "p");
  row("Ljung\u2013Box p", p ? model::pValueText(*p) : kDash);
  row("residual white", yesNo(boolean(d, "white")));
  page.html += "</tbody>\n</table>\n";
  if (u && judged) weakVerdictNote(page, *u, *judged, n.unit);

  const json& windows = array(d, "windows");
  constexpr std::size_t kMaxWindows = 10;
  if (windows.empty()) {
    page.html += "<p class=\"note\">No time window where |residual| exceeds U.</p>\n";
  } else {
    page.html += "<h3>Windows where |residual| &gt; U</h3>\n<table class=\"windows\">\n<thead><tr>" +
                 th("from (h)", true) + th("to (h)", true) + th("peak |residual|" + unit, true) + th("samples", true) +
                 "</tr></thead>\n<tbody>\n";
    for (std::size_t i = 0; i < std::min(windows.size(), kMaxWindows); ++i) {
      const json& w = windows[i];
      page.html += "<tr>" + td(hours(number(w, "from_s")), true) + td(hours(number(w, "to_s")), true) +
                   td(sig(number(w, "peak"), 3), true) + td(whole(number(w, "samples")), true) + "</tr>\n";
    }
    page.html += "</tbody>\n</table>\n";
    if (windows.size() > kMaxWindows)
      page.html += "<p class=\"note\">\u2026 and " + std::to_string(windows.size() - kMaxWindows) + " more windows.</p>\n";
  }

  // The strongest first (stable: ties keep the input's order).
  const json& cross = array(d, "cross_correlation");
  std::vector<const json*> cc;
  for (const auto& c : cross) cc.push_back(&c);
  const auto strength = [](const json* c) { return std::abs(number(*c, "r").value_or(0.0)); };
  std::stable_sort(cc.begin(), cc.end(), [&](const json* a, const json* b) { return strength(a) > strength(b); });
  constexpr std::size_t kMaxCross = 5;
  if (!cc.empty()) {
    page.html += "<h3>Strongest cross-correlations of the residual with the inputs</h3>\n<table class=\"cross\">\n<thead><tr>" +
                 th("input") + th("lag (s)", true) + th("lag (h)", true) + th("r", true) + th("significant") +
                 "</tr></thead>\n<tbody>\n";
    for (std::size_t i = 0; i < std::min(cc.size(), kMaxCross); ++i) {
      const json& c = *cc[i];
      const auto lag = number(c, "lag_s");
      page.html += "<tr>" + td(text(c, "input")) + td(whole(lag), true) + td(hours(lag), true) +
                   td(number(c, "r") ? fixed(*number(c, "r"), 2) : kDash, true) + td(yesNo(boolean(c, "significant"))) +
                   "</tr>\n";
    }
    page.html += "</tbody>\n</table>\n";
  }
}

const json* findChannel(const json* diagnosis, const std::string& id) {
  if (diagnosis == nullptr) return nullptr;
  for (const auto& c : array(*diagnosis, "channels"))
    if (text(c, "channel") == id) return &c;
  return nullptr;
}

std::string verdictText(const std::string& v) {
  if (v == "missing") return "an effect is missing from the model";
  if (v == "nothing_missing") return "nothing is missing: every residual is white and within 1.5 u of the measurement";
  if (v == "unexplained") return "the residual has structure that no candidate effect explains";
  return v.empty() ? kDash : v;
}

void candidatesTable(Page& page, const json& diagnosis) {
  const json& cands = array(diagnosis, "candidates");
  page.html += "<h3>Candidate effects, ranked</h3>\n";
  if (cands.empty()) {
    page.html += "<p class=\"note\">No candidate effect improves the model.</p>\n";
    return;
  }
  page.html += "<table class=\"candidates\">\n<thead><tr>" + th("rank") + th("channel") +
               th("validation RMSE, before \u2192 after", true) + th("MDL, before \u2192 after", true) +
               th("parameters of the effect") + "</tr></thead>\n";
  for (std::size_t k = 0; k < cands.size(); ++k) {
    const json& c = cands[k];
    const json& chans = array(c, "channels");
    const std::size_t rows = std::max<std::size_t>(1, chans.size()) + 1;
    std::string name = text(c, "id");
    if (name.empty()) {
      name = text(c, "effect");
      const std::string input = text(c, "input");
      if (!input.empty()) name += "(" + input + ")";
    }
    const auto rank = number(c, "rank");
    page.html += "<tbody class=\"candidate\">\n<tr><td class=\"rank\" rowspan=\"" + std::to_string(rows) + "\">" +
                 esc(rank ? whole(*rank) : std::to_string(k + 1)) + "</td><td colspan=\"4\"><strong>" +
                 esc(name.empty() ? kDash : name) + "</strong>";
    if (const auto score = number(c, "score")) page.html += " <span class=\"note\">(score " + esc(sig(*score, 3)) + ")</span>";
    page.html += "<p class=\"sentence\">" + esc(text(c, "sentence")) + "</p>";
    const std::string command = text(c, "command");
    if (!command.empty()) page.html += "<pre><code>" + esc(command) + "</code></pre>";
    page.html += "</td></tr>\n";
    if (chans.empty()) page.html += "<tr>" + td(kDash) + td(kDash, true) + td(kDash, true) + td(kDash) + "</tr>\n";
    for (const auto& ch : chans) {
      const std::string id = text(ch, "channel");
      std::string unit;
      if (const json* fc = findChannel(&diagnosis, id)) unit = displayUnit(text(*fc, "unit"));
      std::string params;
      for (const auto& p : array(ch, "parameters")) {
        if (!params.empty()) params += "<br>";
        params += esc(text(p, "name") + " = " + withUnit(valueU(number(p, "value"), number(p, "u")),
                                                          displayUnit(text(p, "unit"))));
      }
      page.html += "<tr>" + td(id) +
                   tdHtml(beforeAfter(sig(number(ch, "validation_rmse_before"), 3),
                                      withUnit(sig(number(ch, "validation_rmse_after"), 3), unit)),
                          true) +
                   tdHtml(beforeAfter(sig(number(ch, "mdl_before"), 3), sig(number(ch, "mdl_after"), 3)), true) +
                   tdHtml(params.empty() ? kDash : params) + "</tr>\n";
    }
    page.html += "</tbody>\n";
  }
  page.html += "</table>\n";
}

void checkKind(const json& j, const char* expected, const char* what) {
  if (!j.is_object())
    throw InputError("", 0, std::string("model report: the ") + what + " is not a JSON object (expected the output of `" +
                                expected + " --json`)");
  const json* kind = field(j, "kind");
  if (kind != nullptr && kind->is_string() && kind->get<std::string>() != expected)
    throw InputError("", 0, std::string("model report: the ") + what + " has kind \"" + kind->get<std::string>() +
                                "\", expected \"" + expected + "\"");
}

// What only this page has: the weak-verdict note.
constexpr const char* kModelStyle = ".strength { background: #fff6e5; border-left: 3px solid #e6a100; padding: .3em .7em; }\n";

}  // namespace

std::string modelReportHtml(const json& fit, const json* diagnosis, const std::string& vega_js_path) {
  checkKind(fit, "probeloop model fit", "fit");
  if (diagnosis != nullptr) checkKind(*diagnosis, "probeloop model diagnose", "diagnosis");
  const json* channels = field(fit, "channels");
  if (channels == nullptr || !channels->is_array())
    throw InputError("", 0, "model report: the fit has no \"channels\" array (expected the output of `probeloop model fit --json`)");
  const std::string vega = vegaRuntime(vega_js_path);  // first: a missing runtime is an error whatever the data
  const std::optional<Window> validation = span(fit, "validation");

  Page page;
  page.html += "<header>\n<h1>Error model fit" + std::string(diagnosis ? " and diagnosis" : "") + "</h1>\n";
  filesTable(page, fit, diagnosis);
  page.html += "</header>\n<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" +
               std::string(kErrorHook) + "</script>\n";

  if (diagnosis != nullptr) {
    const std::string verdict = text(*diagnosis, "verdict");
    page.html += "<section class=\"diagnosis\">\n<h2>Diagnosis</h2>\n<p class=\"verdict\">Verdict: <strong>" +
                 esc(verdictText(verdict)) + "</strong></p>\n";
    const std::string message = text(*diagnosis, "message");
    if (!message.empty()) page.html += "<p class=\"message\">" + esc(message) + "</p>\n";
    candidatesTable(page, *diagnosis);
    page.html += "</section>\n";
  }

  std::vector<std::string> shown;
  for (const auto& c : *channels) {
    const ChannelName n = channelName(c);
    shown.push_back(n.id);
    page.html += "<section class=\"channel\">\n<h2>" + esc(axisTitle(n, "")) + "</h2>\n<p class=\"summary\">";
    std::string facts;
    const auto fact = [&facts](const std::string& s) { facts += (facts.empty() ? "" : " \u00b7 ") + s; };
    if (const auto u = number(c, "u_measurement")) fact("u of measurement = " + withUnit(sig(*u, 3), n.unit));
    if (const auto s = number(c, "sigma")) fact("residual \u03c3 (fit) = " + withUnit(sig(*s, 3), n.unit));
    // The residual a reader weighs against u: the validation RMSE, else the training RMSE.
    const json& ind = object(c, "indicators");
    const bool on_validation = number(object(ind, "validation"), "rmse").has_value();
    const std::optional<double> judged = number(object(ind, on_validation ? "validation" : "training"), "rmse");
    const std::optional<double> u_m = number(c, "u_measurement");
    if (u_m && judged)
      fact("u / " + std::string(on_validation ? "validation" : "training") +
           " RMSE = " + model::ratioText(model::uOverResidual(*u_m, *judged)));
    std::string effects;
    for (const auto& e : array(c, "effects")) effects += (effects.empty() ? "" : ", ") + text(e, "id");
    fact("effects: " + (effects.empty() ? kDash : effects));
    const json* before = field(c, "before");
    if (before != nullptr && before->is_object()) {
      std::string b;
      for (const auto& e : array(*before, "effects")) b += (b.empty() ? "" : ", ") + (e.is_string() ? e.get<std::string>() : e.dump());
      fact("before: " + (b.empty() ? kDash : b));
    }
    page.html += esc(facts) + "</p>\n";
    if (u_m && judged) weakVerdictNote(page, *u_m, *judged, n.unit);

    const SeriesData d = seriesData(object(c, "series"));
    if (d.rows.empty()) {
      page.html += "<p class=\"note\">No series in the input: nothing to plot.</p>\n";
    } else {
      std::string cap = "Measured (points, each with its U as a bar), model (line, drawn over the points) and the band model \u00b1 U";
      if (!d.has_U)
        cap = "Measured (points) and model (line, drawn over the points); the input holds no U for " + n.label +
              ", so the points have no error bars and the model no band";
      if (d.has_before) cap += "; dashed: the model before the effects just added";
      page.plot(fitPlotSpec(n, d, validation), cap + (validation ? "; shaded: validation window." : "."));
      page.plot(residualPlotSpec(n, d, validation),
                "Residual = measured \u2212 model" +
                    std::string(d.has_U ? "; band \u00b1 U; red points: |residual| > U."
                                        : "; the input holds no U for " + n.label + ", so no band."));
    }
    indicatorTable(page, c, n);
    parameterTable(page, c);
    if (const json* dc = findChannel(diagnosis, n.id)) channelDiagnosis(page, *dc, n);
    page.html += "</section>\n";
  }
  if (diagnosis != nullptr) {
    for (const auto& dc : array(*diagnosis, "channels")) {
      const ChannelName n = channelName(dc);
      if (std::find(shown.begin(), shown.end(), n.id) != shown.end()) continue;
      page.html += "<section class=\"channel\">\n<h2>" + esc(axisTitle(n, "")) +
                   " <span class=\"note\">(diagnosed, not in the fit)</span></h2>\n";
      channelDiagnosis(page, dc, n);
      page.html += "</section>\n";
    }
  }

  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
      "content=\"probeloop\">\n<title>" +
      esc("Error model fit" + std::string(diagnosis ? " and diagnosis" : "") +
          (text(fit, "model").empty() ? "" : " \u2014 " + text(fit, "model"))) +
      "</title>\n<style>" + kStyle + kModelStyle + "</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report
