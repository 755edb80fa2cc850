#include "report/sphere_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "report/report_test_support.hpp"
#include "report/sphere_report_plots.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using testing::count;
using testing::dataset;
using testing::spec;

// Hand-made evaluations in the schema of `probeloop evaluate` for a sphere artifact
// (docs/formats.md#evaluation-json): six cycles 420 s apart, cycle 1 the reference. A stand-in
// Vega bundle: these tests check the page the C++ writes; tests/integration/
// sphere_report_check.py renders it in Chromium.
class SphereReport : public testing::PageTest {
 protected:
  SphereReport() : PageTest("sphere-report") {}
};

constexpr int kCycles = 6;
constexpr double kPeriod = 420.0;
const char* const kIds[] = {"EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"};
// EX0C ... EB0C grow linearly; EC0C goes up and down (min at cycle 3, max at cycle 2).
constexpr double kSlope[] = {0.5, -0.3, 1.0, 0.2, 2.0, -1.0, 0.0};
constexpr double kEC0C[] = {0, 4, -2, 3, 1, 2};
constexpr double kU[] = {1.5, 1.5, 2.5, 0.5, 7.0, 7.0, 6.0};

double valueOf(int e, int c) { return e == 6 ? kEC0C[c - 1] : kSlope[e] * (c - 1); }
double uOf(int e, int c) { return c == 1 ? 0.0 : kU[e]; }
double timeOf(int c) { return 60.0 + (c - 1) * kPeriod + 0.3 * (c - 1); }  // planned mean + 0.3 s per cycle

// As evaluate/location_budget.cpp writes them: quantity "EX0C", unit "um".
json budget(int e, int c) {
  const std::string id = kIds[e];
  const std::string unit = id.substr(id.rfind('_') + 1);
  const double U = uOf(e, c);
  return {{"quantity", id.substr(0, id.rfind('_'))},
          {"unit", unit},
          {"value", valueOf(e, c)},
          {"u_c", U / 2},
          {"nu_eff", c == 2 ? json(nullptr) : json(40.5)},
          {"k", 2.0},
          {"U", U},
          {"contributions",
           json::array({{{"input", "tool-change repeatability"}, {"type", "B"}, {"distribution", "normal"},
                         {"basis", "probe.tool_change_repeatability_2sigma / 2"}, {"u", 0.4 * U}, {"dof", nullptr}},
                        {{"input", "probe point scatter"}, {"type", "A"}, {"distribution", "normal"},
                         {"basis", "pooled residual"}, {"u", 0.3 * U}, {"dof", 310}}})}};
}

json evaluation() {
  json cycles = json::array();
  for (int c = 1; c <= kCycles; ++c) {
    json ls = json::object(), budgets = json::array();
    for (int e = 0; e < 7; ++e) {
      ls[kIds[e]] = valueOf(e, c);
      budgets.push_back(budget(e, c));
    }
    cycles.push_back({{"cycle", c}, {"time_s", timeOf(c)}, {"least_squares", ls}, {"formulas_eq_5_4_to_5_10", ls},
                      {"model_residual_xy_um", 0.1}, {"model_residual_z_um", 0.05}, {"budgets", budgets},
                      {"spheres", json::array()}});
  }
  return {{"format", "probeloop-evaluation"},
          {"version", 1},
          {"kind", "sphere_artifact"},
          {"manifest", "plan/plan.json"},
          {"points_file", "run/dprnt.txt"},
          {"reference_cycle", 1},
          {"d_m", 0.32},
          {"least_squares_positions", {1, 2, 3, 4}},
          {"formula_positions", {1, 2, 3, 4}},
          {"incomplete_cycles", json::array({{{"cycle", 7}, {"reason", "position 3 has 2 of 5 points"}}})},
          {"point_scatter", {{"type_b_sigma_um", 0.5}, {"type_a_sigma_um", 0.72}, {"type_a_dof", 310}, {"used", "type A"}}},
          {"centre_repeatability",
           json::array({{{"position", 1}, {"cycles", 6}, {"s_um", {0.6, 0.9, 0.1}}, {"U_single_um", {1.2, 1.8, 0.2}},
                         {"U_single_3d_um", 2.2}, {"U_mean_um", {0.5, 0.7, 0.1}}, {"U_mean_3d_um", 0.9},
                         {"note", "over the complete cycles"}}})},
          {"cycles", cycles}};
}

