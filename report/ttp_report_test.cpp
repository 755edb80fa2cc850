#include "report/ttp_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "report/report_test_support.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using testing::count;
using testing::dataset;
using testing::spec;

// Hand-made evaluations in the schema of `probeloop evaluate` for a thermal test piece: the
// reference cut at t = 1200 s, one cycle per hour after it. A stand-in Vega bundle: these
// tests check the page the C++ writes; tests/integration/ttp_report_check.py renders it.
class TtpReport : public testing::PageTest {
 protected:
  TtpReport() : PageTest("ttp-report") {}
};

constexpr double kT0 = 1200.0;
constexpr double kHour = 3600.0;

json value(const std::string& q, const std::string& unit, double v, double U) {
  return {{"quantity", q},
          {"unit", unit},
          {"value", v},
          {"u_c", U / 2},
          {"nu_eff", 50},
          {"k", 2.0},
          {"U", U},
          {"contributions",
           json::array({{{"input", "probing"}, {"type", "B"}, {"distribution", "normal"}, {"basis", "MPE"},
                         {"u", U / 4}, {"dof", nullptr}},
                        {{"input", "alpha of the piece"}, {"type", "B"}, {"distribution", "rectangular"},
                         {"basis", "handbook"}, {"u", U / 3}, {"dof", 50}}})}};
}

// E_X = 0.5 c, E_Y = 2 c, E_Z = 3 c, E_B = -4 c, E_TTP = -2 c, dT = 0.5 c (c = cycle).
// `route`: cmm (all), on_machine (values + 0.25), gauge (no E_Z, no E_B).
json evaluation(const std::string& route) {
  const double shift = route == "on_machine" ? 0.25 : 0.0;
  json cycles = json::array();
  for (int c = 0; c <= 8; ++c) {
    json values = json::array({value("EX_um", "um", 0.5 * c + shift, 1.5), value("EY_um", "um", 2.0 * c + shift, 1.5)});
    if (route != "gauge") {
      if (c != 3) values.push_back(value("EZ_um", "um", 3.0 * c + shift, 1.25));  // cycle 3: Z3 not measured
      values.push_back(value("EB_urad", "urad", -4.0 * c, 12.0));
    }
    values.push_back(value("ETTP_um", "um", -2.0 * c + shift, 2.0));
    values.push_back(value("dT_K", "K", 0.5 * c, 0.25));
    cycles.push_back({{"cycle", c},
                      {"phase", c == 0 ? "reference" : c <= 4 ? "warm_up" : "hold"},
                      {"time_s", kT0 + c * kHour},
                      {"values", values},
                      {"also", {{"EX_printed_um", 10.0 + c}, {"EY_printed_um", 20.0 + c}, {"ETTP_7_9_um", -1.0 * c}}},
                      {"missing", c == 3 && route != "gauge" ? json::array({"Z3"}) : json::array()}});
  }
  json spans = json::array();
  for (const auto& [p, b] : std::vector<std::pair<int, int>>{{1, 1}, {4, 4}, {8, 8}})
    spans.push_back({{"period_h", p},
                     {"cycles", {0, b}},
                     {"values", json::array({{{"quantity", "EX_um"}, {"span", 0.5 * b}, {"U", 2.1}},
                                             {{"quantity", "ETTP_um"}, {"span", 2.0 * b}, {"U", 2.8}}})}});
  return {{"format", "probeloop-evaluation"},
          {"version", 1},
          {"kind", "thermal_test_piece"},
          {"manifest", "plan/plan.json"},
          {"input", {{"file", "run/" + route + ".csv"}, {"route", route}, {"format", "csv"}, {"points", 1234},
                     {"assigned_by", "id"}}},
          {"alignment", nullptr},
          {"point_scatter", {{"type_b_sigma_um", 0.5}, {"type_a_sigma_um", 0.72}, {"type_a_dof", 310}, {"used", "type A"}}},
          {"features", json::array()},
          {"cycles", cycles},
          {"spans", spans},
          {"comparison", nullptr},
          {"formulas", json::array({{{"output", "EX_um"},
                                     {"formula", "[(d_X2(t_i) - d_X2(t_0)) - (d_X1(t_i) - d_X1(t_0))] / 2"},
                                     {"source", "seed 004 Eq. 7.1 (sign corrected, notes \u00a711 item 10)"},
                                     {"features", "X1_k, X2_k"}}})}};
}

