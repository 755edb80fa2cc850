#include "report/model_report.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "report/report_test_support.hpp"
#include "model/verdict_strength.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using testing::count;
using testing::dataset;
using testing::spec;

// A stand-in Vega bundle (one file): these tests check the page the C++ writes; that Vega
// really draws it is tests/integration/html_render.py's job, in headless Chromium.
class ModelReport : public testing::PageTest {
 protected:
  ModelReport() : PageTest("model-report") {}
};

json indicators(double rmse, double smape, double pv, double p99, int n) {
  return {{"n", n}, {"rmse", rmse}, {"smape_percent", smape}, {"pv_ratio_percent", pv}, {"p99", p99}};
}

json channel(const std::string& name, bool with_before) {
  json c{{"channel", name}, {"unit", "um"}, {"u_measurement", 1.1}, {"sigma", 0.31}};
  c["effects"] = json::array(
      {{{"id", "offset"}, {"kind", "offset"}, {"input", nullptr}, {"just_added", false},
        {"parameters", json::array({{{"name", "c"}, {"value", 0.12}, {"u", 0.05}, {"unit", "um"}}})}},
       {{"id", "lag(c_rpm)"}, {"kind", "lag"}, {"input", "c_rpm"}, {"just_added", with_before},
        {"parameters", json::array({{{"name", "k"}, {"value", 0.017}, {"u", 0.0004}, {"unit", "um/rpm"}},
                                    {{"name", "tau"}, {"value", 2400}, {"u", 80}, {"unit", "s"}}})}}});
  c["indicators"] = {{"training", indicators(0.3, 12.1, 8.0, 0.8, 4)},
                     {"validation", indicators(0.35, 14.0, 9.1, 0.9, 2)}};
  json series{{"time_s", {0, 3600, 7200, 10800, 14400, 18000}},
              {"measured", {0.5, 1.25, 2.75, 3.5, 4.125, nullptr}},
              {"predicted", {0.625, 1.5, 2.5, 3.375, 4.0, 4.5}},
              {"U", {2.2, 2.2, 2.2, 2.2, 2.2, 2.2}}};
  if (with_before) {
    c["before"] = {{"effects", {"offset"}},
                   {"indicators", {{"training", indicators(3.0, 80.0, 60.0, 5.0, 4)},
                                   {"validation", indicators(3.1, 90.0, 70.0, 5.5, 2)}}}};
    series["predicted_before"] = {2.0, 2.0, 2.0, 2.0, 2.0, 2.0};
  } else {
    c["before"] = nullptr;
    series["predicted_before"] = nullptr;
  }
  c["series"] = series;
  return c;
}

json fitJson(bool with_before) {
  return {{"kind", "probeloop model fit"},
          {"model", "m.yaml"},
          {"inputs", "inputs.csv"},
          {"errors", "errors.csv"},
          {"training", {{"from_s", 0}, {"to_s", 10800}, {"samples", 4}}},
          {"validation", {{"from_s", 14400}, {"to_s", 18000}, {"samples", 2}}},
          {"channels", json::array({channel("EY0C_um", with_before), channel("EZ0T_um", false)})}};
}

const std::string kEvil = "</script><script>alert(\"x&y\")</script>";

json diagnosisJson() {
  json d{{"kind", "probeloop model diagnose"}, {"verdict", "missing"}, {"message", "The residual of EY0C <b>drifts</b>."}};
  d["channels"] = json::array(
      {{{"channel", "EY0C_um"},
        {"unit", "um"},
        {"u_measurement", 1.1},
        {"rms_residual", {{"training", 2.0}, {"validation", 3.1}}},
        {"ljung_box", {{"Q", 812.0}, {"lags", 20}, {"p", 0.0}}},
        {"white", false},
        {"within", false},
        {"windows", json::array({{{"from_s", 3600}, {"to_s", 9000}, {"peak", 5.2}, {"samples", 12}}})},
        {"cross_correlation", json::array({{{"input", "T_env_C"}, {"lag_s", 600}, {"r", 0.2}, {"significant", false}},
                                           {{"input", "c_rpm"}, {"lag_s", 2400}, {"r", -0.81}, {"significant", true}}})}}});
  d["candidates"] = json::array(
      {{{"rank", 1},
        {"effect", "lag"},
        {"input", "c_rpm"},
        {"sentence", "EY0C_um residuals follow c_rpm " + kEvil},
        {"command", "probeloop model add lag --input c_rpm --channels EY0C_um --model m.yaml"},
        {"channels", json::array({{{"channel", "EY0C_um"},
                                   {"validation_rmse_before", 3.1},
                                   {"validation_rmse_after", 0.4},
                                   {"mdl_before", 1.2},
                                   {"mdl_after", -1.0},
                                   {"parameters", json::array({{{"name", "tau"}, {"value", 2400}, {"u", 80}, {"unit", "s"}}})}}})}}});
  return d;
}

