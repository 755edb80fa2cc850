// The thermal-test-piece evaluation (seed 004 §7.2) against expectations derived by hand from
// the definitions (surfaces displaced by chosen amounts -> E by the formulas written out
// here), from the thesis (Table 7.2's reductions) and by Monte Carlo of the propagation.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "evaluate/piece_evaluation.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "evaluate/ttp_ingest.hpp"
#include "evaluate/ttp_test_support.hpp"
#include "model/dataset.hpp"

namespace probeloop::evaluate {
namespace {

using namespace ttptest;
using Eigen::Vector3d;

std::string refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TtpEvaluation evaluateCmm(const Fixture& f, const std::string& csv, const TtpOptions& o = {}) {
  return evaluateThermalTestPiece(f.m, readTtpCmmExport("cmm.csv", csv, f.m), o);
}


TEST(TtpEvaluation, HandDerivedErrorsFromDisplacedSurfaces) {
  const auto f = makeFixture();
  const auto e = evaluateCmm(f, cmmCsv(measure(f, chosen(f)), true));
  EXPECT_EQ(e.assigned_by, "labels");
  ASSERT_EQ(e.cycles.size(), 9u);
  expectChosenErrors(e);
  // The printed Eq. 7.1: [d_X2,i - d_X2,0 - d_X1,i - d_X1,0] / 2 = [(a + e) - a - (a - e) - a] / 2 = e - a.
  const auto& c3 = e.cycles[3];
  ASSERT_TRUE(c3.EX_printed_um);
  EXPECT_NEAR(*c3.EX_printed_um, 5.0 - 97500.0, 1e-5);
  // Eq. 7.9 = half of Eq. 7.3.
  ASSERT_TRUE(e.cycles[2].ETTP_7_9_um);
  EXPECT_NEAR(*e.cycles[2].ETTP_7_9_um, -4.0, 1e-6);
  // The features: d of a facet = apothem + offset; depth = notch depth + cut + extra.
  for (const auto& x : e.features) {
    if (x.id == facetId(f, "X2", 3)) {
      EXPECT_NEAR(*x.d_mm, 97.505, 1e-9);
    }
    if (x.id == zId(f, 5)) {
      EXPECT_NEAR(*x.depth_mm, 12.1 + 0.007, 1e-9);
    }
    if (x.id == zId(f, 0)) {
      EXPECT_NEAR(*x.depth_mm, 12.1, 1e-9);
    }
  }
  // The times: the mean planned cut time of the cycle's features (30, 90, 150, 210, 270 s after the start).
  EXPECT_NEAR(e.cycles[3].time_s, 3 * 3600 + 150, 1e-9);
  // The formulas are the manifest's (one list: parts::thermalTestPieceEvaluation), with dT's sign.
  ASSERT_EQ(e.formulas.size(), f.m.evaluation.size());
  for (std::size_t k = 0; k < e.formulas.size(); ++k) {
    EXPECT_EQ(e.formulas[k].output, f.m.evaluation[k].output);
    EXPECT_EQ(e.formulas[k].formula, f.m.evaluation[k].formula);
  }
  EXPECT_EQ(e.formulas.back().output, "dT_K");
  EXPECT_EQ(e.formulas.back().formula, "-E_TTP,7.9 / (alpha R)");
}

TEST(TtpEvaluation, RotatedAndShiftedExportWithLabelsIsAlignedByTheDatums) {
  const auto f = makeFixture();
  const auto pts = measure(f, chosen(f));
  const Eigen::Matrix3d Q = Eigen::AngleAxisd(degToRad(30), Vector3d(0.2, -0.3, 1).normalized()).toRotationMatrix();
  const Vector3d shift(200, -35, 12);
  const auto e = evaluateCmm(f, cmmCsv(pts, true, Q, shift));
  expectChosenErrors(e);
  // file -> part: p' = Q^T (p - shift): rotation vector -30 deg about the axis, translation -Q^T shift.
  ASSERT_TRUE(e.alignment);
  const Vector3d rv = -degToRad(30) * Vector3d(0.2, -0.3, 1).normalized() * 1e6;
  EXPECT_LT((e.alignment->rotation_urad - rv).norm(), 1e-3);
  EXPECT_LT((e.alignment->translation_um - (-(Q.transpose() * shift) * 1e3)).norm(), 1e-3);
  EXPECT_LT((e.alignment->frame.origin_mm - shift).norm(), 1e-9);
}

TEST(TtpEvaluation, UnlabelledPointsInThePartFrameAreAssignedByTheNominalGeometry) {
  const auto f = makeFixture();
  const auto e = evaluateCmm(f, cmmCsv(measure(f, chosen(f)), false));
  EXPECT_EQ(e.assigned_by, "nominal geometry");
  expectChosenErrors(e);
  // Foreign labels are the same as none.
  const auto e2 = evaluateCmm(f, cmmCsv(measure(f, chosen(f)), true, Eigen::Matrix3d::Identity(), Vector3d::Zero(), "PLN_"));
  EXPECT_EQ(e2.assigned_by, "nominal geometry");
  expectChosenErrors(e2);
}

TEST(TtpEvaluation, UnlabelledPointsInAnotherFrameAreRefusedWithTheFix) {
  const auto f = makeFixture();
  const Eigen::Matrix3d Q = Eigen::AngleAxisd(degToRad(30), Vector3d::UnitZ()).toRotationMatrix();
  const auto msg = refusal([&] { evaluateCmm(f, cmmCsv(measure(f, {}), false, Q, Vector3d(200, 0, 0))); });
  EXPECT_NE(msg.find("probably not in the part frame"), std::string::npos) << msg;
  EXPECT_NE(msg.find("Export the points in the part alignment"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'feature' column"), std::string::npos) << msg;
}

TEST(TtpEvaluation, AmbiguousPointAtAFacetEdgeNamesTheLineAndBothFeatures) {
  const auto f = makeFixture();
  std::string csv = cmmCsv(measure(f, {}), false);
  // The edge shared by X1_4 and X1_5: between the two normals, at apothem / cos(pitch / 2).
  const double a4 = parts::facetNormalAngle(f.t, parts::FacetSide::X1, 4), a5 = parts::facetNormalAngle(f.t, parts::FacetSide::X1, 5);
  const double r = f.t.facet_apothem_mm / std::cos(degToRad(3));
  const double mid = degToRad((a4 + a5) / 2);
  csv += formatNumber(r * std::cos(mid)) + "," + formatNumber(r * std::sin(mid)) + ",-6\n";
  const int line = static_cast<int>(std::count(csv.begin(), csv.end(), '\n'));
  const auto msg = refusal([&] { evaluateCmm(f, csv); });
  EXPECT_NE(msg.find("cmm.csv:" + std::to_string(line) + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ambiguous"), std::string::npos) << msg;
  EXPECT_NE(msg.find("X1_4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("X1_5"), std::string::npos) << msg;
}

TEST(TtpEvaluation, APointOffEveryFeatureNamesItsLineAndTheNearestFeature) {
  const auto f = makeFixture();
  auto pts = measure(f, {});
  std::string csv = cmmCsv(pts, false);
  const auto& x = f.m.feature("X1_2")->nominal;
  const Vector3d p = f.t.facet_apothem_mm * x.direction + Vector3d(0, 0, -6) + 3.0 * x.direction;
  csv += formatNumber(p.x()) + "," + formatNumber(p.y()) + "," + formatNumber(p.z()) + "\n";
  const int line = static_cast<int>(std::count(csv.begin(), csv.end(), '\n'));
  const auto msg = refusal([&] { evaluateCmm(f, csv); });
  EXPECT_NE(msg.find("cmm.csv:" + std::to_string(line) + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("fits no nominal feature"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nearest is X1_2 at 3.000 mm"), std::string::npos) << msg;
}

std::string withoutPoints(const std::string& csv, const std::string& feature, std::size_t keep) {
  std::istringstream in(csv);
  std::string out;
  std::size_t kept = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(feature + ",", 0) == 0 && kept++ >= keep) continue;
    out += line + "\n";
  }
  return out;
}

TEST(TtpEvaluation, AFacetWithTwoPointsIsRefusedNamingItAndItsLines) {
  const auto f = makeFixture();
  const std::string id = facetId(f, "X2", 6);
  const std::string csv = withoutPoints(cmmCsv(measure(f, {}), true), id, 2);
  // Lines of the two kept points: the header is line 2.
  std::vector<int> lines;
  {
    std::istringstream in(csv);
    int n = 0;
    for (std::string l; std::getline(in, l);)
      if (++n, l.rfind(id + ",", 0) == 0) lines.push_back(n);
  }
  ASSERT_EQ(lines.size(), 2u);
  const auto msg = refusal([&] { evaluateCmm(f, csv); });
  EXPECT_NE(msg.find("feature " + id + " has 2 points (lines " + std::to_string(lines[0]) + ", " + std::to_string(lines[1]) + ")"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find(">= 3"), std::string::npos) << msg;
}

TEST(TtpEvaluation, AMissingReferenceCutIsRefused) {
  const auto f = makeFixture();
  const std::string id = facetId(f, "Y1", 0);
  const auto msg = refusal([&] { evaluateCmm(f, withoutPoints(cmmCsv(measure(f, {}), true), id, 0)); });
  EXPECT_NE(msg.find("reference feature " + id), std::string::npos) << msg;
  EXPECT_NE(msg.find("a missing reference cut"), std::string::npos) << msg;
  EXPECT_NE(msg.find("cmm.csv"), std::string::npos) << msg;
}

TEST(TtpEvaluation, TooFewDatumPointsNameTheDatum) {
  const auto f = makeFixture();
  const auto msg = refusal([&] { evaluateCmm(f, withoutPoints(cmmCsv(measure(f, {}), true), "CYL", 2)); });
  EXPECT_NE(msg.find("feature CYL has 2 points"), std::string::npos) << msg;
  EXPECT_NE(msg.find("datum CYL"), std::string::npos) << msg;
}

TEST(TtpEvaluation, CollinearTopPointsNameTheDatumAndItsLines) {
  const auto f = makeFixture();
  auto pts = measure(f, {});
  for (auto& p : pts)
    if (p.feature == "TOP") p.surface_mm = Vector3d(10.0 + p.point, 70, 0);  // all on one line
  const auto msg = refusal([&] { evaluateCmm(f, cmmCsv(pts, true)); });
  EXPECT_NE(msg.find("feature TOP has 12 points (lines 3, 4,"), std::string::npos) << msg;
  EXPECT_NE(msg.find("the datum TOP does not define its element"), std::string::npos) << msg;
  EXPECT_NE(msg.find("collinear"), std::string::npos) << msg;
}

TEST(TtpEvaluation, MixedLabelsAreRefused) {
  const auto f = makeFixture();
  std::string csv = cmmCsv(measure(f, {}), true);
  csv += "PLANE_7,1,0,0,0\n";
  const int line = static_cast<int>(std::count(csv.begin(), csv.end(), '\n'));
  const auto msg = refusal([&] { evaluateCmm(f, csv); });
  EXPECT_NE(msg.find("cmm.csv:" + std::to_string(line) + ": feature 'PLANE_7' is not a feature of the manifest"), std::string::npos) << msg;
}

TEST(TtpEvaluation, AMissingMeasurementFacetOmitsOnlyTheValuesThatNeedIt) {
  const auto f = makeFixture();
  const std::string id = facetId(f, "Y2", 4);
  const auto e = evaluateCmm(f, withoutPoints(cmmCsv(measure(f, chosen(f)), true), id, 0));
  const auto& c = e.cycles[4];
  EXPECT_FALSE(c.value("EY_um"));
  EXPECT_FALSE(c.value("ETTP_um"));
  EXPECT_FALSE(c.value("dT_K"));
  EXPECT_TRUE(c.value("EX_um"));
  EXPECT_TRUE(c.value("EZ_um"));
  ASSERT_EQ(c.missing.size(), 1u);
  EXPECT_NE(c.missing[0].find(id), std::string::npos) << c.missing[0];
  // errors.csv leaves the cycle out and says why.
  const auto csv = ttpErrorsCsv(e);
  EXPECT_NE(csv.find("# cycle 4 omitted"), std::string::npos);
  EXPECT_EQ(csv.find("\n" + formatNumber(e.cycles[4].time_s, 3) + ",4,"), std::string::npos);
  // The spans over cycle 4 lack E_Y and E_TTP there: incomplete; E_X, E_Z, E_B complete.
  ASSERT_EQ(e.spans.size(), 3u);
  for (const auto& sp : e.spans)
    for (const auto& v : sp.values) {
      if ((v.quantity == "EY_um" || v.quantity == "ETTP_um") && sp.last >= 4) {
        EXPECT_EQ(v.missing_cycles, std::vector<int>{4}) << sp.last;
      } else {
        EXPECT_TRUE(v.complete()) << sp.last << v.quantity;
      }
    }
}

TEST(TtpEvaluation, OnMachineTipCentresGiveTheSameErrorsForBothSensesOfC) {
  for (bool clockwise : {true, false}) {
    const auto f = makeFixture(clockwise);
    const auto pts = measure(f, chosen(f));
    const auto a = evaluateThermalTestPiece(f.m, readTtpOnMachine("points.csv", pointsCsv(f, pts), "csv", f.m));
    EXPECT_EQ(a.route, TtpRoute::OnMachine);
    EXPECT_EQ(a.assigned_by, "manifest positions");
    expectChosenErrors(a, 1e-5);
    const auto b = evaluateThermalTestPiece(f.m, readTtpOnMachine("dprnt.txt", dprnt(f, pts), "fanuc", f.m));
    expectChosenErrors(b, 2e-3);  // the log has 6 decimals (1 nm)
  }
}

TEST(TtpEvaluation, OnMachineLogFromAnotherPlanIsRefused) {
  const auto f = makeFixture();
  auto pts = measure(f, {});
  pts[40].surface_mm.x() += 25;
  const auto msg = refusal([&] { readTtpOnMachine("dprnt.txt", dprnt(f, pts), "fanuc", f.m); });
  EXPECT_NE(msg.find("dprnt.txt:" + std::to_string(41 + 1) + ":"), std::string::npos) << msg;
  EXPECT_NE(msg.find("does not match the manifest"), std::string::npos) << msg;
}

TEST(TtpEvaluation, DialGaugeReadingsByEqs7_7To7_9) {
  const auto f = makeFixture();
  // Cycle 3's four facets and cycle 5's two X facets, relative to each side's reference.
  std::string csv = "# dial gauge\nfacet,g_um\n";
  csv += facetId(f, "X1", 0) + ",0\n";
  csv += facetId(f, "X1", 3) + ",-2.5\n" + facetId(f, "X2", 3) + ",4.5\n" + facetId(f, "Y1", 3) + ",-1\n" + facetId(f, "Y2", 3) + ",3\n";
  csv += facetId(f, "X1", 5) + ",1\n" + facetId(f, "X2", 5) + ",2\n";
  const auto e = evaluateThermalTestPieceGauge(f.m, readTtpGauge("gauge.csv", csv, f.m));
  EXPECT_NEAR(value(e, 3, "EX_um"), (4.5 - -2.5) / 2, 1e-12);          // Eq. 7.7
  EXPECT_NEAR(value(e, 3, "EY_um"), (3 - -1) / 2.0, 1e-12);            // Eq. 7.8
  // E_TTP is Eq. 7.3 on every route: [(g_X1 + g_X2) + (g_Y1 + g_Y2)] / 2; Eq. 7.9 (/ 4) beside it.
  EXPECT_NEAR(value(e, 3, "ETTP_um"), (3 + -1 + 4.5 + -2.5) / 2.0, 1e-12);  // Eq. 7.3
  ASSERT_TRUE(e.cycles[3].ETTP_7_9_um);
  EXPECT_NEAR(*e.cycles[3].ETTP_7_9_um, (3 + -1 + 4.5 + -2.5) / 4.0, 1e-12);  // Eq. 7.9
  EXPECT_NEAR(value(e, 3, "dT_K"), -1.0 / (22e-6 * 97.5e3), 1e-12);    // Eq. 7.10 from Eq. 7.9's 1 um
  EXPECT_NEAR(value(e, 5, "EX_um"), 0.5, 1e-12);
  EXPECT_FALSE(e.cycles[5].value("EY_um"));
  EXPECT_FALSE(e.cycles[3].value("EZ_um"));
  EXPECT_FALSE(e.alignment);
  // Budget: resolution 1 um rectangular per reading and per zero: E_X = (g2 - g1) / 2 -> each
  // (1/sqrt 12) sqrt(2 / 4).
  const auto& b = budget(e, 3, "EX_um");
  EXPECT_NEAR(contribution(b, "dial gauge readings"), 1 / std::sqrt(12.0) * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(contribution(b, "dial gauge zero"), 1 / std::sqrt(12.0) * std::sqrt(0.5), 1e-12);
  // E_TTP (Eq. 7.3): four readings with weight 1/2 -> (1/sqrt 12) sqrt(4 / 4); dT through Eq. 7.9
  // (weights 1/4) -> (1/sqrt 12) sqrt(4 / 16) / (alpha R).
  EXPECT_NEAR(contribution(budget(e, 3, "ETTP_um"), "dial gauge readings"), 1 / std::sqrt(12.0), 1e-12);
  EXPECT_NEAR(contribution(budget(e, 3, "dT_K"), "dial gauge readings"), 1 / std::sqrt(12.0) * 0.5 / (22e-6 * 97.5e3), 1e-12);
  // The formulas are the manifest's, those of the values the gauge gives.
  std::vector<std::string> outputs;
  for (const auto& r : e.formulas) outputs.push_back(r.output);
  EXPECT_EQ(outputs, (std::vector<std::string>{"EX_um", "EY_um", "ETTP_um", "dT_K"}));
  // errors.csv: only EX, EY, ETTP; cycle 5 lacks EY and is left out.
  const auto csv_out = ttpErrorsCsv(e);
  EXPECT_NE(csv_out.find("time_s,cycle,EX_um,EY_um,ETTP_um,U_EX_um,U_EY_um,U_ETTP_um\n"), std::string::npos) << csv_out;
  EXPECT_NE(csv_out.find("E_TTP: Eq. 7.3 (diametral), (g_X1 + g_X2 + g_Y1 + g_Y2) / 2"), std::string::npos) << csv_out;
  EXPECT_NE(csv_out.find("\n" + formatNumber(e.cycles[3].time_s, 3) + ",3," + formatNumber(3.5, 4) + "," + formatNumber(2.0, 4) + "," +
                         formatNumber(2.0, 4) + ","),
            std::string::npos)
      << csv_out;
  // A facet that is not one is refused with its line.
  const auto msg = refusal([&] { readTtpGauge("gauge.csv", "facet,g_um\nZ3,1\n", f.m); });
  EXPECT_NE(msg.find("gauge.csv:2:"), std::string::npos) << msg;
}

// Dial-gauge readings of the chosen surfaces: g = d(t_i) - d(t_0) per facet (um), the reference
// facets read 0; only the cycles listed.
std::string gaugeCsv(const Fixture& f, const Truth& t, const std::vector<int>& cycles) {
  std::string csv = "facet,g_um\n";
  for (int c : cycles)
    for (const char* s : {"X1", "X2", "Y1", "Y2"}) {
      const std::string id = facetId(f, s, c);
      csv += id + "," + formatNumber(t.offset_mm.count(id) ? t.offset_mm.at(id) * 1e3 : 0.0) + "\n";
    }
  return csv;
}

TEST(TtpEvaluation, EttpIsEquation7_3OnEveryRouteAndRoutesCompare) {
  const auto f = makeFixture();
  const auto truth = chosen(f);
  const auto cmm = evaluateCmm(f, cmmCsv(measure(f, truth), true));
  const auto gauge = evaluateThermalTestPieceGauge(f.m, readTtpGauge("gauge.csv", gaugeCsv(f, truth, {0, 1, 2, 3, 4, 5, 6, 7, 8}), f.m));
  // Cycle 2: every facet 4 um in -> Eq. 7.3 = (-8 - 8) / 2 = -8 um on both routes, Eq. 7.9 = -4 um.
  EXPECT_NEAR(value(gauge, 2, "ETTP_um"), -8.0, 1e-12);
  EXPECT_NEAR(value(cmm, 2, "ETTP_um"), -8.0, 1e-6);
  EXPECT_NEAR(*gauge.cycles[2].ETTP_7_9_um, -4.0, 1e-12);
  EXPECT_NEAR(value(gauge, 2, "dT_K"), value(cmm, 2, "dT_K"), 1e-6);
  for (int c = 1; c < 9; ++c)
    for (const char* q : {"EX_um", "EY_um", "ETTP_um"}) EXPECT_NEAR(value(gauge, c, q), value(cmm, c, q), 1e-6) << c << q;
  // The gauge run compared with the CMM run: the same quantities, the routes named.
  const std::string cmm_json = tempFile("cmm-evaluation.json", ttpEvaluationJson(cmm));
  const auto cmp = compareSpans(gauge, cmm_json);
  EXPECT_EQ(cmp.this_route, "gauge");
  EXPECT_EQ(cmp.other_route, "cmm");
  EXPECT_TRUE(cmp.left_out.empty());
  ASSERT_FALSE(cmp.rows.empty());
  for (const auto& r : cmp.rows) EXPECT_NEAR(r.this_span, r.other_span, 1e-6) << r.quantity;
  auto with = gauge;
  with.comparison = cmp;
  const auto j = nlohmann::ordered_json::parse(ttpEvaluationJson(with));
  EXPECT_EQ(j["comparison"]["this_route"], "gauge");
  EXPECT_EQ(j["comparison"]["other_route"], "cmm");
  EXPECT_NE(ttpStdout(with, "e", "j", "r").find("(routes gauge / cmm)"), std::string::npos);
  // An evaluation whose E_TTP is another quantity (the radial form under the same name) is refused.
  auto old = nlohmann::json::parse(ttpEvaluationJson(gauge));
  for (auto& r : old["formulas"])
    if (r["output"] == "ETTP_um") r["formula"] = "(g_Y2 + g_Y1 + g_X2 + g_X1) / 4: the radial form, half of Eq. 7.3's";
  const std::string old_json = tempFile("old-gauge-evaluation.json", old.dump());
  const auto msg = refusal([&] { compareSpans(cmm, old_json); });
  EXPECT_NE(msg.find(old_json + ": ETTP_um is not the same quantity in both evaluations"), std::string::npos) << msg;
  EXPECT_NE(msg.find("route cmm"), std::string::npos) << msg;
  EXPECT_NE(msg.find("route gauge"), std::string::npos) << msg;
}

TEST(TtpSpans, APeriodWithMissingCyclesIsIncompleteAndNotCompared) {
  const auto f = makeFixture();
  const auto truth = chosen(f);
  // Readings of cycles 0-2 only: E_TTP(2) = -8 um; cycles 3-8 absent.
  const std::string input = tempFile("gauge.csv", gaugeCsv(f, truth, {0, 1, 2}));
  const auto e = evaluateThermalTestPieceGauge(f.m, readTtpGauge(input, readFile(input), f.m));
  ASSERT_EQ(e.spans.size(), 3u);
  EXPECT_EQ(e.spans[0].last, 1);
  for (const auto& v : e.spans[0].values) EXPECT_TRUE(v.complete()) << v.quantity;
  EXPECT_EQ(e.spans[1].last, 4);
  EXPECT_EQ(e.spans[2].last, 8);
  for (int k : {1, 2}) {
    ASSERT_EQ(e.spans[k].values.size(), 3u);  // EX, EY, ETTP (the gauge has no E_Z, E_B)
    for (const auto& v : e.spans[k].values) {
      std::vector<int> missing;
      for (int c = 3; c <= e.spans[k].last; ++c) missing.push_back(c);
      EXPECT_EQ(v.missing_cycles, missing) << v.quantity;
    }
  }
  const std::string out = ttpStdout(e, "e", "j", "r");
  EXPECT_NE(out.find("cycles 0-8 (8.00 h): EX incomplete (cycles 3-8 missing)"), std::string::npos) << out;
  EXPECT_EQ(out.find("ETTP 8.00"), std::string::npos) << out;
  const auto j = nlohmann::ordered_json::parse(ttpEvaluationJson(e));
  const auto& v = j["spans"][2]["values"][2];
  EXPECT_EQ(v["quantity"], "ETTP_um");
  EXPECT_EQ(v["complete"], false);
  EXPECT_TRUE(v["span"].is_null());
  EXPECT_TRUE(v["U"].is_null());
  EXPECT_EQ(v["missing_cycles"], nlohmann::json({3, 4, 5, 6, 7, 8}));
  EXPECT_NE(ttpReport(e).find("incomplete (cycles 3-8 missing)"), std::string::npos);
  // Compared with a complete run: only the first hour, the others listed as not compared.
  const auto full = evaluateCmm(f, cmmCsv(measure(f, truth), true));
  EvaluateRequest r;
  r.input_file = input;
  r.compare_with = tempFile("full-evaluation.json", ttpEvaluationJson(full));
  const auto files = evaluateTestPiece(f.m, r);
  const auto& cmp = *files.thermal_test_piece->comparison;
  for (const auto& row : cmp.rows) EXPECT_LT(row.period_h, 2.0) << row.quantity;
  EXPECT_EQ(cmp.rows.size(), 3u);
  ASSERT_EQ(cmp.left_out.size(), 6u);
  EXPECT_EQ(cmp.left_out[0], "cycles 0-4 EX_um: incomplete in this run (cycles 3-4 missing)");
  EXPECT_NE(files.stdout_text.find("Not compared: cycles 0-8 ETTP_um: incomplete in this run (cycles 3-8 missing)"), std::string::npos)
      << files.stdout_text;
  // The other way round: the incomplete run's spans are left out too.
  const std::string partial = tempFile("partial-evaluation.json", files.evaluation_json);
  const auto back = compareSpans(full, partial);
  EXPECT_EQ(back.rows.size(), 3u);  // E_Z and E_B are not in the gauge run: not compared
  ASSERT_FALSE(back.left_out.empty());
  EXPECT_EQ(back.left_out[0], "cycles 0-4 EX_um: incomplete in " + partial + " (cycles 3-4 missing)");
}

// Swaps two labels in a labelled export.
std::string swapLabels(const std::string& csv, const std::string& a, const std::string& b) {
  std::istringstream in(csv);
  std::string out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(a + ",", 0) == 0)
      line = b + line.substr(a.size());
    else if (line.rfind(b + ",", 0) == 0)
      line = a + line.substr(b.size());
    out += line + "\n";
  }
  return out;
}

int firstLineOf(const std::string& csv, const std::string& feature) {
  std::istringstream in(csv);
  int n = 0;
  for (std::string l; std::getline(in, l);)
    if (++n, l.rfind(feature + ",", 0) == 0) return n;
  return 0;
}

TEST(TtpEvaluation, AFeatureOffItsNominalAfterTheAlignmentIsRefused) {
  const auto f = makeFixture();
  // X1_3's points labelled X1_4 and the other way round: the normals are 6 deg apart.
  const std::string csv = swapLabels(cmmCsv(measure(f, {}), true), "X1_3", "X1_4");
  auto msg = refusal([&] { evaluateCmm(f, csv); });
  EXPECT_NE(msg.find("cmm.csv:" + std::to_string(firstLineOf(csv, "X1_3")) + ": feature X1_3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("normal is 6 deg from the nominal one"), std::string::npos) << msg;
  EXPECT_NE(msg.find("mislabelled points?"), std::string::npos) << msg;
  // A Z path tilted by 3 deg (no NaN or huge depth from / n_z).
  Truth tilt;
  tilt.beta_rad[zId(f, 5)] = degToRad(3);
  const std::string tilted = cmmCsv(measure(f, tilt), true);
  msg = refusal([&] { evaluateCmm(f, tilted); });
  EXPECT_NE(msg.find("cmm.csv:" + std::to_string(firstLineOf(tilted, zId(f, 5))) + ": feature " + zId(f, 5)), std::string::npos) << msg;
  EXPECT_NE(msg.find("normal is 3 deg"), std::string::npos) << msg;
  // A facet 0.8 mm off its nominal surface.
  Truth off;
  off.offset_mm[facetId(f, "X2", 6)] = 0.8;
  msg = refusal([&] { evaluateCmm(f, cmmCsv(measure(f, off), true)); });
  EXPECT_NE(msg.find("feature " + facetId(f, "X2", 6)), std::string::npos) << msg;
  EXPECT_NE(msg.find("centre 0.8 mm from the nominal surface (at most 1 deg and 0.5 mm)"), std::string::npos) << msg;
  // Within the limits (0.4 mm, 0.9 deg) the values are evaluated.
  Truth near;
  near.offset_mm[facetId(f, "X2", 6)] = 0.4;
  near.beta_rad[zId(f, 5)] = degToRad(0.9);
  EXPECT_EQ(refusal([&] { evaluateCmm(f, cmmCsv(measure(f, near), true)); }), "(accepted)");
}

TEST(TtpEvaluation, GaugeOnAManifestWithoutAReferenceSideIsRefused) {
  auto f = makeFixture();
  const std::string ref = facetId(f, "X1", 0);
  auto& fs = f.m.features;
  fs.erase(std::remove_if(fs.begin(), fs.end(), [&](const parts::ManifestFeature& x) { return x.nominal.id == ref; }), fs.end());
  const std::string csv = "facet,g_um\n" + facetId(f, "X1", 3) + ",1\n" + facetId(f, "X2", 3) + ",2\n";
  const auto msg = refusal([&] { evaluateThermalTestPieceGauge(f.m, readTtpGauge("gauge.csv", csv, f.m)); });
  EXPECT_NE(msg.find("hand-built-plan.json: the manifest has no reference X1 facet (cycle 0)"), std::string::npos) << msg;
}

// Budgets: structure, and the point-scatter terms derived by hand for the on-machine route
// (sigma = 0.5 um on every point).
TEST(TtpBudget, ContributionsAddUpAndPointScatterMatchesTheHandDerivation) {
  const auto f = makeFixture();
  const auto e = evaluateThermalTestPiece(f.m, readTtpOnMachine("points.csv", pointsCsv(f, measure(f, chosen(f))), "csv", f.m));
  for (const auto& c : e.cycles)
    for (const auto& b : c.values) {
      double s = 0;
      for (const auto& x : b.contributions) s += x.u * x.u;
      EXPECT_NEAR(s, b.u_c * b.u_c, 1e-12 * std::max(1.0, b.u_c * b.u_c)) << c.cycle << b.quantity;
      EXPECT_NEAR(b.U, 2.0 * b.u_c, 1e-15) << c.cycle << b.quantity;
    }
  const double sigma = 0.5e-3;  // mm
  // A facet: 3 x 2 points, across {-3, 0, 3}, heights {-3, -9}: the centroid on the facet's centre
  // line at z = -6. d = n.c moves by the offset (var sigma^2 / 6) and by c.dn = z_c dn_z with the
  // tilt about the horizontal (var sigma^2 / (6 * 9)): var d = sigma^2 (1/6 + 36/54).
  const double u_d = sigma * std::sqrt(1.0 / 6 + 36.0 / 54);
  for (const auto& x : e.features) {
    if (x.d_mm) {
      EXPECT_NEAR(x.u_d_um, u_d * 1e3, 1e-9) << x.id;
    }
  }
  // Z path: 12 points centred at (0, y_j): the depth there is the plane's offset, var sigma^2 / 12.
  for (const auto& x : e.features) {
    if (x.depth_mm) {
      EXPECT_NEAR(x.u_d_um, sigma / std::sqrt(12.0) * 1e3, 1e-9) << x.id;
    }
  }
  const auto& bx = budget(e, 8, "EX_um");
  // E_X: four independent d's with weights 1/2.
  EXPECT_NEAR(contribution(bx, "probe repeatability"), std::sqrt(4 * 0.25) * u_d * 1e3, 1e-9);
  // Resolution q = 1 um: q / sqrt 12 per point, through the same fits.
  EXPECT_NEAR(contribution(bx, "coordinate resolution"), std::sqrt(4 * 0.25) * u_d / sigma * 1e-3 / std::sqrt(12.0) * 1e3, 1e-9);
  // Machine repeatability 1 um as 2 sigma, one shift per facet: sqrt(4 / 4) * 0.5 um.
  EXPECT_NEAR(contribution(bx, "machine repeatability"), 0.5, 1e-9);
  // Temperature change 0.1 K between a facet and its reference: half-width alpha dT d, two pairs
  // with weight 1/2: u = sqrt(2) (alpha dT d / 2) / sqrt 3 (d = 97.5 mm, alpha 23.4 um/(m K)).
  EXPECT_NEAR(contribution(bx, "part temperature change"), std::sqrt(2.0) * (23.4e-6 * 0.1 * 97.5e3 / 2) / std::sqrt(3.0), 1e-9);
  const auto& bz = budget(e, 8, "EZ_um");
  EXPECT_NEAR(contribution(bz, "probe repeatability"), std::sqrt(2.0) * sigma / std::sqrt(12.0) * 1e3, 1e-9);
  // beta: slope in x of 12 points at x = +-20, +-50, +-80: var = sigma^2 / sum x^2.
  const double sxx = 4 * (20.0 * 20 + 50 * 50 + 80 * 80);
  EXPECT_NEAR(contribution(budget(e, 8, "EB_urad"), "probe repeatability"), std::sqrt(2.0) * sigma / std::sqrt(sxx) * 1e6, 1e-6);
  EXPECT_EQ(contribution(budget(e, 8, "EB_urad"), "part temperature"), 0.0);
  // dT: E_TTP,7.9's contributions / (alpha R) and u(alpha) |dT| / alpha.
  const auto& bt = budget(e, 2, "dT_K");
  EXPECT_NEAR(contribution(bt, "alpha of Eq. 7.10"), std::fabs(bt.value) * 1.0 / 22.0, 1e-12);
  // CMM route: Eq. 7.6's alpha dT E for the CMM room (0.3 K).
  const auto c = evaluateCmm(f, cmmCsv(measure(f, chosen(f)), true));
  EXPECT_NEAR(contribution(budget(c, 3, "EX_um"), "part temperature in the CMM room"), 23.4e-6 * 0.3 * 5.0 / std::sqrt(3.0), 1e-12);
  for (const auto& x : budget(c, 3, "EX_um").contributions)
    if (x.input.rfind("part temperature in the CMM room", 0) == 0) {
      EXPECT_NE(x.basis.find("half-width of a rectangular distribution (our interpretation)"), std::string::npos) << x.basis;
    }
}

TEST(TtpBudget, TheLargerScatterEstimateIsUsedAndTheOtherListedWithZero) {
  const auto f = makeFixture();
  auto pts = measure(f, {});
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0, 2e-3);  // 2 um along the normal: far above the probe's 0.5 um
  for (auto& p : pts)
    if (f.m.feature(p.feature)->nominal.group != "datum") p.surface_mm += normal(rng) * p.outward;
  const auto e = evaluateThermalTestPiece(f.m, readTtpOnMachine("points.csv", pointsCsv(f, pts), "csv", f.m));
  EXPECT_TRUE(e.scatter.type_a_used);
  EXPECT_EQ(e.scatter.type_a_dof, 9 * (12 - 3) + 36 * (6 - 3));  // Z paths 12 points, facets 6, planes 3 parameters
  const auto& b = budget(e, 8, "EX_um");
  EXPECT_EQ(contribution(b, "probe repeatability (specification)"), 0.0);
  EXPECT_GT(contribution(b, "point scatter (type A)"), 0.0);
  for (const auto& c : b.contributions) {
    if (c.input.rfind("point scatter (type A)", 0) == 0) {
      EXPECT_EQ(c.dof, 189);
    }
  }
  EXPECT_TRUE(std::isfinite(b.nu_eff));
}

// Monte Carlo of the propagation: normal noise along each point's normal with the CMM's
// sigma = MPE(L)/2; the standard deviation of E over n synthetic exports against the budget's
// term. With n trials the relative standard error of a standard deviation is about
// 1/sqrt(2(n - 1)); the ratio MC / budget must lie within 3 of those of 1 (6.7 % at n = 1000).
// Under AddressSanitizer (the Debug ASan+UBSan build, ~1 min for 1000) n = 300: 12.3 %.
#if defined(__SANITIZE_ADDRESS__)
#define PROBELOOP_TTP_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PROBELOOP_TTP_SANITIZED 1
#endif
#endif
#ifdef PROBELOOP_TTP_SANITIZED
constexpr int kMonteCarloTrials = 300;
#else
constexpr int kMonteCarloTrials = 1000;
#endif

TEST(TtpBudget, MonteCarloAgreesWithThePropagation) {
  const int n = kMonteCarloTrials;
  const double tolerance = 3.0 / std::sqrt(2.0 * (n - 1));
  const auto f = makeFixture();
  const auto base = measure(f, {});
  const auto nominal = evaluateCmm(f, cmmCsv(base, true));
  TtpOptions quick;
  quick.budgets = false;
  quick.form_mz = false;
  std::mt19937_64 rng(20240613);
  std::normal_distribution<double> normal(0, 1);
  const auto& cmm = f.m.ttp.cmm;
  for (int datums = 0; datums < 2; ++datums) {
    std::map<std::string, std::vector<double>> v;
    for (int trial = 0; trial < n; ++trial) {
      auto pts = base;
      for (auto& p : pts) {
        const bool datum = f.m.feature(p.feature)->nominal.group == "datum";
        if (datum != (datums == 1)) continue;
        const double L = p.surface_mm.norm();
        p.surface_mm += (cmm.mpe_constant_um + L / cmm.mpe_length_mm) / 2 * 1e-3 * normal(rng) * p.outward;
      }
      const auto e = evaluateCmm(f, cmmCsv(pts, true), quick);
      for (const char* q : {"EX_um", "EZ_um", "EB_urad"}) v[q].push_back(value(e, 8, q));
    }
    for (const char* q : {"EX_um", "EZ_um", "EB_urad"}) {
      if (datums == 1 && std::string(q) == "EB_urad") continue;  // the frame's tilt cancels in E_B to first order
      double mean = 0, ss = 0;
      for (double x : v[q]) mean += x;
      mean /= n;
      for (double x : v[q]) ss += (x - mean) * (x - mean);
      const double sd = std::sqrt(ss / (n - 1));
      const auto& b = budget(nominal, 8, q);
      const double u = datums ? contribution(b, "datum alignment") : contribution(b, "CMM probing error");
      EXPECT_NEAR(sd / u, 1.0, tolerance) << n << " trials, " << q << (datums ? " datum points" : " measurement points") << ": MC " << sd << ", budget " << u;
      std::printf("[ MC ] %d trials, cycle 8 %-8s %-18s MC sd %.5f  budget u %.5f  ratio %.3f (tolerance %.3f)\n", n, q,
                  datums ? "datum points" : "measurement points", sd, u, sd / u, tolerance);
    }
  }
}

// Table 7.2: the thesis's E_Y spans (UC 15.8 / 27.3 / 31 um) against its compensated ones
// (0.5 / 1.6 / 2.9 um) -> 96.8 % and 90.6 % (notes/seed004.md §5.7).
TEST(TtpSpans, Table7_2ReductionsThroughCompareWith) {
  const auto f = makeFixture();
  const double ey[9] = {0, 15.8, 20, 25, 27.3, 29, 30, 30.5, 31};
  Truth t;
  for (int c = 1; c < 9; ++c) {
    t.offset_mm[facetId(f, "Y2", c)] = ey[c] * 1e-3;  // E_Y = [(+e) - (-e)] / 2 = e
    t.offset_mm[facetId(f, "Y1", c)] = -ey[c] * 1e-3;
  }
  const auto e = evaluateCmm(f, cmmCsv(measure(f, t), true));
  ASSERT_EQ(e.spans.size(), 3u);
  const int last[3] = {1, 4, 8};
  const double uc[3] = {15.8, 27.3, 31};
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(e.spans[k].first, 0);
    EXPECT_EQ(e.spans[k].last, last[k]);
    for (const auto& v : e.spans[k].values)
      if (v.quantity == "EY_um") {
        EXPECT_NEAR(v.span, uc[k], 1e-6);
        // U of the span from the U of the extremes (cycle 0 has U = 0).
        EXPECT_NEAR(v.U, budget(e, last[k], "EY_um").U, 1e-12);
      }
  }
  // The compensated run: this evaluation.json with the thesis's C spans of E_Y.
  auto other = nlohmann::json::parse(ttpEvaluationJson(e));
  other["spans"] = nlohmann::json::array();
  const double c[3] = {0.5, 1.6, 2.9};
  for (int k = 0; k < 3; ++k)
    other["spans"].push_back({{"period_h", last[k]},
                              {"cycles", {0, last[k]}},
                              {"values", {{{"quantity", "EY_um"}, {"complete", true}, {"span", c[k]}, {"U", 0.1}, {"missing_cycles", nlohmann::json::array()}}}}});
  const std::string path = tempFile("other-evaluation.json", other.dump());
  const auto cmp = compareSpans(e, path);
  ASSERT_EQ(cmp.rows.size(), 3u);
  EXPECT_EQ(cmp.this_route, "cmm");
  EXPECT_EQ(cmp.other_route, "cmm");
  EXPECT_NEAR(*cmp.rows[0].reduction_percent, (15.8 - 0.5) / 15.8 * 100, 1e-6);
  EXPECT_NEAR(std::round(*cmp.rows[0].reduction_percent * 10) / 10, 96.8, 1e-9);
  EXPECT_NEAR(std::round(*cmp.rows[2].reduction_percent * 10) / 10, 90.6, 1e-9);
  EXPECT_NE(refusal([&] { compareSpans(e, tempFile("bad.json", "{\"format\": \"x\"}")); }).find("not a thermal-test-piece"),
            std::string::npos);
  // Another kind (a sphere campaign's evaluation.json) is refused naming the kind.
  const auto sphere = refusal([&] {
    compareSpans(e, tempFile("sphere-evaluation.json", "{\"format\": \"probeloop-evaluation\", \"kind\": \"sphere_artifact\"}"));
  });
  EXPECT_NE(sphere.find("found kind 'sphere_artifact'"), std::string::npos) << sphere;
}

TEST(TtpOutputs, ErrorsCsvLoadsWithTheModelAndTheJsonHasTheSchema) {
  const auto f = makeFixture();
  const std::string input = tempFile("cmm_export.csv", cmmCsv(measure(f, chosen(f)), true));
  EvaluateRequest r;
  r.input_file = input;
  r.out_dir = "out";
  const auto files = evaluateTestPiece(f.m, r);
  ASSERT_TRUE(files.thermal_test_piece);
  EXPECT_EQ(files.thermal_test_piece->route, TtpRoute::Cmm);  // auto-detected
  const auto s = model::loadErrors(tempFile("errors.csv", files.errors_csv));
  ASSERT_EQ(s.channels, (std::vector<std::string>{"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}));
  ASSERT_EQ(s.size(), 9);
  EXPECT_NEAR(s.values[0][3], 5.0, 1e-4);
  EXPECT_NEAR(s.values[2][5], 7.0, 1e-4);
  EXPECT_GT(s.U[0][3], 0);
  EXPECT_EQ(s.U[0][0], 0);
  const auto j = nlohmann::ordered_json::parse(files.evaluation_json);
  std::vector<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"format", "version", "kind", "manifest", "input", "alignment", "point_scatter", "features",
                                            "cycles", "spans", "comparison", "formulas"}));
  auto keysOf = [](const nlohmann::ordered_json& o) {
    std::vector<std::string> k;
    for (const auto& [a, b] : o.items()) k.push_back(a);
    return k;
  };
  EXPECT_EQ(keysOf(j["input"]), (std::vector<std::string>{"file", "route", "format", "points", "assigned_by"}));
  EXPECT_EQ(keysOf(j["alignment"]), (std::vector<std::string>{"origin_mm", "x_axis", "y_axis", "z_axis", "file_to_part_rotation_urad",
                                                              "file_to_part_translation_um", "datums"}));
  EXPECT_EQ(keysOf(j["point_scatter"]), (std::vector<std::string>{"type_b_sigma_um", "type_a_sigma_um", "type_a_dof", "used"}));
  EXPECT_EQ(keysOf(j["features"][0]), (std::vector<std::string>{"id", "group", "index", "cycle", "time_s", "points", "rms_um", "form_mz_um",
                                                                "normal", "d_mm", "depth_mm", "beta_urad", "u_d_um"}));
  EXPECT_EQ(keysOf(j["cycles"][3]), (std::vector<std::string>{"cycle", "phase", "time_s", "values", "also", "missing"}));
  EXPECT_EQ(keysOf(j["cycles"][3]["values"][0]),
            (std::vector<std::string>{"quantity", "unit", "value", "u_c", "nu_eff", "k", "U", "contributions"}));
  EXPECT_EQ(keysOf(j["cycles"][3]["values"][0]["contributions"][0]),
            (std::vector<std::string>{"input", "type", "distribution", "basis", "u", "dof"}));
  EXPECT_EQ(keysOf(j["cycles"][3]["also"]), (std::vector<std::string>{"EX_printed_um", "EY_printed_um", "ETTP_7_9_um"}));
  EXPECT_EQ(keysOf(j["spans"][0]), (std::vector<std::string>{"period_h", "cycles", "values"}));
  EXPECT_EQ(keysOf(j["formulas"][0]), (std::vector<std::string>{"output", "formula", "source", "features"}));
  EXPECT_TRUE(j["comparison"].is_null());
  EXPECT_EQ(j["input"]["route"], "cmm");
  EXPECT_EQ(j["cycles"][3]["values"][0]["quantity"], "EX_um");
  EXPECT_NE(files.stdout_text.find("Wrote out/errors.csv, out/evaluation.json (budgets) and out/report.md (report)"), std::string::npos)
      << files.stdout_text;
  EXPECT_NE(files.report_md.find("Table 7.2"), std::string::npos);
  // Deterministic: the same input gives the same bytes.
  EXPECT_EQ(evaluateTestPiece(f.m, r).evaluation_json, files.evaluation_json);
}

TEST(TtpOutputs, FormatsAreDetectedFromTheContent) {
  const auto f = makeFixture();
  const auto pts = measure(f, chosen(f));
  EvaluateRequest r;
  r.input_file = tempFile("points.csv", pointsCsv(f, pts));
  EXPECT_EQ(evaluateTestPiece(f.m, r).thermal_test_piece->route, TtpRoute::OnMachine);
  r.input_file = tempFile("dprnt.txt", dprnt(f, pts));
  EXPECT_EQ(evaluateTestPiece(f.m, r).thermal_test_piece->format, "log");
  r.input_file = tempFile("gauge.csv", "facet,g_um\nX1_1,1\nX2_1,3\n");
  EXPECT_EQ(evaluateTestPiece(f.m, r).thermal_test_piece->route, TtpRoute::Gauge);
  r.format = "sphere";
  EXPECT_NE(refusal([&] { evaluateTestPiece(f.m, r); }).find("expected auto, cmm, qif, dmis, features, linuxcnc, fanuc, csv or gauge"), std::string::npos);
}

TEST(TtpPrediction, BothRoutesFromThePlannedPointsAlone) {
  const auto f = makeFixture();
  const auto p = predictThermalTestPiece(f.m);
  ASSERT_TRUE(p.note.empty()) << p.note;
  ASSERT_EQ(p.cmm.size(), 6u);
  ASSERT_EQ(p.on_machine.size(), 6u);
  // On-machine E_X of the last cycle: the same terms as a measurement of nominal surfaces,
  // the temperature scaling with nothing measured.
  const auto e = evaluateThermalTestPiece(f.m, readTtpOnMachine("points.csv", pointsCsv(f, measure(f, {})), "csv", f.m));
  double worst = 0;
  for (const auto& c : e.cycles)
    if (c.cycle > 0) worst = std::max(worst, c.value("EX_um")->U);
  EXPECT_NEAR(p.on_machine[0].U, worst, 1e-9);
  const std::string text = planPrediction(f.m, 0.001);
  EXPECT_NE(text.find("CMM"), std::string::npos);
  EXPECT_NE(text.find("on-machine"), std::string::npos);
  EXPECT_NE(text.find("specifications alone"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::evaluate