// R-test rows every half hour from the reference cut; E_R0T reaches 14.08 um at 4 h
// (-> 14.08 / (11 * 0.160) = 8.0 K), E_B0C = 10 urad per hour.
std::string rTestCsv(double first_s = kT0) {
  std::string s =
      "# probeloop location errors of the C axis, relative to cycle 1\n"
      "time_s,cycle,EX0C_um,EY0C_um,EZ0T_um,ER0T_um,EA0C_urad,EB0C_urad,EC0C_urad,U_EX0C_um,U_EY0C_um,U_EZ0T_um,"
      "U_ER0T_um,U_EA0C_urad,U_EB0C_urad,U_EC0C_urad\n";
  for (int i = 0; i <= 16; ++i) {
    const double h = i * 0.5;
    const double er = i == 8 ? 14.08 : 3.52 * h;
    char row[512];
    std::snprintf(row, sizeof row, "%.0f,%d,%g,%g,%g,%g,0,%g,0,1.1,1.1,1.2,0.88,3,3,2\n", first_s + h * kHour, i + 1,
                  0.4 * h, 1.9 * h, 2.8 * h, er, 10.0 * h);
    s += row;
  }
  return s;
}

std::vector<std::string> plotQuantities(const std::string& html) {
  std::vector<std::string> out;
  for (int k = 1;; ++k) {
    const json s = spec(html, k);
    if (s.is_null()) return out;
    out.push_back(s["usermeta"]["quantity"]);
  }
}

TEST_F(TtpReport, OnePlotPerQuantityWithTheEvaluationsValues) {
  const json cmm = evaluation("cmm"), om = evaluation("on_machine");
  const std::string html = thermalTestPieceReportHtml(cmm, &om, nullptr, vega_);
  EXPECT_EQ(plotQuantities(html), (std::vector<std::string>{"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"}));
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 6u);
  // Plot 2 (E_Y): both routes, every cycle, value and U as in the input.
  const json s = spec(html, 2);
  EXPECT_EQ(s["$schema"], "https://vega.github.io/schema/vega/v5.json");
  for (const auto& [name, eval] : std::vector<std::pair<std::string, const json*>>{{"route1", &cmm}, {"route2", &om}}) {
    const json values = dataset(s, name)["values"];
    ASSERT_EQ(values.size(), 9u) << name;
    for (int c = 0; c <= 8; ++c) {
      EXPECT_EQ(values[c]["time_s"], (*eval)["cycles"][c]["time_s"]);
      EXPECT_EQ(values[c]["cycle"], c);
      EXPECT_EQ(values[c]["value"], (*eval)["cycles"][c]["values"][1]["value"]);
      EXPECT_EQ(values[c]["U"], 1.5);
    }
  }
  EXPECT_EQ(s["usermeta"]["series"][0]["label"], "CMM");
  EXPECT_EQ(s["usermeta"]["series"][1]["label"], "on-machine (OM)");
  // Hours since the reference cut, error bars as rule marks from value - U to value + U.
  EXPECT_EQ(s["signals"][0]["name"], "t0_s");
  EXPECT_EQ(s["signals"][0]["value"], kT0);
  const std::string dumped = s.dump();
  EXPECT_NE(dumped.find("(datum.time_s - t0_s) / 3600"), std::string::npos);
  EXPECT_NE(dumped.find("datum.value - datum.U"), std::string::npos);
  bool rules = false;
  for (const auto& m : s["marks"])
    if (m["type"] == "rule" && m.contains("from") && m["from"]["data"] == "route1_U") rules = true;
  EXPECT_TRUE(rules);
  // E_TTP carries the Eq. 7.9 form of each route beside Eq. 7.3.
  const json ttp = spec(html, 5);
  ASSERT_TRUE(dataset(ttp, "route1_eq_7_9").is_object());
  EXPECT_EQ(dataset(ttp, "route1_eq_7_9")["values"][4]["value"], -4.0);
  // Eq. 7.9 is exactly half of Eq. 7.3 from the same facets: U is half of E_TTP's (2.0 / 2).
  EXPECT_EQ(dataset(ttp, "route1_eq_7_9")["values"][4]["U"], 1.0);
  // Render-error contract, SVG.
  EXPECT_NE(html.find("<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>"), std::string::npos);
  EXPECT_NE(html.find("renderer: 'svg'"), std::string::npos);
}