// The Vega spec of plot k, parsed back from its <script type="application/json">.
TEST_F(ModelReport, OneVegaSpecPerPlotCarryingTheInputValues) {
  const json fit = fitJson(true);
  const std::string html = modelReportHtml(fit, nullptr, vega_);
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 4u);  // two per channel
  EXPECT_EQ(count(html, "<script type=\"application/json\""), 4u);
  for (int k = 1; k <= 4; ++k) {
    const json s = spec(html, k);
    ASSERT_TRUE(s.is_object()) << "plot " << k;
    EXPECT_NE(html.find("<div class=\"vega-plot\" id=\"plot-" + std::to_string(k) + "\">"), std::string::npos);
    EXPECT_EQ(s["$schema"], "https://vega.github.io/schema/vega/v5.json");
    const json values = dataset(s, "series")["values"];
    const json& series = fit["channels"][(k - 1) / 2]["series"];
    ASSERT_EQ(values.size(), 6u);
    for (std::size_t i = 0; i < 6; ++i) {
      EXPECT_EQ(values[i]["time_s"], series["time_s"][i]);
      EXPECT_EQ(values[i]["measured"], series["measured"][i]);  // null stays null
      EXPECT_EQ(values[i]["predicted"], series["predicted"][i]);
      EXPECT_EQ(values[i]["U"], series["U"][i]);
    }
  }
  // Plot 1 (EY0C, with before): the dashed "before" line over its own data.
  const json p1 = spec(html, 1);
  EXPECT_EQ(dataset(p1, "series")["values"][0]["before"], 2.0);
  EXPECT_TRUE(dataset(p1, "before").is_object());
  bool dashed = false;
  for (const auto& m : p1["marks"])
    if (m["type"] == "line" && m["encode"]["enter"].contains("strokeDash")) dashed = true;
  EXPECT_TRUE(dashed);
  // Plot 2: residual and band are formulas over the input values.
  const std::string p2 = spec(html, 2).dump();
  EXPECT_NE(p2.find("datum.measured - datum.predicted"), std::string::npos);
  EXPECT_NE(p2.find("-datum.U"), std::string::npos);
  // Plot 3 (EZ0T, before = null): no before data, no dashed line.
  const json p3 = spec(html, 3);
  EXPECT_TRUE(dataset(p3, "before").is_null());
  EXPECT_FALSE(dataset(p3, "series")["values"][0].contains("before"));
  // Time in hours, SVG rendering, the error box.
  EXPECT_NE(p2.find("datum.time_s / 3600"), std::string::npos);
  EXPECT_NE(html.find("renderer: 'svg'"), std::string::npos);
  EXPECT_NE(html.find("<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>"), std::string::npos);
}

// Index of the mark named `name` in a spec's marks (drawing order), -1 when absent.
int markIndex(const json& spec, const std::string& name) {
  for (std::size_t i = 0; i < spec["marks"].size(); ++i)
    if (spec["marks"][i].value("name", "") == name) return static_cast<int>(i);
  return -1;
}

