#include "report/sw_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "core/error.hpp"
#include "report/report_test_support.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using testing::count;
using testing::dataset;
using testing::spec;

// Hand-made evaluations in the schema of `probeloop evaluate` for a stepped workpiece (W8,
// four steps). A stand-in Vega bundle: these tests check the page the C++ writes;
// tests/integration/sw_separation.py renders it in Chromium.
class SwReport : public testing::PageTest {
 protected:
  SwReport() : PageTest("sw-report") {}
};

json budget(double value, double u_c) {
  return {{"value", value},
          {"u_c", u_c},
          {"k", 2.0},
          {"U", 2 * u_c},
          {"contributions", json::array({{{"input", "probe repeatability"}, {"u", 0.6 * u_c}, {"basis", "s of repeats"}},
                                         {{"input", "CMM length measurement"}, {"u", 0.8 * u_c}, {"basis", "MPE"}}})}};
}

// Step k: width X error 2k um (CMM) and 2k - 1 (probe); e_pos_x u_c = 1.0, the CMM's u 0.8
// (so the probe's share is 0.6: U 1.2); wall tilt X 24.7 +- 479.4 urad (not resolved), Oz
// -153 +- 24 urad (resolved). `shift`: the compensated part's errors are smaller by it.
json evaluation(double shift = 0.0, bool with_before_after = false) {
  json cmm = json::array(), om = json::array(), sep = json::array();
  for (int k = 1; k <= 4; ++k) {
    const auto geometry = [&](double w) {
      return json{{"step", k},
                  {"width_x_error_um", w},
                  {"width_y_error_um", 1.5 * w},
                  {"depth_error_um", -0.5 * w},
                  {"wall_tilt_x_urad", 24.7},
                  {"U_wall_tilt_x_urad", 479.4},
                  {"wall_tilt_y_urad", -310.0},
                  {"U_wall_tilt_y_urad", 250.0},
                  {"floor_slope_x_urad", 30.6},
                  {"U_floor_slope_x_urad", 14.6},
                  {"floor_slope_y_urad", -5.0},
                  {"U_floor_slope_y_urad", 14.6},
                  {"oz_urad", -153.0},
                  {"U_oz_urad", 24.0}};
    };
    cmm.push_back(geometry(2.0 * k - shift));
    om.push_back(geometry(2.0 * k - 1.0 - shift));
    sep.push_back({{"step", k},
                   {"feed_mm_per_min", 100 * (1 << (k - 1))},
                   {"temp_state_min", 5.0 + 36 * (k - 1)},
                   {"travel_probe_mm", 20.0 * k + 4},
                   {"u_cmm_width_x_um", 0.8},
                   {"u_cmm_width_y_um", 0.9},
                   {"u_cmm_depth_um", 0.4},
                   {"e_pos_x_um", budget(1.0 + k - shift, 1.0)},
                   {"e_pos_y_um", budget(1.5 + k, 1.2)},
                   {"e_pos_z_um", budget(0.1, 0.5)},
                   {"e_proc_x_um", budget(0.5 * k, 0.6)},
                   {"e_proc_y_um", budget(0.6 * k, 0.6)},
                   {"e_splz_um", budget(3.0 * k - 2.5, 0.5)}});
  }
  json e = {{"format", "probeloop-evaluation"},
            {"kind", "stepped_workpiece"},
            {"experiment", "W8"},
            {"cmm", {{"file", "run/cmm_export.csv"}, {"route", "cmm"}, {"steps", cmm}}},
            {"on_machine", {{"file", "run/sw_probe.log"}, {"route", "on_machine"}, {"steps", om}}},
            {"probe_repeatability_um", 0.7},
            {"probe_repeat_pairs", 8},
            {"k_pos_x_um_per_mm", budget(0.181, 0.017)},
            {"k_pos_y_um_per_mm", budget(0.302, 0.017)},
            {"k_pos_z_um_per_mm", budget(0.04, 0.025)},
            {"separation", sep},
            {"notes", json::array({"e_pt of one part taken as 0"})}};
  if (with_before_after) {
    e["compared_with"] = "eval/evaluation.json";
    json ba = json::array();
    for (int k = 1; k <= 4; ++k)
      for (const auto& [q, before] : std::vector<std::pair<std::string, double>>{
               {"width_x", 2.0 * k}, {"width_y", 3.0 * k}, {"depth", -1.0 * k}})
        ba.push_back({{"step", k}, {"quantity", q}, {"before_um", before}, {"after_um", before - shift},
                      {"fall_um", shift}, {"promised_um", shift}, {"U_promised_um", 1.5}});
    e["before_after"] = ba;
  }
  return e;
}

std::string between(const std::string& html, const std::string& from, const std::string& to) {
  const std::size_t a = html.find(from);
  if (a == std::string::npos) return "";
  return html.substr(a, html.find(to, a) - a);
}

