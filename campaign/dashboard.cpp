#include "campaign/dashboard.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "model/dataset.hpp"
#include "model/indicators.hpp"
#include "report/vega.hpp"

namespace probeloop::campaign {
namespace {

using namespace report::web;

constexpr const char* kMeasured = "#1f77b4";
constexpr const char* kPrediction = "#2ca02c";
constexpr const char* kResidual = "#ff7f0e";
constexpr const char* kBeyond = "#d62728";

struct Band {
  double from_s = 0, to_s = 0;
  std::string phase;
};

// The phase bands from the stored phase history (CP and NG; the compensation phase unshaded).
std::vector<Band> phaseBands(Database& db, double end_s) {
  std::vector<Band> out;
  auto q = db.prepare("SELECT t_s, phase FROM phases ORDER BY seq");
  std::vector<std::pair<double, std::string>> h;
  while (q.step()) h.emplace_back(q.real(0), q.text(1));
  for (std::size_t i = 0; i < h.size(); ++i) {
    if (h[i].second == "compensation") continue;
    out.push_back({h[i].first, i + 1 < h.size() ? h[i + 1].first : end_s, h[i].second});
  }
  return out;
}

json channelPlot(const std::string& channel, double limit, const json& measured, const json& predicted,
                 const json& bands) {
  const std::string unit = displayUnit(model::channelUnit(channel));
  json spec = baseSpec(channel + ": uncompensated error with U, prediction, compensated residual, action limits", 220);
  spec["data"] = json::array();
  spec["data"].push_back({{"name", "measured"}, {"values", measured},
                          {"transform", json::array({formulaTx("t_h", "datum.t_s / 3600"),
                                                     formulaTx("lo", "datum.uncompensated - datum.U"),
                                                     formulaTx("hi", "datum.uncompensated + datum.U")})}});
  spec["data"].push_back({{"name", "compensated"}, {"source", "measured"},
                          {"transform", json::array({filterTx("isValid(datum.residual)"),
                                                     formulaTx("beyond", "abs(datum.residual) > " + std::to_string(limit))})}});
  spec["data"].push_back({{"name", "predicted"}, {"values", predicted},
                          {"transform", json::array({formulaTx("t_h", "datum.t_s / 3600")})}});
  spec["data"].push_back({{"name", "bands"}, {"values", bands},
                          {"transform", json::array({formulaTx("from_h", "datum.from_s / 3600"),
                                                     formulaTx("to_h", "datum.to_s / 3600")})}});
  spec["data"].push_back({{"name", "limits"}, {"values", json::array({{{"v", limit}}, {{"v", -limit}}})}});
  spec["scales"] = json::array();
  spec["scales"].push_back({{"name", "x"}, {"type", "linear"}, {"range", "width"}, {"zero", false}, {"nice", false},
                            {"domain", {{"fields", json::array({{{"data", "measured"}, {"field", "t_h"}},
                                                                {{"data", "predicted"}, {"field", "t_h"}}})}}}});
  spec["scales"].push_back({{"name", "y"}, {"type", "linear"}, {"range", "height"}, {"zero", true}, {"nice", true},
                            {"domain", {{"fields", json::array({{{"data", "measured"}, {"field", "lo"}},
                                                                {{"data", "measured"}, {"field", "hi"}},
                                                                {{"data", "predicted"}, {"field", "value"}},
                                                                {{"data", "limits"}, {"field", "v"}}})}}}});
  spec["axes"] = json::array({{{"orient", "bottom"}, {"scale", "x"}, {"title", "time (h)"}, {"tickCount", 10}},
                              {{"orient", "left"}, {"scale", "y"}, {"title", channel + " (" + unit + ")"},
                               {"grid", true}, {"tickCount", 6}, {"minExtent", 40}}});
  json marks = json::array();
  marks.push_back({{"type", "rect"}, {"from", {{"data", "bands"}}}, {"clip", true},
                   {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "from_h"}}},
                                          {"x2", {{"scale", "x"}, {"field", "to_h"}}},
                                          {"y", {{"value", 0}}}, {"y2", {{"signal", "height"}}},
                                          {"fill", {{"signal", "datum.phase === 'NG' ? '#d62728' : '#000000'"}}},
                                          {"fillOpacity", {{"value", 0.06}}}}}}}});
  marks.push_back({{"type", "rule"}, {"from", {{"data", "limits"}}},
                   {"encode", {{"enter", {{"x", {{"value", 0}}}, {"x2", {{"signal", "width"}}},
                                          {"y", {{"scale", "y"}, {"field", "v"}}},
                                          {"stroke", {{"value", kBeyond}}}, {"strokeDash", {{"value", json::array({6, 4})}}}}}}}});
  marks.push_back({{"type", "rule"}, {"from", {{"data", "measured"}}},
                   {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                          {"y", {{"scale", "y"}, {"field", "lo"}}},
                                          {"y2", {{"scale", "y"}, {"field", "hi"}}},
                                          {"stroke", {{"value", kMeasured}}}, {"strokeOpacity", {{"value", 0.35}}}}}}}});
  marks.push_back({{"type", "line"}, {"from", {{"data", "predicted"}}},
                   {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                          {"y", {{"scale", "y"}, {"field", "value"}}},
                                          {"stroke", {{"value", kPrediction}}}, {"strokeWidth", {{"value", 1.5}}}}}}}});
  marks.push_back({{"type", "symbol"}, {"from", {{"data", "measured"}}},
                   {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                          {"y", {{"scale", "y"}, {"field", "uncompensated"}}},
                                          {"size", {{"value", 14}}}, {"fill", {{"value", kMeasured}}}}}}}});
  marks.push_back({{"type", "symbol"}, {"from", {{"data", "compensated"}}},
                   {"encode", {{"enter", {{"x", {{"scale", "x"}, {"field", "t_h"}}},
                                          {"y", {{"scale", "y"}, {"field", "residual"}}},
                                          {"shape", {{"value", "diamond"}}}, {"size", {{"value", 22}}},
                                          {"fill", {{"signal", "datum.beyond ? '" + std::string(kBeyond) + "' : '" +
                                                                   kResidual + "'"}}}}}}}});
  spec["marks"] = marks;
  const json solid = json::array({1, 0});
  addLegend(spec, {{"uncompensated \u00b1 U", "circle", kMeasured, "transparent", solid},
                   {"prediction", "stroke", "transparent", kPrediction, solid},
                   {"compensated residual", "diamond", kResidual, "transparent", solid},
                   {"beyond the action limit", "diamond", kBeyond, "transparent", solid},
                   {"action limit", "stroke", "transparent", kBeyond, json::array({6, 4})}});
  return spec;
}

}  // namespace