TEST_F(ModelReport, ModelLineIsDrawnOverThePointsAndEachPointCarriesItsU) {
  const std::string html = modelReportHtml(fitJson(true), nullptr, vega_);
  const json p1 = spec(html, 1);
  const int band = markIndex(p1, "band_area"), bars = markIndex(p1, "error_bar_rules"), points = markIndex(p1, "measured_points"),
            model = markIndex(p1, "model_line"), label = markIndex(p1, "validation_label");
  ASSERT_GE(band, 0);
  ASSERT_GE(bars, 0);
  ASSERT_GE(points, 0);
  ASSERT_GE(model, 0);
  // SVG paints in document order: the later mark lies on top.
  EXPECT_LT(band, bars);
  EXPECT_LT(bars, points);
  EXPECT_LT(points, model);
  EXPECT_EQ(label, static_cast<int>(p1["marks"].size()) - 1);
  // The model line is wider than the points' size suggests and not the points' colour.
  const json& line = p1["marks"][model]["encode"]["enter"];
  const json& dots = p1["marks"][points]["encode"]["enter"];
  EXPECT_GE(line["strokeWidth"]["value"].get<double>(), 2.0);
  EXPECT_NE(line["stroke"]["value"], dots["fill"]["value"]);
  // The bars run from measured − U to measured + U of each row, U being the input's value.
  const json bar_data = dataset(p1, "error_bars");
  ASSERT_TRUE(bar_data.is_object());
  EXPECT_EQ(bar_data["source"], "series");
  EXPECT_NE(bar_data.dump().find("datum.measured - datum.U"), std::string::npos);
  EXPECT_NE(bar_data.dump().find("datum.measured + datum.U"), std::string::npos);
  EXPECT_EQ(p1["marks"][bars]["encode"]["enter"]["y"]["field"], "U_lo");
  EXPECT_EQ(p1["marks"][bars]["encode"]["enter"]["y2"]["field"], "U_hi");
  EXPECT_EQ(dataset(p1, "series")["values"][2]["U"], 2.2);
  // The y scale reaches the ends of the bars, so no bar is cut.
  EXPECT_NE(p1.dump().find("{\"data\":\"error_bars\",\"field\":\"U_hi\"}"), std::string::npos);
  // The residual plot: its label too comes last, and its points over the band.
  const json p2 = spec(html, 2);
  EXPECT_LT(markIndex(p2, "band_area"), markIndex(p2, "residual_points"));
  EXPECT_EQ(markIndex(p2, "validation_label"), static_cast<int>(p2["marks"].size()) - 1);
}

TEST_F(ModelReport, MarkNamesDifferFromDataSetNames) {
  // Vega makes a data set of each named mark: a mark named like a data set is a parse error.
  const std::string html = modelReportHtml(fitJson(true), nullptr, vega_);
  for (int k = 1; k <= 4; ++k) {
    const json s = spec(html, k);
    for (const auto& m : s["marks"]) {
      if (m.contains("name")) {
        EXPECT_TRUE(dataset(s, m["name"]).is_null()) << "plot " << k << ": " << m["name"];
      }
    }
  }
}

TEST_F(ModelReport, ValidationLabelIsCentredOverItsWindowAndNeverClipped) {
  const json p1 = spec(modelReportHtml(fitJson(false), nullptr, vega_), 1);
  const json& label = p1["marks"][markIndex(p1, "validation_label")];
  EXPECT_EQ(label["clip"], false);
  EXPECT_EQ(label["encode"]["enter"]["align"]["value"], "center");
  EXPECT_NE(label["encode"]["enter"]["x"]["signal"].get<std::string>().find("datum.to_h"), std::string::npos);
  // autosize "pad": the view grows to hold any mark that reaches beyond width × height.
  EXPECT_EQ(p1["autosize"]["type"], "pad");
}

TEST_F(ModelReport, ManyPointsAreSmallerAndTranslucent) {
  json fit = fitJson(false);
  json& series = fit["channels"][0]["series"];
  series = {{"time_s", json::array()}, {"measured", json::array()}, {"predicted", json::array()}, {"U", json::array()}};
  for (int i = 0; i < 616; ++i) {
    series["time_s"].push_back(60.0 * i);
    series["measured"].push_back(0.01 * i);
    series["predicted"].push_back(0.01 * i);
    series["U"].push_back(2.2);
  }
  const std::string html = modelReportHtml(fit, nullptr, vega_);
  const json many = spec(html, 1)["marks"][markIndex(spec(html, 1), "measured_points")]["encode"]["enter"];
  const json few = spec(html, 3)["marks"][markIndex(spec(html, 3), "measured_points")]["encode"]["enter"];  // EZ0T: 5 points
  EXPECT_LT(many["size"]["value"].get<double>(), few["size"]["value"].get<double>());
  EXPECT_LT(many["fillOpacity"]["value"].get<double>(), few["fillOpacity"]["value"].get<double>());
}