// The plan: 8 cycles, each cycle's points at 0, 50 and 100 s after its origin; origins 420 s
// apart from 10 s, so a cycle's planned mean point time is 60 + 420 (c - 1) s.
parts::PlanManifest manifest() {
  parts::PlanManifest m;
  m.kind = "sphere_artifact";
  m.machine_name = "NMV 5000 DCG";
  m.sphere_radius_mm = 15;
  m.radius_from_axis_mm = 160;
  for (int p = 1; p <= 4; ++p) {
    parts::ManifestSphere s;
    s.id = "S" + std::to_string(p);
    s.position = p;
    s.c_deg = 90.0 * (p - 1);
    m.spheres.push_back(s);
  }
  for (const double t : {0.0, 50.0, 100.0}) {
    parts::ManifestPoint p;
    p.feature = "S1";
    p.position = 1;
    p.time_in_cycle_s = t;
    m.points.push_back(p);
  }
  m.cycles = 8;
  m.gap_s = 300;
  m.cycle_time_s = 120;
  m.tool_change_each_cycle = true;
  for (int c = 1; c <= m.cycles; ++c) m.cycle_start_s.push_back(10.0 + (c - 1) * kPeriod);
  return m;
}

// inputs.csv as the simulator writes it, every 60 s from 0 to 2700 s; T_env_C = 20 + t / 3600.
std::string inputsCsv() {
  std::string s = "time_s,T_env_C,T_caxis_C,c_rpm,spindle_rpm,feed_mm_per_min,mwf_on,tool_changes\n";
  for (int i = 0; i <= 45; ++i) {
    const double t = 60.0 * i;
    char row[256];
    std::snprintf(row, sizeof row, "%g,%.6g,%.6g,%g,0,%g,%d,%d\n", t, 20 + t / 3600, 21 + 2 * t / 3600,
                  i >= 10 && i < 30 ? 1200.0 : 0.0, i % 7 == 0 ? 200.0 : 0.0, i >= 20 ? 1 : 0, i / 10);
    s += row;
  }
  return s;
}

std::vector<json> specs(const std::string& html) {
  std::vector<json> out;
  for (int k = 1;; ++k) {
    json s = spec(html, k);
    if (s.is_null()) return out;
    out.push_back(std::move(s));
  }
}

json mark(const json& s, const std::string& name) {
  for (const auto& m : s["marks"])
    if (m.value("name", "") == name) return m;
  return nullptr;
}