TEST_F(TtpReport, MissingValuesAreLeftOut) {
  const json cmm = evaluation("cmm");
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_);
  const json ez = spec(html, 3);
  ASSERT_EQ(ez["usermeta"]["quantity"], "EZ_um");
  const json values = dataset(ez, "route1")["values"];
  ASSERT_EQ(values.size(), 8u);  // cycle 3 has no E_Z
  for (const auto& v : values) EXPECT_NE(v["cycle"], 3);
  // In the table it is a dash, and the missing feature is named.
  EXPECT_NE(html.find("<td>Z3</td>"), std::string::npos);
  // The gauge route has no E_Z and no E_B: no plots for them.
  const json gauge = evaluation("gauge");
  EXPECT_EQ(plotQuantities(thermalTestPieceReportHtml(gauge, nullptr, nullptr, vega_)),
            (std::vector<std::string>{"EX_um", "EY_um", "ETTP_um", "dT_K"}));
  // A cycle whose value is null or not a number is left out, not drawn at 0.
  json broken = evaluation("gauge");
  broken["cycles"][2]["values"][0]["value"] = nullptr;
  broken["cycles"][5]["values"][0]["value"] = "x";
  broken["cycles"][6]["time_s"] = nullptr;
  const json ex = dataset(spec(thermalTestPieceReportHtml(broken, nullptr, nullptr, vega_), 1), "route1")["values"];
  EXPECT_EQ(ex.size(), 6u);
}

TEST_F(TtpReport, TablesShowValuesSpansBudgetsAndFormulas) {
  json cmm = evaluation("cmm");
  cmm["comparison"] = {{"against", "uncompensated/evaluation.json"},
                       {"rows", json::array({{{"period_h", 1}, {"quantity", "EY_um"}, {"this", 0.5}, {"other", 15.8},
                                              {"reduction_percent", 96.83}},
                                             {{"period_h", 4}, {"quantity", "EY_um"}, {"this", 1.6}, {"other", 27.3},
                                              {"reduction_percent", 94.14}}})}};
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_);
  // Every table but the inputs' in a scroll container: a wide one scrolls, nothing is cut off.
  EXPECT_EQ(count(html, "<div class=\"table-wrap\">\n<table"), count(html, "<table") - count(html, "<table class=\"meta\""));
  EXPECT_GE(count(html, "<div class=\"table-wrap\">\n<table"), 5u);
  // Units in the column names.
  for (const char* h : {"E_X \u00b1 U (\u00b5m)", "E_B \u00b1 U (\u00b5rad)", "\u0394T \u00b1 U (K)",
                        "E_X span \u00b1 U (\u00b5m)", "E_TTP, Eq. 7.9 \u00b1 U (\u00b5m)"})
    EXPECT_NE(html.find("<th class=\"num\">" + std::string(h) + "</th>"), std::string::npos) << h;
  // Cycle 4: hours:minutes since the reference cut, E_Y = 8.0 +- 1.5.
  EXPECT_NE(html.find("<td class=\"num\">4</td><td>warm-up</td><td class=\"num\">4:00</td><td class=\"num\">2.0 \u00b1 "
                      "1.5</td><td class=\"num\">8.0 \u00b1 1.5</td>"),
            std::string::npos);
  // Spans in Table 7.2's layout: one row per period; E_X's span 2.0 is within its U 2.1: n.s.
  EXPECT_NE(html.find("<tr><th>4:00 (cycles 0\u20134)</th><td class=\"num ns\">2.0 \u00b1 2.1 <span class=\"ns-mark\">"
                      "n.s.</span></td><td class=\"num\">8.0 \u00b1 2.8</td></tr>"),
            std::string::npos);
  // Comparison with reductions.
  EXPECT_NE(html.find("uncompensated/evaluation.json"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\">0.500</td><td class=\"num\">15.8</td><td class=\"num\">96.8</td>"),
            std::string::npos);
  // Largest contribution of E_Y in cycle 8: "alpha of the piece", u = U/3 = 0.5.
  EXPECT_NE(html.find("<tr><th>E_Y (\u00b5m)</th><td class=\"num\">8</td><td class=\"num\">16.0 \u00b1 1.5</td>"),
            std::string::npos);
  EXPECT_NE(html.find("<td>alpha of the piece</td><td>B</td><td>rectangular</td><td class=\"num\">0.50 \u00b5m</td>"),
            std::string::npos);
  EXPECT_NE(html.find("type A \u03c3 = 0.72 \u00b5m (\u03bd = 310), type B \u03c3 = 0.50 \u00b5m; used: type A"),
            std::string::npos);
  // Formulas with sources.
  // Formulas with the thesis's section and equation, not the evaluation's notes reference.
  EXPECT_NE(html.find("<td>Blaser 2020 (ETH Diss. 26709), Sec. 7.2, Eq. 7.1 (the sign of its last term corrected: see the "
                      "note on Eqs. 7.1 and 7.2)</td>"),
            std::string::npos);
}