TEST_F(ModelReport, AChannelWithoutUSaysSoInsteadOfDrawingNoBars) {
  json fit = fitJson(false);
  fit["channels"][0]["series"]["U"] = nullptr;
  const std::string html = modelReportHtml(fit, nullptr, vega_);
  EXPECT_EQ(markIndex(spec(html, 1), "error_bar_rules"), -1);
  EXPECT_NE(html.find("the input holds no U for EY0C, so the points have no error bars"), std::string::npos);
  EXPECT_GE(markIndex(spec(html, 3), "error_bar_rules"), 0);  // EZ0T still has its U
}

TEST(PValueText, BelowOneInTenThousandIsABoundNeverZero) {
  EXPECT_EQ(model::pValueText(0.0), "< 1e-4");
  EXPECT_EQ(model::pValueText(3e-7), "< 1e-4");
  EXPECT_EQ(model::pValueText(0.012), "0.012");
  EXPECT_EQ(model::pValueText(1e-4), "0.0001");
  EXPECT_EQ(model::pValueText(0.5), "0.5");
  EXPECT_EQ(model::pValueClause(0.0), "p < 1e-4");
  EXPECT_EQ(model::pValueClause(0.012), "p = 0.012");
}

TEST_F(ModelReport, LjungBoxPOfZeroIsPrintedAsABound) {
  const json d = diagnosisJson();  // p = 0 in the input
  const std::string html = modelReportHtml(fitJson(true), &d, vega_);
  EXPECT_NE(html.find("Ljung\u2013Box p</th><td class=\"num\">&lt; 1e-4</td>"), std::string::npos);
  EXPECT_EQ(html.find("Ljung\u2013Box p</th><td class=\"num\">0</td>"), std::string::npos);
}

TEST(WeakVerdict, SentenceFromTwiceTheResidualOn) {
  // u = 1.0 against RMS 0.5: exactly 2x.
  EXPECT_EQ(model::weakVerdictSentence(1.0, 0.5, "um"),
            "the measurement's uncertainty (u = 1 um) is 2.0\u00d7 the residual (RMS 0.5 um): the model cannot be judged "
            "finer than u.");
  EXPECT_EQ(model::weakVerdictSentence(1.0, 0.51, "um"), "");
  EXPECT_EQ(model::weakVerdictSentence(1.0, 3.0, "um"), "");
  EXPECT_NE(model::weakVerdictSentence(1.0, 0.0, "um").find("> 1000\u00d7"), std::string::npos);
  EXPECT_EQ(model::ratioText(model::uOverResidual(1.1, 0.35)), "3.1");
  EXPECT_EQ(model::ratioText(model::uOverResidual(25, 2)), "12");
}

TEST_F(ModelReport, StatesTheVerdictsStrengthWhereUDwarfsTheResidual) {
  // Fit channels: u = 1.1 µm, validation RMSE 0.35 µm: u is 3.1x the residual.
  const json d = diagnosisJson();  // EY0C: u = 1.1 µm against a validation RMS of 3.1 µm: 0.35x
  const std::string html = modelReportHtml(fitJson(true), &d, vega_);
  EXPECT_NE(html.find("u / validation RMSE = 3.1"), std::string::npos);
  const std::string sentence =
      "the measurement&#39;s uncertainty (u = 1.1 \u00b5m) is 3.1\u00d7 the residual (RMS 0.35 \u00b5m): the model "
      "cannot be judged finer than u.";
  EXPECT_EQ(count(html, sentence), 2u);  // EY0C's and EZ0T's fit summaries
  // The diagnosis of EY0C: the ratio is shown, the sentence is not (u < 2x the residual).
  EXPECT_NE(html.find("u / RMS residual (validation)</th><td class=\"num\">0.4</td>"), std::string::npos);
  EXPECT_NE(html.find("RMS residual (validation) within 1.5 u"), std::string::npos);
  EXPECT_EQ(count(html, "is 0.4\u00d7 the residual"), 0u);
  EXPECT_EQ(count(html, "Weak verdict"), 2u);
}