TEST_F(SphereReport, OnePlotPerErrorCarryingTheEvaluationsValuesAndU) {
  const json eval = evaluation();
  const std::string html = sphereCampaignReportHtml(eval, nullptr, nullptr, vega_);
  const auto all = specs(html);
  ASSERT_EQ(all.size(), 7u);
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 7u);
  for (int e = 0; e < 7; ++e) {
    const json& s = all[e];
    EXPECT_EQ(s["$schema"], "https://vega.github.io/schema/vega/v5.json");
    EXPECT_EQ(s["usermeta"]["kind"], "error");
    EXPECT_EQ(s["usermeta"]["error"], kIds[e]);
    // The unit in the y axis title: µm for the lengths, µrad for the angles.
    const std::string unit = e < 4 ? "\u00b5m" : "\u00b5rad";
    EXPECT_NE(s["axes"][1]["title"].get<std::string>().find("(" + unit + ")"), std::string::npos) << kIds[e];
    EXPECT_EQ(s["axes"][0]["title"].get<std::string>().rfind("time (h", 0), 0u);
    const json values = dataset(s, "cycles")["values"];
    ASSERT_EQ(values.size(), static_cast<std::size_t>(kCycles)) << kIds[e];
    for (int c = 1; c <= kCycles; ++c) {
      const json& row = values[c - 1];
      EXPECT_EQ(row["cycle"], c);
      EXPECT_EQ(row["time_s"], eval["cycles"][c - 1]["time_s"]);
      EXPECT_EQ(row["value"], eval["cycles"][c - 1]["budgets"][e]["value"]);
      EXPECT_EQ(row["U"], eval["cycles"][c - 1]["budgets"][e]["U"]);
      EXPECT_DOUBLE_EQ(row["value"].get<double>(), valueOf(e, c));
      EXPECT_DOUBLE_EQ(row["U"].get<double>(), uOf(e, c));
    }
    // The band: value - U to value + U over the rows that have U; a symbol per cycle.
    const json band_data = dataset(s, "cycles_U");
    ASSERT_TRUE(band_data.is_object());
    EXPECT_EQ(band_data["source"], "cycles");
    const std::string tx = band_data["transform"].dump();
    EXPECT_NE(tx.find("\"as\":\"lo\",\"expr\":\"datum.value - datum.U\""), std::string::npos) << tx;
    EXPECT_NE(tx.find("\"as\":\"hi\",\"expr\":\"datum.value + datum.U\""), std::string::npos) << tx;
    const json band = mark(s, "u_band");
    ASSERT_TRUE(band.is_object());
    EXPECT_EQ(band["type"], "area");
    EXPECT_EQ(band["from"]["data"], "cycles_U");
    EXPECT_EQ(band["encode"]["enter"]["y"]["field"], "lo");
    EXPECT_EQ(band["encode"]["enter"]["y2"]["field"], "hi");
    EXPECT_EQ(mark(s, "values")["type"], "symbol");
    EXPECT_EQ(mark(s, "values")["from"]["data"], "cycles");
    EXPECT_EQ(mark(s, "value_line")["type"], "line");
    // Hours on the log's clock, one domain: the first and the last cycle.
    EXPECT_EQ(dataset(s, "cycles")["transform"][0]["expr"], "datum.time_s / 3600");
    EXPECT_DOUBLE_EQ(s["scales"][0]["domain"][0].get<double>(), timeOf(1) / 3600);
    EXPECT_DOUBLE_EQ(s["scales"][0]["domain"][1].get<double>(), timeOf(kCycles) / 3600);
  }
  EXPECT_NE(html.find("<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>"), std::string::npos);
  EXPECT_NE(html.find("renderer: 'svg'"), std::string::npos);
}

TEST_F(SphereReport, ValuesWithoutABudgetComeFromLeastSquaresWithoutABand) {
  json eval = evaluation();
  eval["cycles"][3]["budgets"] = json::array();  // cycle 4: no budgets
  eval["cycles"][4]["time_s"] = nullptr;          // cycle 5: no time, left out
  const json s = spec(sphereCampaignReportHtml(eval, nullptr, nullptr, vega_), 3);
  ASSERT_EQ(s["usermeta"]["error"], "EZ0T_um");
  const json values = dataset(s, "cycles")["values"];
  ASSERT_EQ(values.size(), 5u);
  EXPECT_EQ(values[3]["cycle"], 4);
  EXPECT_DOUBLE_EQ(values[3]["value"].get<double>(), valueOf(2, 4));
  EXPECT_TRUE(values[3]["U"].is_null());
  for (const auto& v : values) EXPECT_NE(v["cycle"], 5);
}