TEST_F(TtpReport, RTestBesideTheRoutesWithSignAndTemperatureEquivalent) {
  const json cmm = evaluation("cmm");
  const std::string csv = rTestCsv();
  TtpReportOptions o;
  o.r_test_file = "rtest/errors.csv";
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, &csv, vega_, o);
  ASSERT_EQ(plotQuantities(html).size(), 6u);
  // E_X with E_X0C as given (the R-test starts at the reference cut: nothing to subtract).
  const json ex = dataset(spec(html, 1), "r_test")["values"];
  ASSERT_EQ(ex.size(), 17u);
  EXPECT_DOUBLE_EQ(ex[2]["value"].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(ex[2]["U"].get<double>(), 1.1);
  EXPECT_EQ(ex[2]["time_s"], kT0 + kHour);
  // E_B beside -E_B0C.
  const json eb = dataset(spec(html, 4), "r_test")["values"];
  EXPECT_DOUBLE_EQ(eb[4]["input"].get<double>(), 20.0);
  EXPECT_DOUBLE_EQ(eb[4]["value"].get<double>(), -20.0);
  EXPECT_DOUBLE_EQ(eb[4]["U"].get<double>(), 3.0);
  EXPECT_EQ(spec(html, 4)["usermeta"]["series"][0]["label"], "R-test \u2212E_B0C");
  // E_TTP has no R-test counterpart.
  EXPECT_TRUE(dataset(spec(html, 5), "r_test").is_null());
  // The table's temperature from E_R0T: 14.08 um / (11 um/(m K) * 0.160 m) = 8.0 K; U 0.88 -> 0.5 K.
  const json dt = dataset(spec(html, 6), "r_test")["values"];
  EXPECT_DOUBLE_EQ(dt[8]["input"].get<double>(), 14.08);
  EXPECT_NEAR(dt[8]["value"].get<double>(), 8.0, 1e-12);
  EXPECT_NEAR(dt[8]["U"].get<double>(), 0.5, 1e-12);
  EXPECT_NE(html.find("rtest/errors.csv"), std::string::npos);
  EXPECT_NE(html.find("\u03b1 = 11.0 \u00b5m/(m\u00b7K) and R = 160.0 mm"), std::string::npos);
  // Other alpha and radius.
  o.table_alpha_um_per_m_K = 22;
  o.r_test_radius_mm = 80;
  const json dt2 = dataset(spec(thermalTestPieceReportHtml(cmm, nullptr, &csv, vega_, o), 6), "r_test")["values"];
  EXPECT_NEAR(dt2[8]["value"].get<double>(), 14.08 / (22 * 0.080), 1e-12);
}