TEST_F(ModelReport, TablesShowIndicatorsBeforeAfterParametersAndUnits) {
  const std::string html = modelReportHtml(fitJson(true), nullptr, vega_);
  EXPECT_NE(html.find("<th class=\"num\">RMSE (\u00b5m)</th>"), std::string::npos);
  EXPECT_NE(html.find("<th class=\"num\">SMAPE (%)</th>"), std::string::npos);
  EXPECT_NE(html.find("<th class=\"num\">PV ratio (%)</th>"), std::string::npos);
  EXPECT_NE(html.find("<th class=\"num\">P99 (\u00b5m)</th>"), std::string::npos);
  // EY0C: validation RMSE 3.1 before, 0.35 after.
  EXPECT_NE(html.find("<span class=\"before\">3.10</span> \u2192 0.350"), std::string::npos);
  EXPECT_NE(html.find("2400 \u00b1 80"), std::string::npos);
  EXPECT_NE(html.find("0.01700 \u00b1 0.00040"), std::string::npos);
  EXPECT_NE(html.find("\u00b5m/rpm"), std::string::npos);
  EXPECT_NE(html.find("just added"), std::string::npos);
  EXPECT_NE(html.find("m.yaml"), std::string::npos);
  EXPECT_NE(html.find("0.00 \u2013 3.00 h (4 samples)"), std::string::npos);
}

TEST_F(ModelReport, DiagnosisVerdictCandidatesAndChannelDetails) {
  const json d = diagnosisJson();
  const std::string html = modelReportHtml(fitJson(true), &d, vega_);
  EXPECT_NE(html.find("an effect is missing from the model"), std::string::npos);
  EXPECT_NE(html.find("The residual of EY0C &lt;b&gt;drifts&lt;/b&gt;."), std::string::npos);
  EXPECT_NE(html.find("<pre><code>probeloop model add lag --input c_rpm --channels EY0C_um --model m.yaml</code></pre>"),
            std::string::npos);
  EXPECT_NE(html.find("<span class=\"before\">3.10</span> \u2192 0.400 \u00b5m"), std::string::npos);
  EXPECT_NE(html.find("<span class=\"before\">1.20</span> \u2192 -1.00"), std::string::npos);
  EXPECT_NE(html.find("tau = 2400 \u00b1 80 s"), std::string::npos);
  EXPECT_NE(html.find("Ljung\u2013Box Q (20 lags)</th><td class=\"num\">812.0</td>"), std::string::npos);
  // Cross-correlations, strongest |r| first.
  EXPECT_LT(html.find("<td>c_rpm</td>"), html.find("<td>T_env_C</td>"));
  EXPECT_NE(html.find("-0.81"), std::string::npos);
  // The window beyond U, in hours.
  EXPECT_NE(html.find("<td class=\"num\">1.00</td><td class=\"num\">2.50</td><td class=\"num\">5.20</td>"),
            std::string::npos);
}

TEST_F(ModelReport, EscapesEveryTextSoNoInputOpensOrClosesAScript) {
  json fit = fitJson(true);
  fit["model"] = "m" + kEvil + ".yaml";
  fit["channels"][1]["channel"] = "EZ0T" + kEvil;  // lands in headings and in a Vega spec
  const json d = diagnosisJson();
  const std::string html = modelReportHtml(fit, &d, vega_);
  const int plots = 4;
  // Our own scripts only: the error hook, one spec per plot, the Vega runtime, the renderer.
  EXPECT_EQ(count(html, "<script"), static_cast<std::size_t>(plots + 3));
  EXPECT_EQ(count(html, "</script"), static_cast<std::size_t>(plots + 3));
  EXPECT_EQ(html.find("alert(\"x"), std::string::npos);
  EXPECT_NE(html.find("&lt;/script&gt;&lt;script&gt;alert(&quot;x&amp;y&quot;)&lt;/script&gt;"), std::string::npos);
  // Inside a spec the name is still intact once parsed.
  EXPECT_NE(spec(html, 3)["description"].get<std::string>().find("EZ0T" + kEvil), std::string::npos);
}