std::string liveDashboardHtml(CampaignStore& store, const LiveLoop& loop, const std::string& vega_js_path) {
  const std::string vega = vegaRuntime(vega_js_path);
  Database& db = store.database();
  const StoreStatus s = store.status();
  Page page;
  std::string plan_file;
  {
    auto q = db.prepare("SELECT file FROM manifest WHERE id = 1");
    if (q.step()) plan_file = q.text(0);
  }
  page.html += "<header>\n<h1>Live TALC loop: " + esc(s.machine) + "</h1>\n<p>Store " + esc(s.path) + "; plan " +
               esc(plan_file) + ". Phase now: <strong>" + esc(model::talcPhaseName(loop.phase())) + "</strong>.</p>\n";
  {
    // The options as "name value" pairs, so that the line wraps.
    auto q = db.prepare("SELECT json FROM talc_config WHERE id = 1");
    if (q.step()) {
      std::string options;
      const json o = json::parse(q.text(0));
      for (const auto& [k, v] : o.items())
        if (!(v.is_array() && v.empty())) options += (options.empty() ? "" : ", ") + k + " " + v.dump();
      page.html += "<p class=\"note\">TALC options: " + esc(options) + "</p>\n";
    }
  }
  const CycleStatus* last = nullptr;
  for (const auto& c : s.cycles)
    if (c.status != "incomplete") last = &c;
  if (last) {
    page.html += "<table>\n<tr>" + th("latest cycle (as measured)") + th("time (h)", true);
    for (const char* n : geometry::LocationErrors::names()) page.html += th(n, true);
    page.html += "</tr>\n<tr>" + td(std::to_string(last->cycle)) + td(fixed(last->time_s / 3600.0, 3), true);
    for (std::size_t i = 0; i < last->values.size(); ++i) page.html += td(valueU(last->values[i], last->U[i] / 2), true);
    page.html += "</tr>\n</table>\n<p class=\"note\">value \u00b1 u; U = 2 u (k = 2).</p>\n";
  }
  if (!loop.latestDiagnosis().empty())
    page.html += "<p class=\"verdict\">Diagnosis at the latest model update: <strong>" + esc(loop.latestDiagnosis()) +
                 "</strong></p>\n";
  page.html += "</header>\n<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" +
               std::string(kErrorHook) + "</script>\n";

  double end_s = 0;
  for (const auto& m : loop.measurements()) end_s = std::max(end_s, m.t_s);
  {
    auto q = db.prepare("SELECT MAX(t_s) FROM talc_ticks");
    if (q.step() && !q.isNull(0)) end_s = std::max(end_s, q.real(0));
  }
  json bands = json::array();
  for (const auto& b : phaseBands(db, end_s)) bands.push_back({{"from_s", b.from_s}, {"to_s", b.to_s}, {"phase", b.phase}});

  std::map<int, const CycleStatus*> cycle_of;  // a measurement's U
  for (const auto& c : s.cycles) cycle_of[c.cycle] = &c;
  const auto& names = geometry::LocationErrors::names();
  std::vector<double> uc_p99, c_p99;
  for (std::size_t q = 0; q < loop.channels().size(); ++q) {
    const std::string& ch = loop.channels()[q];
    const auto idx = static_cast<std::size_t>(std::find(names.begin(), names.end(), ch) - names.begin());
    json measured = json::array();
    std::vector<double> uc, cc;
    for (const auto& m : loop.measurements()) {
      const auto it = cycle_of.find(m.cycle);
      const double U = it != cycle_of.end() && idx < it->second->U.size() ? it->second->U[idx] : 0.0;
      json row = {{"t_s", m.t_s}, {"cycle", m.cycle}, {"uncompensated", m.uncompensated[q]}, {"U", U}};
      if (m.scored(loop.offsetsApplied())) {
        // With the offsets applied the cycle measured the compensated error itself.
        const double compensated = loop.offsetsApplied() ? m.measured[q] : m.residual[q];
        row["residual"] = compensated;
        uc.push_back(std::fabs(m.uncompensated[q]));
        cc.push_back(std::fabs(compensated));
      }
      measured.push_back(row);
    }
    json predicted = json::array();
    auto p = db.prepare("SELECT t.t_s, p.value FROM predictions p JOIN talc_ticks t USING (k) WHERE p.channel = ? ORDER BY k");
    p.bind(1, ch);
    while (p.step()) predicted.push_back({{"t_s", p.real(0)}, {"value", p.real(1)}});
    double lim = 0;
    {
      auto c = db.prepare("SELECT json FROM talc_config WHERE id = 1");
      c.step();
      const json o = json::parse(c.text(0));
      lim = model::channelUnit(ch) == "um" ? o.value("limit_linear_um", 5.0) : o.value("limit_angular_urad", 15.0);
    }
    page.html += "<section class=\"channel\">\n<h2>" + esc(ch) + "</h2>\n";
    page.plot(channelPlot(ch, lim, measured, predicted, bands),
              ch + ": points = uncompensated error with U (k = 2); line = TALC's prediction on the grid (the offset "
                   "issued); diamonds = compensated residual after the calibration phase (red beyond the \u00b1" +
                  sig(lim, 3) + " " + displayUnit(model::channelUnit(ch)) +
                  " action limit, dashed); shaded: calibration phase (grey), No-Good phases (red).");
    page.html += "</section>\n";
    uc_p99.push_back(uc.empty() ? 0 : model::hazenPercentile(uc, 0.99));
    c_p99.push_back(cc.empty() ? 0 : model::hazenPercentile(cc, 0.99));
  }

  page.html += "<section>\n<h2>Compensation so far (seed 004 Table 6.5 layout)</h2>\n<table>\n<tr>" + th("");
  for (const auto& ch : loop.channels()) page.html += th(ch, true);
  page.html += "</tr>\n";
  auto row = [&](const std::string& label, auto cell) {
    page.html += "<tr>" + td(label);
    for (std::size_t q = 0; q < loop.channels().size(); ++q) page.html += td(cell(q), true);
    page.html += "</tr>\n";
  };
  auto unit = [&](std::size_t q) { return displayUnit(model::channelUnit(loop.channels()[q])); };
  row("P99 uncompensated", [&](std::size_t q) { return fixed(uc_p99[q], 1) + " " + unit(q); });
  row("P99 compensated", [&](std::size_t q) { return fixed(c_p99[q], 1) + " " + unit(q); });
  row("reduction", [&](std::size_t q) { return fixed(uc_p99[q] > 0 ? 100 * (1 - c_p99[q] / uc_p99[q]) : 0, 1) + " %"; });
  page.html += "</table>\n<p class=\"note\">Over the measurements after the calibration phase; P99 = Hazen percentile of "
               "|value|.</p>\n</section>\n";

  page.html += "<section>\n<h2>Model versions</h2>\n<table>\n<tr>" + th("version", true) + th("time (h)", true) + th("why") +
               th("diagnosis") + "</tr>\n";
  {
    auto q = db.prepare("SELECT version, t_s, reason, diagnosis FROM models ORDER BY version");
    while (q.step())
      page.html += "<tr>" + td(std::to_string(q.integer(0)), true) + td(fixed(q.real(1) / 3600.0, 3), true) + td(q.text(2)) +
                   td(q.text(3)) + "</tr>\n";
  }
  page.html += "</table>\n</section>\n<section>\n<h2>Events</h2>\n<table>\n<tr>" + th("time (h)", true) + th("channel") +
               th("residual", true) + th("action") + "</tr>\n";
  {
    auto q = db.prepare("SELECT t_s, channel, residual, action FROM talc_events ORDER BY seq");
    while (q.step())
      page.html += "<tr>" + td(fixed(q.real(0) / 3600.0, 3), true) + td(q.text(1).empty() ? kDash : q.text(1)) +
                   td(q.text(1).empty() ? "" : fixed(q.real(2), 2), true) + td(q.text(3)) + "</tr>\n";
  }
  page.html += "</table>\n</section>\n";

  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
      "content=\"probeloop\">\n<title>" +
      esc("Live TALC loop \u2014 " + s.machine) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}