TEST_F(TtpReport, RTestIsReReferencedToTheReferenceCut) {
  const json cmm = evaluation("cmm");
  // The R-test starts 1 h before the reference cut: its values at the cut are subtracted.
  const std::string csv = rTestCsv(kT0 - kHour);
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, &csv, vega_);
  const json ex = dataset(spec(html, 1), "r_test")["values"];
  EXPECT_EQ(ex[2]["time_s"], kT0);
  EXPECT_NEAR(ex[2]["value"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(ex[0]["value"].get<double>(), -0.4, 1e-12);
  EXPECT_NEAR(ex[4]["value"].get<double>(), 0.4, 1e-12);
  // Half way between two rows: interpolated (E_Y0C 1.9 um/h, reference 0.25 h after a row).
  const std::string csv2 = rTestCsv(kT0 - 0.25 * kHour);
  const json ey = dataset(spec(thermalTestPieceReportHtml(cmm, nullptr, &csv2, vega_), 2), "r_test")["values"];
  EXPECT_NEAR(ey[0]["value"].get<double>(), -0.25 * 1.9, 1e-12);
  EXPECT_NE(html.find("re-referenced to its value at the reference cut"), std::string::npos);
  // Starting after the reference cut: drawn as given, and the page says so.
  const std::string late = rTestCsv(kT0 + 600);
  const std::string html3 = thermalTestPieceReportHtml(cmm, nullptr, &late, vega_);
  EXPECT_DOUBLE_EQ(dataset(spec(html3, 1), "r_test")["values"][2]["value"].get<double>(), 0.4);
  EXPECT_NE(html3.find("does not cover the reference cut"), std::string::npos);
}

const std::string kEvil = "</script><script>alert(\"x&y\")</script>";

TEST_F(TtpReport, EscapesEveryText) {
  json cmm = evaluation("cmm");
  cmm["input"]["route"] = "cmm" + kEvil;  // lands in headings, titles and a spec's usermeta
  cmm["manifest"] = kEvil;
  cmm["cycles"][1]["phase"] = kEvil;
  cmm["cycles"][3]["missing"] = json::array({kEvil});
  cmm["formulas"][0]["source"] = kEvil;
  cmm["cycles"][2]["values"][0]["contributions"][1]["input"] = kEvil;
  std::string csv = rTestCsv();
  TtpReportOptions o;
  o.evaluation_file = "eval" + kEvil;
  o.r_test_file = "r" + kEvil;
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, &csv, vega_, o);
  const std::size_t plots = 6;
  EXPECT_EQ(count(html, "<script"), plots + 3);  // hook, specs, runtime, renderer
  EXPECT_EQ(count(html, "</script"), plots + 3);
  EXPECT_EQ(html.find("alert(\"x"), std::string::npos);
  EXPECT_NE(html.find("&lt;/script&gt;&lt;script&gt;alert(&quot;x&amp;y&quot;)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(spec(html, 1)["usermeta"]["series"][1]["label"].get<std::string>().find(kEvil), std::string::npos);
}

// The reader's warnings (issue 34): a section naming file, line and what, escaped; none, and the
// page unchanged, without them.
TEST_F(TtpReport, InputWarningsOnlyWhenThereAreSome) {
  const json clean = evaluation("cmm");
  json warned = clean;
  warned["input_warnings"] = json::array({{{"file", "a" + kEvil + ".qif"}, {"line", 1068}, {"what", "WholePointSetId: no set 828; assigned 829"}}});
  const std::string plain = thermalTestPieceReportHtml(clean, nullptr, nullptr, vega_);
  const std::string html = thermalTestPieceReportHtml(warned, nullptr, nullptr, vega_);
  EXPECT_EQ(plain.find("Input warnings"), std::string::npos);
  EXPECT_NE(html.find("<h2>Input warnings</h2>"), std::string::npos);
  EXPECT_NE(html.find("line 1068: WholePointSetId: no set 828; assigned 829</li>"), std::string::npos) << html.substr(html.find("Input warnings"), 600);
  EXPECT_EQ(html.find("alert(\"x"), std::string::npos);
  // Everything else as the clean page: the section is the only difference.
  const std::size_t at = html.find("<section class=\"input-warnings\">");
  const std::size_t end = html.find("</section>\n", at) + 11;
  EXPECT_EQ(html.substr(0, at) + html.substr(end), plain);
}

TEST_F(TtpReport, IsDeterministic) {
  const json cmm = evaluation("cmm"), om = evaluation("on_machine");
  const std::string csv = rTestCsv();
  EXPECT_EQ(thermalTestPieceReportHtml(cmm, &om, &csv, vega_), thermalTestPieceReportHtml(cmm, &om, &csv, vega_));
}

TEST_F(TtpReport, SameRouteTwiceIsNumbered) {
  const json a = evaluation("cmm"), b = evaluation("cmm");
  const std::string html = thermalTestPieceReportHtml(a, &b, nullptr, vega_);
  EXPECT_EQ(spec(html, 1)["usermeta"]["series"][0]["label"], "CMM #1");
  EXPECT_EQ(spec(html, 1)["usermeta"]["series"][1]["label"], "CMM #2");
}

TEST_F(TtpReport, RefusesWhatIsNotAThermalTestPieceEvaluation) {
  json sphere = evaluation("cmm");
  sphere["kind"] = "sphere_artifact";
  TtpReportOptions o;
  o.evaluation_file = "eval/evaluation.json";
  try {
    thermalTestPieceReportHtml(sphere, nullptr, nullptr, vega_, o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("eval/evaluation.json"), std::string::npos) << w;
    EXPECT_NE(w.find("\"sphere_artifact\""), std::string::npos) << w;
    EXPECT_NE(w.find("expected \"thermal_test_piece\""), std::string::npos) << w;
  }
  EXPECT_THROW(thermalTestPieceReportHtml(json::array(), nullptr, nullptr, vega_), InputError);
  json no_cycles = evaluation("cmm");
  no_cycles.erase("cycles");
  EXPECT_THROW(thermalTestPieceReportHtml(no_cycles, nullptr, nullptr, vega_), InputError);
  const json cmm = evaluation("cmm");
  EXPECT_THROW(thermalTestPieceReportHtml(cmm, &sphere, nullptr, vega_), InputError);
  // An R-test file that is not an error series.
  const std::string not_errors = "time_s,T_env_C\n0,20\n";
  EXPECT_THROW(thermalTestPieceReportHtml(cmm, nullptr, &not_errors, vega_), InputError);
  const std::string no_time = "cycle,EX0C_um\n1,0\n";
  EXPECT_THROW(thermalTestPieceReportHtml(cmm, nullptr, &no_time, vega_), InputError);
}

// The page between two markers (the first occurrence of each).
std::string between(const std::string& html, const std::string& from, const std::string& to) {
  const std::size_t a = html.find(from);
  if (a == std::string::npos) return "";
  const std::size_t b = html.find(to, a);
  return html.substr(a, b == std::string::npos ? std::string::npos : b - a);
}

TEST_F(TtpReport, PrintedEquationsOnlyInTheNoteAndTheAppendix) {
  json cmm = evaluation("cmm");
  // Eq. 7.1 as printed keeps -d_X1(t0): about -97.5 mm on the shipped piece.
  for (auto& c : cmm["cycles"]) c["also"]["EX_printed_um"] = -97498.95;
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_);
  const std::size_t appendix = html.find("<section class=\"appendix\" id=\"appendix-printed\">");
  ASSERT_NE(appendix, std::string::npos);
  // The main tables (values, spans, budgets, formulas) hold neither the value nor the column.
  const std::string main_part = html.substr(0, appendix);
  EXPECT_EQ(main_part.find("-97498.95"), std::string::npos);
  EXPECT_EQ(main_part.find("as printed (\u00b5m)"), std::string::npos);
  const std::string values = between(html, "<section class=\"values\">", "</section>");
  EXPECT_EQ(values.find("printed"), std::string::npos) << values.substr(values.find("printed") - 200, 400);
  // The appendix lists it per cycle; the note shows the printed equation and why it is wrong.
  EXPECT_EQ(count(html.substr(appendix), "<td class=\"num\">-97498.95</td>"), 9u);
  const std::string note = between(html, "<section class=\"printed-forms\">", "</section>");
  EXPECT_NE(note.find("E_X(t_i) = [ d_X2(t_i) \u2212 d_X2(t_0) \u2212 d_X1(t_i) \u2212 d_X1(t_0) ] / 2"), std::string::npos);
  EXPECT_NE(note.find("does not cancel"), std::string::npos);
  EXPECT_NE(note.find("-97.50 mm here"), std::string::npos);
  // A value that is not half of Eq. 7.3 gets no U (not invented): cycle 2 altered.
  json odd = evaluation("cmm");
  odd["cycles"][2]["also"]["ETTP_7_9_um"] = -1.5;
  const json rows79 = dataset(spec(thermalTestPieceReportHtml(odd, nullptr, nullptr, vega_), 5), "route1_eq_7_9")["values"];
  EXPECT_TRUE(rows79[2]["U"].is_null());
  EXPECT_EQ(rows79[3]["U"], 1.0);
  // E_TTP by Eq. 7.9 is a form of the thesis, not a misprint: it stays in the main tables.
  EXPECT_NE(between(html, "<section class=\"values\">", "</section>").find("E_TTP, Eq. 7.9"), std::string::npos);
}

TEST_F(TtpReport, HoursAsHoursAndMinutes) {
  EXPECT_EQ(web::hoursMinutes(3633.0), "1:01");
  EXPECT_EQ(web::hoursMinutes(29100.0), "8:05");
  EXPECT_EQ(web::hoursMinutes(1.00927 * 3600), "1:01");
  EXPECT_EQ(web::hoursMinutes(-1800.0), "\u22120:30");
  EXPECT_EQ(web::hoursMinutes(0.0), "0:00");
  EXPECT_EQ(web::hoursMinutes(std::nullopt), web::kDash);
  json cmm = evaluation("cmm");
  cmm["spans"][0]["period_h"] = 1.00927;  // as the evaluation writes it: the cycles' real distance
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_);
  EXPECT_NE(html.find("<tr><th>1:01 (cycles 0\u20131)</th>"), std::string::npos);
  EXPECT_EQ(html.find("1.00927"), std::string::npos);
  EXPECT_NE(html.find("<td class=\"num\">8:00</td>"), std::string::npos);  // cycle 8
  // The plots' time axis is labelled h:mm too.
  EXPECT_EQ(spec(html, 1)["axes"][0]["title"], "time since the reference cut (h:mm)");
  EXPECT_TRUE(spec(html, 1)["axes"][0]["encode"]["labels"]["update"]["text"].contains("signal"));
}