TEST_F(ModelReport, IsDeterministic) {
  const json d = diagnosisJson();
  EXPECT_EQ(modelReportHtml(fitJson(true), &d, vega_), modelReportHtml(fitJson(true), &d, vega_));
}

TEST_F(ModelReport, WithoutBeforeOrDiagnosis) {
  const std::string html = modelReportHtml(fitJson(false), nullptr, vega_);
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 4u);
  EXPECT_EQ(html.find("class=\"before\""), std::string::npos);
  EXPECT_EQ(html.find("Diagnosis"), std::string::npos);
  EXPECT_EQ(html.find("strokeDash\":{\"value\""), std::string::npos);
  EXPECT_EQ(html.find("\"model before\""), std::string::npos);
}

TEST_F(ModelReport, ToleratesMissingAndNullOptionalFields) {
  json fit = {{"channels", json::array({{{"channel", "EX0C_um"}},
                                        {{"channel", "EA0C_urad"}, {"unit", "urad"}, {"effects", nullptr},
                                         {"indicators", {{"training", nullptr}, {"validation", nullptr}}},
                                         {"before", nullptr},
                                         {"series", {{"time_s", {0, 60, "x", 180}}, {"measured", {1, nullptr}},
                                                     {"predicted", nullptr}, {"U", nullptr}}}}})}};
  std::string html;
  ASSERT_NO_THROW(html = modelReportHtml(fit, nullptr, vega_));
  EXPECT_EQ(count(html, "class=\"vega-plot\""), 2u);  // EA0C only: EX0C has no series
  EXPECT_NE(html.find("EA0C (\u00b5rad)"), std::string::npos);
  const json values = dataset(spec(html, 1), "series")["values"];
  ASSERT_EQ(values.size(), 3u);  // the row whose time is not a number is left out
  EXPECT_EQ(values[1]["measured"], nullptr);
  const json d = {{"channels", json::array({{{"channel", "EZ0T_um"}, {"windows", nullptr}}})},
                  {"candidates", json::array({{{"sentence", nullptr}}})}};
  ASSERT_NO_THROW(html = modelReportHtml(fit, &d, vega_));
  EXPECT_NE(html.find("(diagnosed, not in the fit)"), std::string::npos);
}

TEST_F(ModelReport, RefusesWhatIsNotAFit) {
  EXPECT_THROW(modelReportHtml(json::array(), nullptr, vega_), InputError);
  EXPECT_THROW(modelReportHtml(json{{"kind", "probeloop model fit"}}, nullptr, vega_), InputError);
  const json d = diagnosisJson();
  EXPECT_THROW(modelReportHtml(d, nullptr, vega_), InputError);  // the two swapped
  const json fit = fitJson(false);
  EXPECT_THROW(modelReportHtml(fit, &fit, vega_), InputError);
}

TEST_F(ModelReport, MissingVegaIsAnInputErrorNamingThePackage) {
  try {
    modelReportHtml(fitJson(false), nullptr, (dir_ / "no-such-vega").string());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("libjs-vega"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no-such-vega"), std::string::npos) << e.what();
  }
  // A directory without the module builds names the first missing module.
  fs::create_directories(dir_ / "empty");
  try {
    modelReportHtml(fitJson(false), nullptr, (dir_ / "empty").string());
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vega-util.min.js"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("libjs-vega"), std::string::npos) << e.what();
  }
}

TEST_F(ModelReport, InlinesDebianVegaModules) {
  if (!fs::is_directory(defaultVegaPath())) GTEST_SKIP() << "libjs-vega not installed";
  const std::string html = modelReportHtml(fitJson(true), nullptr);
  for (const char* m : {"vega-util.min.js", "vega-view.min.js", "vega-parser.min.js", "vega-encode.min.js"})
    EXPECT_NE(html.find(std::string("/* ") + m + " */"), std::string::npos) << m;
  EXPECT_NE(html.find("window.vega = vega;"), std::string::npos);
  EXPECT_EQ(html.find("sourceMappingURL"), std::string::npos);
  EXPECT_EQ(count(html, "</script"), 4u + 3u);
  EXPECT_EQ(html.find("<script src"), std::string::npos);  // self-contained: nothing to fetch
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::report