TEST_F(SwReport, WidthAndDepthErrorsCarryTheirU) {
  const json plain = evaluation();
  const std::string html = steppedWorkpieceReportHtml(plain, "eval/evaluation.json", vega_);
  const std::string geometry = between(html, "<table class=\"geometry\">", "</table>");
  // CMM, step 2: width X 4.0 +- 2 x 0.8; width Y 6.0 +- 2 x 0.9; depth -2.0 +- 2 x 0.4.
  EXPECT_NE(geometry.find("<tr><td>CMM</td><td>2</td><td class=\"num\">4.0 \u00b1 1.6</td><td class=\"num\">6.0 \u00b1 "
                          "1.8</td><td class=\"num\">-2.00 \u00b1 0.80</td></tr>"),
            std::string::npos)
      << geometry;
  // On the machine, step 2: the probe's share of e_pos's u_c: sqrt(1.0^2 - 0.8^2) = 0.6 -> U 1.2;
  // Y: sqrt(1.2^2 - 0.9^2) = 0.794 -> 1.6; depth: sqrt(0.5^2 - 0.4^2) = 0.3 -> 0.6.
  EXPECT_NE(geometry.find("<tr><td>on the machine</td><td>2</td><td class=\"num\">3.0 \u00b1 1.2</td><td class=\"num\">4.5 "
                          "\u00b1 1.6</td><td class=\"num\">-1.50 \u00b1 0.60</td></tr>"),
            std::string::npos)
      << geometry;
}

TEST_F(SwReport, TiltsWithinTheirUAreNotResolvedAndOzIsExplained) {
  const std::string html = steppedWorkpieceReportHtml(evaluation(), "eval/evaluation.json", vega_);
  const std::string orient = between(html, "<table class=\"orientations\">", "</table>");
  // 24.7 +- 479.4 urad: not resolved; -310 +- 250: resolved; Oz -153 +- 24: resolved.
  EXPECT_EQ(count(orient, "<td class=\"num ns\">25 \u00b1 479 <span class=\"ns-mark\">not resolved</span></td>"), 8u);
  EXPECT_EQ(count(orient, "<td class=\"num\">-310 \u00b1 250</td>"), 8u);
  EXPECT_EQ(count(orient, "<td class=\"num\">-153 \u00b1 24</td>"), 8u);
  EXPECT_EQ(orient.find("-153 \u00b1 24 <span"), std::string::npos);
  // The sentence that says what "not resolved" means, and Oz in words.
  EXPECT_NE(html.find("the part cannot tell the angle from zero"), std::string::npos);
  EXPECT_NE(html.find("the angle between the X walls' normal and the Y walls' normal minus 90\u00b0"), std::string::npos);
  // Components: e_proc_x of step 1, 0.5 +- 1.2, is not significant; e_splz of step 4, 9.5 +- 1.0, is.
  const std::string comp = between(html, "<table class=\"components\">", "</table>");
  EXPECT_NE(comp.find("<td class=\"num ns\">0.5 \u00b1 1.2 <span class=\"ns-mark\">n.s.</span></td>"), std::string::npos);
  EXPECT_NE(comp.find("<td class=\"num\">9.5 \u00b1 1.0</td></tr>"), std::string::npos);
}

TEST_F(SwReport, EveryTableIsInsideAScrollContainer) {
  const std::string html = steppedWorkpieceReportHtml(evaluation(), "eval/evaluation.json", vega_, nullptr, "");
  const std::size_t tables = count(html, "<table");
  EXPECT_GE(tables, 4u);
  EXPECT_EQ(count(html, "<div class=\"table-wrap\">\n<table"), tables);
  EXPECT_NE(html.find(".table-wrap { max-width: 100%; overflow-x: auto;"), std::string::npos);
  // The old widest table (geometry and orientations, 10 columns) is two tables now.
  EXPECT_EQ(between(html, "<table class=\"geometry\">", "</table>").find("tilt"), std::string::npos);
}