TEST_F(SphereReport, InputsArePlottedByUnitOnTheErrorsTimeAxis) {
  const json eval = evaluation();
  const std::string csv = inputsCsv();
  SphereReportOptions o;
  o.inputs_file = "run/inputs.csv";
  const std::string html = sphereCampaignReportHtml(eval, &csv, nullptr, vega_, o);
  const auto all = specs(html);
  ASSERT_EQ(all.size(), 11u);  // 7 errors, then °C, rpm, mm/min and the unitless columns
  const auto columns = [](const json& s) {
    std::vector<std::string> out;
    for (const auto& c : s["usermeta"]["columns"]) out.push_back(c["column"]);
    return out;
  };
  EXPECT_EQ(all[7]["usermeta"]["kind"], "inputs");
  EXPECT_EQ(all[7]["usermeta"]["unit"], "\u00b0C");
  EXPECT_EQ(columns(all[7]), (std::vector<std::string>{"T_env_C", "T_caxis_C"}));
  EXPECT_EQ(all[7]["axes"][1]["title"], "temperature (\u00b0C)");
  EXPECT_EQ(columns(all[8]), (std::vector<std::string>{"c_rpm", "spindle_rpm"}));
  EXPECT_EQ(all[8]["usermeta"]["unit"], "rpm");
  EXPECT_EQ(columns(all[9]), (std::vector<std::string>{"feed_mm_per_min"}));
  EXPECT_EQ(all[9]["usermeta"]["unit"], "mm/min");
  EXPECT_EQ(columns(all[10]), (std::vector<std::string>{"mwf_on", "tool_changes"}));
  EXPECT_EQ(all[10]["usermeta"]["unit"], "");
  // The file's numbers, one row per sample: T_env_C = 20 + t / 3600 at t = 1800 s (row 30).
  const json rows = dataset(all[7], "inputs")["values"];
  ASSERT_EQ(rows.size(), 46u);
  EXPECT_EQ(rows[30]["time_s"], 1800.0);
  EXPECT_DOUBLE_EQ(rows[30]["v0"].get<double>(), 20.5);
  EXPECT_DOUBLE_EQ(rows[30]["v1"].get<double>(), 22.0);
  EXPECT_DOUBLE_EQ(dataset(all[8], "inputs")["values"][15]["v0"].get<double>(), 1200.0);
  EXPECT_EQ(mark(all[8], "input_1")["encode"]["enter"]["y"]["field"], "v1");
  EXPECT_EQ(all[8]["legends"].size(), 1u);
  // States and counts as steps.
  EXPECT_EQ(mark(all[10], "input_0")["encode"]["enter"]["interpolate"]["value"], "step-after");
  // One time domain for all plots: from the first sample (0 s) to the last (2700 s).
  for (const auto& s : all) {
    EXPECT_DOUBLE_EQ(s["scales"][0]["domain"][0].get<double>(), 0.0);
    EXPECT_DOUBLE_EQ(s["scales"][0]["domain"][1].get<double>(), 2700.0 / 3600);
  }
  EXPECT_NE(html.find("run/inputs.csv: 46 samples from 0.00 h to 0.75 h"), std::string::npos);
}

TEST_F(SphereReport, UnitsFromColumnNames) {
  EXPECT_EQ(sphere::unitOfColumn("T_env_C"), "\u00b0C");
  EXPECT_EQ(sphere::unitOfColumn("c_rpm"), "rpm");
  EXPECT_EQ(sphere::unitOfColumn("feed_mm_per_min"), "mm/min");
  EXPECT_EQ(sphere::unitOfColumn("c_load_pct"), "%");
  EXPECT_EQ(sphere::unitOfColumn("mwf_on"), "");
  EXPECT_EQ(sphere::unitOfColumn("tool_changes"), "");
  EXPECT_EQ(sphere::unitOfColumn("C"), "");
}