TEST_F(TtpReport, NotSignificantValuesAreMarked) {
  json cmm = evaluation("cmm");
  cmm["cycles"][1]["values"][3]["value"] = -2.0;  // E_B -2 +- 11 urad (the review's example)
  cmm["cycles"][1]["values"][3]["U"] = 11.0;
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_);
  const std::string values = between(html, "<section class=\"values\">", "</section>");
  EXPECT_NE(values.find("<td class=\"num ns\">-2 \u00b1 11 <span class=\"ns-mark\">n.s.</span></td>"), std::string::npos);
  // Cycle 1's E_Y 2.0 +- 1.5 is significant: no class, no marker.
  EXPECT_NE(values.find("<td class=\"num\">2.0 \u00b1 1.5</td>"), std::string::npos);
  EXPECT_EQ(values.find("<td class=\"num ns\">2.0 \u00b1 1.5"), std::string::npos);
  // The legend says what it means, and the style makes it grey.
  EXPECT_NE(values.find("not significant, |value| \u2264 U (k = 2)"), std::string::npos);
  EXPECT_NE(html.find("td.ns, .ns { color: #8a8a8a; }"), std::string::npos);
  EXPECT_TRUE(web::notSignificant(-2.0, 11.0));
  EXPECT_TRUE(web::notSignificant(11.0, 11.0));
  EXPECT_FALSE(web::notSignificant(11.5, 11.0));
  EXPECT_FALSE(web::notSignificant(1.0, std::nullopt));
}