std::string liveSummaryText(const LiveLoop& loop) {
  const auto& ms = loop.measurements();
  int taken = 0, scored = 0;
  for (const auto& m : ms) {
    taken += m.taken ? 1 : 0;
    scored += m.scored(loop.offsetsApplied()) ? 1 : 0;
  }
  std::ostringstream s;
  s << "TALC live: " << model::talcPhaseName(loop.phase()) << "; " << ms.size() << " cycles measured (" << taken
    << " fed to TALC), " << scored << " scored after the calibration phase"
    << (loop.offsetsApplied() ? " with the offsets applied" : "") << "\n";
  if (scored == 0) return s.str();
  s << std::string(12, ' ');
  for (const auto& c : loop.channels()) s << std::setw(13) << c;
  s << "\n";
  std::vector<double> uc_p99, c_p99;
  for (std::size_t q = 0; q < loop.channels().size(); ++q) {
    std::vector<double> uc, cc;
    for (const auto& m : ms)
      if (m.scored(loop.offsetsApplied())) {
        uc.push_back(std::fabs(m.uncompensated[q]));
        cc.push_back(std::fabs(loop.offsetsApplied() ? m.measured[q] : m.residual[q]));
      }
    uc_p99.push_back(model::hazenPercentile(uc, 0.99));
    c_p99.push_back(model::hazenPercentile(cc, 0.99));
  }
  auto row = [&](const char* label, auto value) {
    s << std::left << std::setw(12) << label << std::right;
    for (std::size_t q = 0; q < loop.channels().size(); ++q) s << std::setw(13) << value(q);
    s << "\n";
  };
  auto unit = [&](std::size_t q) { return model::channelUnit(loop.channels()[q]); };
  row("P99_UC", [&](std::size_t q) { return fixed(uc_p99[q], 1) + " " + unit(q); });
  row("P99_C", [&](std::size_t q) { return fixed(c_p99[q], 1) + " " + unit(q); });
  row("Reduction", [&](std::size_t q) { return fixed(uc_p99[q] > 0 ? 100 * (1 - c_p99[q] / uc_p99[q]) : 0, 1) + " %"; });
  return s.str();
}

}  // namespace probeloop::campaign