TEST_F(SphereReport, TablesSummaryCyclesBudgetsAndSchedule) {
  const json eval = evaluation();
  const parts::PlanManifest m = manifest();
  SphereReportOptions o;
  o.manifest_file = "plan/plan.json";
  const std::string html = sphereCampaignReportHtml(eval, nullptr, &m, vega_, o);
  // The header: machine, artifact, cycles, span (5 x 420.3 s = 35 min).
  EXPECT_NE(html.find("on NMV 5000 DCG</h1>"), std::string::npos);
  EXPECT_NE(html.find("spheres of \u00d8 30 mm at d/2 = 160 mm from the C axis, 4 positions (C = 0\u00b0, 90\u00b0, "
                      "180\u00b0, 270\u00b0)"),
            std::string::npos);
  EXPECT_NE(html.find("6 evaluated, reference cycle 1, 1 incomplete; 8 planned"), std::string::npos);
  EXPECT_NE(html.find("<td>0:35 (h:mm), from 0.02 h to 0.60 h on the log&#39;s clock</td>"), std::string::npos);
  // Summary of EC0C (min -2 at cycle 3, max 4 at cycle 2): range 6 ± (6 + 6).
  EXPECT_NE(html.find("<tr><th>EC0C (\u00b5rad)</th><td class=\"num\">0<br><span class=\"at\">reference cycle 1, "
                      "0.02 h</span></td><td class=\"num\">2.0 \u00b1 6.0<br><span class=\"at\">cycle 6, 0.60 h</span></td>"
                      "<td class=\"num\">2.0 \u00b1 6.0</td><td class=\"num\">-2.0 \u00b1 6.0<br><span class=\"at\">cycle 3, "
                      "0.25 h</span></td><td class=\"num\">4.0 \u00b1 6.0<br><span class=\"at\">cycle 2, 0.13 h</span></td>"
                      "<td class=\"num\">6 \u00b1 12</td></tr>"),
            std::string::npos);
  // EX0C: last 2.5 ± 1.5 at cycle 6; last - first = 2.5 ± 1.5 (the reference's U is 0).
  EXPECT_NE(html.find("<td class=\"num\">2.5 \u00b1 1.5<br><span class=\"at\">cycle 6, 0.60 h</span></td><td "
                      "class=\"num\">2.5 \u00b1 1.5</td>"),
            std::string::npos);
  // Every cycle: cycle 4, t = 1320.9 s = 0.367 h, EZ0T = 3.0 ± 2.5.
  EXPECT_NE(html.find("<tr><td class=\"num\">4</td><td class=\"num\">0.367</td><td class=\"num\">1.5 \u00b1 1.5</td>"
                      "<td class=\"num\">-0.9 \u00b1 1.5</td><td class=\"num\">3.0 \u00b1 2.5</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<details class=\"cycles\" open>"), std::string::npos);
  EXPECT_NE(html.find("Cycle 7 not evaluated: position 3 has 2 of 5 points"), std::string::npos);
  // Budgets of the last cycle (6): EA0C = 10.0 ± 7.0 urad; u = 0.4 U = 2.8 (share 0.8² = 64 %), dof ∞.
  EXPECT_NE(html.find("<h3>Budgets of cycle 6 (the last evaluated)"), std::string::npos);
  EXPECT_NE(html.find("<h4>EA0C = 10.0 \u00b1 7.0 \u00b5rad (k = 2.00): u_c = 3.5 \u00b5rad, \u03bd_eff = 40.5</h4>"),
            std::string::npos);
  EXPECT_NE(html.find("<tr><td>tool-change repeatability</td><td>B</td><td>normal</td><td class=\"num\">2.8</td>"
                      "<td class=\"num\">64.0</td><td class=\"num\">\u221e</td>"
                      "<td>probe.tool_change_repeatability_2sigma / 2</td></tr>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>probe point scatter</td><td>A</td><td>normal</td><td class=\"num\">2.1</td>"
                      "<td class=\"num\">36.0</td><td class=\"num\">310</td>"),
            std::string::npos);
  // Range of U: EZ0T 2.5 in every cycle after the reference, the largest term first.
  EXPECT_NE(html.find("<tr><th>EZ0T (\u00b5m)</th><td class=\"num\">2.50 (cycle 2)</td><td class=\"num\">2.50 (cycle "
                      "2)</td><td>tool-change repeatability</td><td class=\"num\">1.0 \u00b5m</td></tr>"),
            std::string::npos);
  EXPECT_NE(html.find("type A, \u03bd = 310); the budgets use type A"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\">1.2, 1.8, 0.20</td><td class=\"num\">2.2</td>"), std::string::npos);
  // Schedule: cycle 3's points planned from 850 s to 950 s (0.236 - 0.264 h), 320 s (5.33 min)
  // to cycle 4's first point; evaluated at 900.6 s, 0.6 s after the planned mean.
  EXPECT_NE(html.find("<tr><td class=\"num\">3</td><td class=\"num\">0.236</td><td class=\"num\">0.264</td>"
                      "<td class=\"num\">5.33</td><td class=\"num\">0.250</td><td class=\"num\">0.6</td>"
                      "<td>evaluated</td></tr>"),
            std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\">7</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>incomplete: position 3 has 2 of 5 points</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>not in the log</td>"), std::string::npos);  // cycle 8
  EXPECT_NE(html.find("by at most 1.5 s (cycle 6)"), std::string::npos);
  EXPECT_NE(html.find("Planned: 8 cycles of 120.0 s"), std::string::npos);
}