TEST_F(SwReport, PlainAndCompensatedPartsSideBySide) {
  const json plain = evaluation(), comp = evaluation(0.25, true);
  const std::string html = steppedWorkpieceReportHtml(plain, "eval/evaluation.json", vega_, &comp, "eval-c/evaluation.json");
  // The plain part's components first, labelled, then the compensated part's.
  const std::string table = between(html, "<table class=\"components\">", "</table>");
  const std::size_t a = table.find("<tr><td>uncompensated</td><td>1</td>"),
                    b = table.find("<tr><td>compensated</td><td>1</td>");
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  EXPECT_LT(a, b);
  // The plain part's e_pos_x of step 2 is 3.0 +- 2.0, as evaluate printed it; of step 1 2.0 +- 2.0 (n.s.); the
  // compensated part's 1.75.
  EXPECT_NE(table.find("<tr><td>uncompensated</td><td>2</td><td class=\"num\">200.0</td><td class=\"num\">41.0</td><td "
                       "class=\"num\">3.0 \u00b1 2.0</td>"),
            std::string::npos)
      << table.substr(0, 1500);
  EXPECT_NE(table.find("<td class=\"num ns\">1.8 \u00b1 2.0 <span class=\"ns-mark\">n.s.</span></td>"), std::string::npos);
  // Both parts in the plots: e_pos has four series, the compensated ones open.
  const json epos = spec(html, 1);
  EXPECT_EQ(epos["usermeta"]["series"][2]["label"], "compensated: e_pos_x");
  EXPECT_EQ(dataset(epos, "e_pos_x_um")["values"][0]["value"], 2.0);
  EXPECT_EQ(dataset(epos, "e_pos_x_um_compensated")["values"][0]["value"], 1.75);
  EXPECT_EQ(epos["legends"][0]["columns"], 2);  // eight entries in two columns, not one row past the page
  // Before/after: before +- U from the plain part (2 x 0.8), after +- U from the compensated one.
  const json ba = spec(html, 4);
  ASSERT_TRUE(ba.is_object());
  const json rows = dataset(ba, "features")["values"];
  ASSERT_EQ(rows.size(), 12u);
  EXPECT_EQ(rows[0]["feature"], "S1 width_x");
  EXPECT_DOUBLE_EQ(rows[0]["U_before"].get<double>(), 1.6);
  EXPECT_DOUBLE_EQ(rows[0]["U_after"].get<double>(), 1.6);
  EXPECT_DOUBLE_EQ(rows[2]["U_before"].get<double>(), 0.8);  // depth: 2 x 0.4
  bool before_bars = false, after_bars = false;
  for (const auto& m : ba["marks"]) {
    before_bars |= m.value("name", "") == "before_error_bars" && m["from"]["data"] == "before_U";
    after_bars |= m.value("name", "") == "after_error_bars" && m["from"]["data"] == "after_U";
  }
  EXPECT_TRUE(before_bars);
  EXPECT_TRUE(after_bars);
  // The table: before, after and fall each with U (fall: hypot(1.6, 1.6) = 2.26).
  EXPECT_NE(html.find("<tr><td>S1 width_x</td><td class=\"num\">2.0 \u00b1 1.6</td><td class=\"num\">1.8 \u00b1 1.6</td><td "
                      "class=\"num ns\">0.2 \u00b1 2.3 <span class=\"ns-mark\">n.s.</span></td>"),
            std::string::npos);
}

TEST_F(SwReport, ACompensatedPartComparedWithAnotherPartIsRefused) {
  const json plain = evaluation(0.5);  // not the part the compensated one was compared with
  const json comp = evaluation(0.25, true);
  try {
    steppedWorkpieceReportHtml(plain, "eval/evaluation.json", vega_, &comp, "eval-c/evaluation.json");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("eval-c/evaluation.json"), std::string::npos) << e.what();
  }
  // One without a before/after cannot be the compensated part.
  const json no_ba = evaluation();
  EXPECT_THROW(steppedWorkpieceReportHtml(evaluation(), "a.json", vega_, &no_ba, "b.json"), InputError);
  EXPECT_THROW(steppedWorkpieceReportHtml(json::array(), "a.json", vega_), InputError);
}

TEST_F(SwReport, TheCompensatedPartAloneStillWorks) {
  const json comp = evaluation(0.25, true);
  const std::string html = steppedWorkpieceReportHtml(comp, "eval-c/evaluation.json", vega_);
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 4u);
  const json rows = dataset(spec(html, 4), "features")["values"];
  EXPECT_TRUE(rows[0]["U_before"].is_null());  // not in this file: no bar, not invented
  EXPECT_DOUBLE_EQ(rows[0]["U_after"].get<double>(), 1.6);
}

TEST_F(SwReport, ReferencesWithoutLineNumbersEscapedAndDeterministic) {
  json plain = evaluation();
  plain["notes"] = json::array({"</script><script>alert(1)</script>"});
  const std::string html = steppedWorkpieceReportHtml(plain, "eval/<b>.json", vega_);
  EXPECT_FALSE(std::regex_search(html, std::regex(R"(\bL[0-9]{3,4}\b)")));
  EXPECT_EQ(html.find("seed 000"), std::string::npos);
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_NE(html.find("eval/&lt;b&gt;.json"), std::string::npos);
  EXPECT_EQ(html, steppedWorkpieceReportHtml(plain, "eval/<b>.json", vega_));
}

}  // namespace
}  // namespace probeloop::report