TEST_F(TtpReport, ReferencesAReaderCanFollow) {
  json cmm = evaluation("cmm");
  cmm["formulas"].push_back({{"output", "EQ_um"},
                             {"formula", "alpha dT E"},
                             {"source", "seed 004 Eq. 7.6 (notes/seed004.md \u00a74.4, L2111)"},
                             {"features", "-"}});
  // A budget line's basis as the evaluation writes it (evaluate/ttp_budget.cpp).
  for (auto& c : cmm["cycles"])
    for (auto& v : c["values"]) v["contributions"][1]["basis"] = "22 um/(m K) (seed 004 L2177): |dT| u(alpha) / alpha";
  const std::string csv = rTestCsv();
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, &csv, vega_);
  EXPECT_NE(html.find("<td>22 um/(m K): |dT| u(alpha) / alpha</td>"), std::string::npos);
  EXPECT_EQ(html.find("notes/seed"), std::string::npos);
  EXPECT_EQ(html.find("notes \u00a7"), std::string::npos);
  EXPECT_EQ(html.find("seed 004"), std::string::npos) << html.substr(html.find("seed 004") - 300, 400);
  const std::regex line_number(R"(\bL[0-9]{3,4}\b)");
  EXPECT_FALSE(std::regex_search(html, line_number)) << "a source-file line number in the page";
  EXPECT_NE(html.find("<td>Blaser 2020 (ETH Diss. 26709), Eq. 7.6</td>"), std::string::npos);
  EXPECT_NE(html.find("Blaser 2020 (ETH Diss. 26709), Sec. 7.3, Eq. 7.10"), std::string::npos);
}