TEST_F(SphereReport, MissingOptionalInputsAreSaidNotInvented) {
  const json eval = evaluation();
  const std::string html = sphereCampaignReportHtml(eval, nullptr, nullptr, vega_);
  EXPECT_EQ(specs(html).size(), 7u);
  EXPECT_NE(html.find("not known without the plan (--manifest)"), std::string::npos);
  EXPECT_NE(html.find("No plan given (--manifest PLAN/plan.json adds the planned cycles)."), std::string::npos);
  EXPECT_NE(html.find("No inputs given"), std::string::npos);
  EXPECT_EQ(html.find("<table class=\"schedule\">"), std::string::npos);
  EXPECT_EQ(html.find("<a href="), std::string::npos);
  EXPECT_NE(html.find("d = 320 mm (the evaluation&#39;s"), std::string::npos);
  // Fields missing or null: a dash, not a number.
  json sparse = evaluation();
  sparse.erase("point_scatter");
  sparse.erase("centre_repeatability");
  sparse["cycles"][5]["budgets"][0]["contributions"][0]["u"] = nullptr;
  const std::string h2 = sphereCampaignReportHtml(sparse, nullptr, nullptr, vega_);
  EXPECT_NE(h2.find("<tr><td>tool-change repeatability</td><td>B</td><td>normal</td><td class=\"num\">\u2014</td>"
                    "<td class=\"num\">\u2014</td>"),
            std::string::npos);
  EXPECT_EQ(h2.find("Probe point scatter"), std::string::npos);
  // With the scene: a relative link.
  SphereReportOptions o;
  o.scene_href = "campaign.gltf";
  EXPECT_NE(sphereCampaignReportHtml(eval, nullptr, nullptr, vega_, o).find("<a href=\"campaign.gltf\">campaign.gltf</a>"),
            std::string::npos);
}

const std::string kEvil = "</script><script>alert(\"x&y\")</script>";

TEST_F(SphereReport, EscapesEveryText) {
  json eval = evaluation();
  eval["points_file"] = kEvil;
  eval["manifest"] = kEvil;
  eval["incomplete_cycles"][0]["reason"] = kEvil;
  eval["cycles"][5]["budgets"][2]["contributions"][0]["input"] = kEvil;
  eval["cycles"][5]["budgets"][2]["contributions"][1]["basis"] = kEvil;
  eval["point_scatter"]["used"] = kEvil;
  parts::PlanManifest m = manifest();
  m.machine_name = "NMV" + kEvil;
  const std::string csv = "time_s,T_" + std::string("<b>") + "_C,c_rpm\n0,20,0\n60,20.5,100\n";
  SphereReportOptions o;
  o.evaluation_file = "eval" + kEvil;
  o.inputs_file = "in" + kEvil;
  o.manifest_file = "plan" + kEvil;
  o.scene_href = "scene\"" + kEvil + ".gltf";
  const std::string html = sphereCampaignReportHtml(eval, &csv, &m, vega_, o);
  const std::size_t plots = specs(html).size();
  EXPECT_EQ(plots, 9u);
  EXPECT_EQ(count(html, "<script"), plots + 3);  // hook, specs, runtime, renderer
  EXPECT_EQ(count(html, "</script"), plots + 3);
  EXPECT_EQ(html.find("alert(\"x"), std::string::npos);
  EXPECT_EQ(html.find("<b>"), std::string::npos);
  EXPECT_NE(html.find("&lt;/script&gt;&lt;script&gt;alert(&quot;x&amp;y&quot;)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("<a href=\"scene&quot;&lt;/script&gt;"), std::string::npos);
  // In a spec the text is kept (JSON-escaped for the script element).
  EXPECT_EQ(specs(html)[7]["usermeta"]["columns"][0]["column"], "T_<b>_C");
}

TEST_F(SphereReport, IsDeterministic) {
  const json eval = evaluation();
  const std::string csv = inputsCsv();
  const parts::PlanManifest m = manifest();
  EXPECT_EQ(sphereCampaignReportHtml(eval, &csv, &m, vega_), sphereCampaignReportHtml(eval, &csv, &m, vega_));
}

template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

TEST_F(SphereReport, RefusesWhatIsNotASphereCampaign) {
  SphereReportOptions o;
  o.evaluation_file = "ttp/cmm/evaluation.json";
  o.inputs_file = "run/inputs.csv";
  o.manifest_file = "ttp/plan/plan.json";
  // A thermal test piece's evaluation.
  json ttp = evaluation();
  ttp["kind"] = "thermal_test_piece";
  std::string w = refusal([&] { sphereCampaignReportHtml(ttp, nullptr, nullptr, vega_, o); });
  EXPECT_NE(w.find("ttp/cmm/evaluation.json"), std::string::npos) << w;
  EXPECT_NE(w.find("has kind \"thermal_test_piece\", expected \"sphere_artifact\""), std::string::npos) << w;
  EXPECT_NE(w.find("probeloop report ttp"), std::string::npos) << w;
  EXPECT_THROW(sphereCampaignReportHtml(json::array(), nullptr, nullptr, vega_), InputError);
  json no_cycles = evaluation();
  no_cycles.erase("cycles");
  EXPECT_THROW(sphereCampaignReportHtml(no_cycles, nullptr, nullptr, vega_), InputError);
  // Without "kind" (older files): accepted only with least_squares cycles.
  json old = evaluation();
  old.erase("kind");
  EXPECT_NO_THROW(sphereCampaignReportHtml(old, nullptr, nullptr, vega_));
  for (auto& c : old["cycles"]) c.erase("least_squares");
  EXPECT_THROW(sphereCampaignReportHtml(old, nullptr, nullptr, vega_), InputError);

  const json eval = evaluation();
  // Inputs without time_s, with no signal, or an error series.
  const std::string no_time = "t,T_env_C\n0,20\n";
  w = refusal([&] { sphereCampaignReportHtml(eval, &no_time, nullptr, vega_, o); });
  EXPECT_NE(w.find("run/inputs.csv:1:"), std::string::npos) << w;
  EXPECT_NE(w.find("no time_s column"), std::string::npos) << w;
  const std::string only_time = "time_s\n0\n60\n";
  w = refusal([&] { sphereCampaignReportHtml(eval, &only_time, nullptr, vega_, o); });
  EXPECT_NE(w.find("no signal column besides time_s"), std::string::npos) << w;
  const std::string errors = "time_s,cycle,EX0C_um,U_EX0C_um\n60,1,0,0\n";
  w = refusal([&] { sphereCampaignReportHtml(eval, &errors, nullptr, vega_, o); });
  EXPECT_NE(w.find("an error series"), std::string::npos) << w;
  const std::string bad_time = "time_s,T_env_C\n0,20\nx,21\n";
  w = refusal([&] { sphereCampaignReportHtml(eval, &bad_time, nullptr, vega_, o); });
  EXPECT_NE(w.find("run/inputs.csv:3"), std::string::npos) << w;

  // A manifest of another kind, or of fewer cycles than the evaluation holds.
  parts::PlanManifest m = manifest();
  m.kind = "thermal_test_piece";
  w = refusal([&] { sphereCampaignReportHtml(eval, nullptr, &m, vega_, o); });
  EXPECT_NE(w.find("ttp/plan/plan.json"), std::string::npos) << w;
  EXPECT_NE(w.find("expected \"sphere_artifact\""), std::string::npos) << w;
  m = manifest();
  m.cycles = 4;
  m.cycle_start_s.resize(4);
  w = refusal([&] { sphereCampaignReportHtml(eval, nullptr, &m, vega_, o); });
  EXPECT_NE(w.find("plans 4 cycles, the evaluation holds cycle 5"), std::string::npos) << w;
}

TEST_F(SphereReport, InlinesDebianVega) {
  if (!fs::is_directory(defaultVegaPath())) GTEST_SKIP() << "libjs-vega not installed";
  const std::string html = sphereCampaignReportHtml(evaluation(), nullptr, nullptr);
  EXPECT_NE(html.find("window.vega = vega;"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::report