// inputs.csv as `probeloop simulate` writes it: a sample every 10 min from 1 h before the
// reference cut to 1 h after the last cycle.
std::string inputsCsv() {
  std::string s = "# probeloop simulate: machine inputs\ntime_s,T_env_C,T_caxis_C,c_rpm,spindle_rpm,tool_changes\n";
  for (int i = -6; i <= 54; ++i) {
    const double t = kT0 + i * 600.0;
    char row[256];
    std::snprintf(row, sizeof row, "%.0f,%.2f,%.2f,%d,0,0\n", t, 20.0 + 0.01 * i, 21.0 + 0.1 * i, i >= 0 && i < 24 ? 1200 : 0);
    s += row;
  }
  return s;
}

TEST_F(TtpReport, TemperaturesAndCLoadFromTheMachinesInputs) {
  const json cmm = evaluation("cmm");
  TtpReportOptions o;
  o.inputs_csv_text = inputsCsv();
  o.inputs_file = "run/inputs.csv";
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_, o);
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 8u);  // 6 quantities, temperatures, C load
  const json t = spec(html, 7), c = spec(html, 8);
  ASSERT_TRUE(t.is_object());
  ASSERT_TRUE(c.is_object());
  EXPECT_EQ(t["usermeta"]["inputs"], "temperatures");
  EXPECT_EQ(t["usermeta"]["series"][0]["column"], "T_env_C");
  EXPECT_EQ(t["usermeta"]["series"][1]["column"], "T_caxis_C");
  // Over the errors' hours (0 to 8 h): the samples from 0 h to 8 h and one beyond each end.
  const json caxis = dataset(t, "temperature_2")["values"];
  ASSERT_EQ(caxis.size(), 51u);
  EXPECT_EQ(caxis[0]["time_s"], kT0 - 600.0);
  EXPECT_DOUBLE_EQ(caxis[1]["value"].get<double>(), 21.0);
  EXPECT_DOUBLE_EQ(caxis[7]["value"].get<double>(), 21.6);
  EXPECT_EQ(t["scales"][0]["domain"], json::array({0.0, 8.0}));
  EXPECT_EQ(c["usermeta"]["inputs"], "c_load");
  const json rpm = dataset(c, "c_rpm")["values"];
  EXPECT_EQ(rpm[1]["value"], 1200.0);
  EXPECT_EQ(rpm[25]["value"], 0.0);
  EXPECT_NE(c.dump().find("step-after"), std::string::npos);
  EXPECT_NE(html.find("<td>run/inputs.csv: T_env_C (\u00b0C), T_caxis_C (\u00b0C), c_rpm (rpm)</td>"), std::string::npos);
  // Without the inputs: no such plots.
  EXPECT_EQ(count(thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_), "class=\"vega-plot\""), 6u);
  // Inputs that are not a machine's log are refused, naming the file.
  o.inputs_csv_text = "cycle,EX0C_um\n1,0\n";
  EXPECT_THROW(thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_, o), InputError);
  o.inputs_csv_text = "time_s,spindle_rpm\n0,0\n";
  try {
    thermalTestPieceReportHtml(cmm, nullptr, nullptr, vega_, o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("run/inputs.csv"), std::string::npos) << e.what();
  }
}

TEST_F(TtpReport, InlinesDebianVega) {
  if (!fs::is_directory(defaultVegaPath())) GTEST_SKIP() << "libjs-vega not installed";
  const json cmm = evaluation("cmm");
  const std::string html = thermalTestPieceReportHtml(cmm, nullptr, nullptr);
  EXPECT_NE(html.find("window.vega = vega;"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::report
