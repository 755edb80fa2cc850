// The thermal test piece's description, geometry and formulas (seed 004 Ch. 7). Reference
// numbers come from the thesis (Eq. 7.6, Eq. 7.10, Table 7.2, the geometry counts of §7.1)
// or are derived here by hand from the definitions.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <unistd.h>

#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/plan_manifest.hpp"
#include "parts/piece_kinds.hpp"
#include "parts/test_support.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::parts {
namespace {

namespace fs = std::filesystem;

std::string shipped() { return std::string(PROBELOOP_SOURCE_DIR) + "/parts/thermal_test_piece.yaml"; }

std::string variant(const std::string& from, const std::string& to) { return test::variantOf(shipped(), from, to); }

std::string refusal(const std::string& file) {
  try {
    loadThermalTestPiece(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(ThermalTestPiece, ShippedDescriptionHasTheThesisCounts) {
  const auto t = loadThermalTestPiece(shipped());
  const auto f = nominalFeatures(t);
  int z = 0, facets = 0;
  std::map<std::string, int> per_side;
  for (const auto& x : f) {
    if (x.role == "z_path") ++z;
    if (x.role == "facet") ++facets, ++per_side[x.group];
  }
  // Seed 004 L2039-L2047: 45 finished surfaces = 9 Z paths + 36 facets, 9 per side.
  EXPECT_EQ(z, 9);
  EXPECT_EQ(facets, 36);
  EXPECT_EQ(z + facets, 45);
  for (const char* s : {"X1", "Y1", "X2", "Y2"}) EXPECT_EQ(per_side[s], 9) << s;
  // 6 deg between neighbouring facets, 12 mm between neighbouring Z paths (L2041).
  for (int k = 1; k < 9; ++k) {
    EXPECT_NEAR(facetNormalAngle(t, FacetSide::X1, k + 1) - facetNormalAngle(t, FacetSide::X1, k), 6.0, 1e-12);
    EXPECT_NEAR(zPathY(t, k + 1) - zPathY(t, k), 12.0, 1e-12);
  }
  EXPECT_NEAR(zPathY(t, 5), 0.0, 1e-12);  // path 5 in the middle
  // The blank, the bands and the tools of L1990-L2024.
  EXPECT_EQ(t.blank_diameter_mm, 203);
  EXPECT_EQ(t.blank_height_mm, 25);
  ASSERT_EQ(t.bands.size(), 4u);
  EXPECT_EQ(t.bands[0].diameter_mm, 202);
  EXPECT_EQ(t.bands[3].diameter_mm, 199);
  EXPECT_EQ(t.tool(t.test_tool)->diameter_mm, 12);
  EXPECT_EQ(t.tool(t.face_tool)->diameter_mm, 16);
  EXPECT_EQ(t.tool(t.y_notch_tool)->diameter_mm, 8);
  EXPECT_EQ(t.x_notch_depth_mm, 12);
  EXPECT_NEAR(t.cut_depth_mm, 0.1, 1e-12);
}

TEST(ThermalTestPiece, OppositeFacetsAreParallelAndYFacetsMirrorX) {
  const auto t = loadThermalTestPiece(shipped());
  for (int k = 1; k <= 9; ++k) {
    const double x1 = facetNormalAngle(t, FacetSide::X1, k), x2 = facetNormalAngle(t, FacetSide::X2, k);
    const double y1 = facetNormalAngle(t, FacetSide::Y1, k), y2 = facetNormalAngle(t, FacetSide::Y2, k);
    EXPECT_NEAR(std::fmod(x2 - x1 + 360, 360), 180, 1e-9);
    EXPECT_NEAR(std::fmod(y2 - y1 + 360, 360), 180, 1e-9);
    EXPECT_NEAR(y1, 180 - x1, 1e-9);  // mirror about the Y axis
    // Each side's facets face into its own quadrant: X1 +X+Y, Y1 -X+Y, X2 -X-Y, Y2 +X-Y.
    EXPECT_GT(x1, 0);
    EXPECT_LT(x1, 90);
    EXPECT_GT(y1, 90);
    EXPECT_LT(y1, 180);
    EXPECT_GT(x2, 180);
    EXPECT_LT(x2, 270);
    EXPECT_GT(y2, 270);
    EXPECT_LT(y2, 360);
  }
}

TEST(ThermalTestPiece, FacetWidthFollowsTheApothemAndThePitch) {
  // Seed 004 L2047: facets 10.2 mm wide; a polygon of 6 deg pitch at apothem 97.5 mm has
  // sides 2 x 97.5 x tan 3 deg = 10.22 mm. The outermost facets are clipped by the notches.
  const auto t = loadThermalTestPiece(shipped());
  const double full = 2 * 97.5 * std::tan(degToRad(3));
  EXPECT_NEAR(full, 10.2, 0.05);
  for (const auto& f : nominalFeatures(t))
    if (f.role == "facet") {
      EXPECT_LE(2 * f.half_u_mm, full + 1e-9) << f.id;
      EXPECT_GT(2 * f.half_u_mm, 7.0) << f.id;  // 2 x (3 mm + 0.5 mm) of probing room at least
      EXPECT_NEAR(f.point_mm.head<2>().norm(), 97.5, 1e-9) << f.id;
      EXPECT_NEAR(2 * f.half_v_mm, 12.1, 1e-9) << f.id;  // L2047: 12 mm high (+ the 0.1 mm cut below the floor)
    }
}

TEST(ThermalTestPiece, CuttingCyclesFollowTheOrderAndTheLoad) {
  const auto t = loadThermalTestPiece(shipped());
  const auto c = cuttingCycles(t);
  ASSERT_EQ(c.size(), 9u);
  EXPECT_EQ(c[0].phase, "reference");
  EXPECT_EQ(c[0].z_path, 5);
  EXPECT_EQ(c[1].z_path, 1);
  EXPECT_EQ(c[8].z_path, 9);
  for (int i = 1; i <= 8; ++i) {
    EXPECT_EQ(c[i].phase, i <= 4 ? "warm_up" : "hold");
    EXPECT_EQ(c[i].c_axis_rpm_before, i <= 4 ? 1200 : 0);
  }
}

TEST(ThermalTestPiece, WorkpieceIsTheBlankOnItsAdapter) {
  const auto t = loadThermalTestPiece(shipped());
  const auto w = thermalTestPieceWorkpiece(t);
  EXPECT_TRUE(w.cylindrical);
  EXPECT_NEAR(w.blankRadius(), 101.5, 1e-12);
  EXPECT_NEAR(w.stock_max_mm.z(), 1.0, 1e-12);    // the blank stands 1 mm above the finished top
  EXPECT_NEAR(w.stock_min_mm.z(), -24.0, 1e-12);
  ASSERT_EQ(w.holes.size(), 3u);
  // Symmetric to the X axis (L1990): one on -X, the others mirrored.
  EXPECT_NEAR(w.holes[0].centre_mm.y(), 0, 1e-9);
  EXPECT_NEAR(w.holes[1].centre_mm.y(), -w.holes[2].centre_mm.y(), 1e-9);
  EXPECT_NEAR(w.holes[1].centre_mm.x(), w.holes[2].centre_mm.x(), 1e-9);
  const auto o = partOriginOnMachine(t, Eigen::Vector2d(1, 2), 0);
  EXPECT_NEAR(o.z(), 40 + 3 + 24, 1e-12);
  EXPECT_EQ(o.x(), 1);
}

TEST(ThermalTestPiece, ErrorsFromAShiftAGrowthAndADepth) {
  // Derived by hand: the table shifted by e in X while cycle i is cut. X1 is cut on the
  // machine's +X side of the C axis with the tool standing still, so the facet ends up e
  // closer to the part's centre; X2, cut on the -X side, e farther. A part cut warm by dT
  // is smaller at 20 °C by alpha dT a on every side.
  const double a = 97.5, e = 0.004, shrink = 23.4e-6 * 5 * a;
  TtpMeasures ref{a, a, a, a, 12.1, 0}, now{a - e - shrink, a + e - shrink, a - shrink, a - shrink, 12.1035, 7};
  const auto E = ttpErrors(now, ref);
  EXPECT_NEAR(E.EX_um, 4.0, 1e-9);
  EXPECT_NEAR(E.EY_um, 0.0, 1e-9);
  EXPECT_NEAR(E.ETTP_7_3_um, -2 * shrink * 1e3, 1e-9);  // the mean change of the two diameters
  EXPECT_NEAR(E.ETTP_7_9_um, -shrink * 1e3, 1e-9);      // one side: half of it (notes §11 item 11)
  EXPECT_NEAR(E.EZ_um, 3.5, 1e-9);
  EXPECT_NEAR(E.EB_urad, 7, 1e-12);
  // As printed, the reference distance d_X1(t0) does not cancel: about -a/2.
  EXPECT_NEAR(E.EX_printed_um, (now.d_X2_mm - a - now.d_X1_mm - a) / 2 * 1e3, 1e-9);
  EXPECT_LT(E.EX_printed_um, -48000);
}

TEST(ThermalTestPiece, GaugeFormsAgreeWithTheDistanceForms) {
  // Eqs. 7.7-7.9 with g = d(ti) - d(t0) are Eqs. 7.1, 7.2 (corrected) and half of Eq. 7.3.
  const TtpMeasures ref{97.5, 97.49, 97.51, 97.5, 12.1, 0}, now{97.497, 97.496, 97.512, 97.493, 12.1, 0};
  const auto E = ttpErrors(now, ref);
  const auto g = gaugeErrors((now.d_X1_mm - ref.d_X1_mm) * 1e3, (now.d_X2_mm - ref.d_X2_mm) * 1e3,
                             (now.d_Y1_mm - ref.d_Y1_mm) * 1e3, (now.d_Y2_mm - ref.d_Y2_mm) * 1e3);
  EXPECT_NEAR(g.EX_um, E.EX_um, 1e-9);
  EXPECT_NEAR(g.EY_um, E.EY_um, 1e-9);
  EXPECT_NEAR(g.ETTP_um, E.ETTP_7_9_um, 1e-9);
  EXPECT_NEAR(2 * g.ETTP_um, E.ETTP_7_3_um, 1e-9);
}

TEST(ThermalTestPiece, ThesisNumbersOfEquations76And710AndTable72) {
  // Eq. 7.6 (L2113): 22 um/(m K) x 10 K x 100 um = 0.022 um.
  EXPECT_NEAR(measurementDeviationEq76_um(22, 10, 100), 0.022, 1e-15);
  // Eq. 7.10 (L2177): 8 K of a cast-iron table (11 um/(m K)) at R = 160 mm is 14.1 um
  // (notes/seed004.md §5.5), and back.
  EXPECT_NEAR(temperatureEquivalentEq710_K(14.1, 11, 160), 8.0, 0.02);
  EXPECT_NEAR(temperatureEquivalentEq710_K(14.08, 11, 160), 8.0, 1e-12);
  // The test piece at R = 97.5 mm, aluminium 22 um/(m K): 8 K is 17.16 um.
  EXPECT_NEAR(temperatureEquivalentEq710_K(17.16, 22, 97.5), 8.0, 1e-3);
  // Table 7.2 (L2234): E_Y spans 15.8 -> 0.5 um (1 h) and 31 -> 2.9 um (8 h): the abstract's
  // -97 % and -91 % (L297).
  EXPECT_NEAR(spanReductionPercent(15.8, 0.5), 96.8, 0.05);
  EXPECT_NEAR(spanReductionPercent(31, 2.9), 90.6, 0.05);
  EXPECT_NEAR(spanReductionPercent(25.3, 9.1), 64.0, 0.05);  // E_Z, 8 h
  EXPECT_THROW(spanReductionPercent(0, 1), GeometryError);
  EXPECT_NEAR(span({0, 1.5, -2.1, 0.4}), 3.6, 1e-12);
}

TEST(ThermalTestPiece, TheThesisNotchWidthDoesNotHoldNinePaths) {
  // 9 paths x 12 mm pitch with the d12 tool span 108 mm: the thesis's 106 mm notch would
  // lose its flanks (the CMM's X datum); the loader says so and names the numbers.
  const auto msg = refusal(variant("width: 110 mm, depth: 12 mm", "width: 106 mm, depth: 12 mm"));
  EXPECT_NE(msg.find("span 108 mm"), std::string::npos) << msg;
  EXPECT_NE(msg.find("106 mm notch"), std::string::npos) << msg;
  EXPECT_TRUE(std::regex_search(msg, std::regex(R"(\.yaml:\d+: test\.z_paths\.pitch)"))) << msg;
}

TEST(ThermalTestPiece, BadDescriptionsNameTheLineAndTheKey) {
  EXPECT_TRUE(std::regex_search(refusal(variant("  wait: 1 h", "  wait: 1 h\n  wiat: 2 h")),
                                std::regex(R"(:\d+: unknown key 'test\.wiat')")));
  EXPECT_NE(refusal(variant("order: [5, 1, 2, 3, 4, 6, 7, 8, 9]", "order: [5, 1, 2, 3, 4, 6, 7, 8, 8]")).find("once"),
            std::string::npos);
  EXPECT_NE(refusal(variant("{phase: hold, cycles: 4", "{phase: hold, cycles: 3")).find("after the reference there are 8"),
            std::string::npos);
  EXPECT_NE(refusal(variant("tool: 3\n  spindle_speed", "tool: 7\n  spindle_speed")).find("T7 is not in the tools list"),
            std::string::npos);
  EXPECT_NE(refusal(variant("{phase: hold, cycles: 4, c_axis_speed: 0 rpm}", "{phase: hold, cycles: 4, c_axis_speed: 10 rpm}"))
                .find("NC hold"),
            std::string::npos);
  EXPECT_NE(refusal(variant("across: [-3 mm, 0 mm, 3 mm]", "across: [-4.5 mm, 0 mm, 4.5 mm]")).find("edge of facet X1_1"),
            std::string::npos);
  EXPECT_NE(refusal(variant("z: -16.5 mm", "z: -12.5 mm")).find("origin circle"), std::string::npos);
}

TEST(TestPieces, EveryKindLoadsIntoOneModel) {
  const auto ttp = loadTestPiece(shipped());
  EXPECT_EQ(ttp.kind, "thermal_test_piece");
  ASSERT_NE(ttp.thermalTestPiece(), nullptr);
  EXPECT_TRUE(ttp.stock.has_value());
  EXPECT_EQ(ttp.features.size(), 4u + 45u);  // TOP, FLANK_P, FLANK_N, CYL + 45 surfaces
  EXPECT_FALSE(ttp.evaluation.empty());
  std::set<std::string> ids;
  for (const auto& f : ttp.features) EXPECT_TRUE(ids.insert(f.id).second) << f.id;

  const auto sphere = loadTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/parts/sphere_artifact.yaml");
  EXPECT_EQ(sphere.kind, "sphere_artifact");
  ASSERT_NE(sphere.sphereArtifact(), nullptr);
  EXPECT_FALSE(sphere.stock.has_value());
  ASSERT_EQ(sphere.features.size(), 1u);
  EXPECT_NEAR(sphere.features[0].point_mm.x(), -160, 1e-9);  // angle_at_c0 180 deg, d/2 = 160 mm
  EXPECT_EQ(sphere.evaluation.size(), 7u);

  const auto block = loadTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/examples/workpiece_block.yaml");
  EXPECT_EQ(block.kind, "workpiece");
  EXPECT_TRUE(block.stock.has_value());

  const auto p = fs::temp_directory_path() / ("probeloop-kind-" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(p) << "kind: nas979\n";
  try {
    loadTestPiece(p.string());
    FAIL() << "accepted an unknown kind";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sphere_artifact, thermal_test_piece, stepped_workpiece, workpiece"), std::string::npos) << e.what();
  }
}

TEST(TestPieces, ExpansionLeversFollowTheGeometry) {
  // Derived by hand: a Z path cut warm at a fixed machine height lies alpha dT h deeper at
  // 20 C, h its height above the table (40 mm adapter + 3 mm washers + 24 mm piece - 12.1 mm);
  // Eq. 7.3 of a piece cut warm reads -2 a alpha dT (a = 97.5 mm).
  const auto ttp = expansionLevers(loadTestPiece(shipped()));
  EXPECT_NEAR(ttp.alpha_um_per_m_K, 23.4, 1e-12);
  EXPECT_NEAR(*ttp.lengthFor("EZ_um"), 40 + 3 + 24 - 12.1, 1e-9);
  EXPECT_NEAR(*ttp.lengthFor("ETTP_um"), -195, 1e-9);
  EXPECT_FALSE(ttp.lengthFor("EX_um").has_value());  // a uniform growth moves X1 and X2 alike
  const auto sphere = expansionLevers(loadTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/parts/sphere_artifact.yaml"));
  EXPECT_NEAR(*sphere.lengthFor("EZ0T_um"), 60 + 15 + 15, 1e-9);  // stem + ball diameter (centre + R)
  EXPECT_NEAR(*sphere.lengthFor("ER0T_um"), 160, 1e-9);
  EXPECT_THROW(expansionLevers(loadTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/examples/workpiece_block.yaml")), InputError);
}

TEST(PlanManifest, GenericKindRoundTrips) {
  PlanManifest m;
  m.file = "plan.json";
  m.kind = "thermal_test_piece";
  m.dialect = "linuxcnc";
  m.programs.push_back({"test.ngc", "linuxcnc", "", "test", 900, 29000});
  m.programs.push_back({"inspect.ngc", "linuxcnc", "ttp_probe.log", "inspection", 29900, 1500});
  m.part_name = "ttp";
  m.part_origin_mm = Eigen::Vector3d(0, 0, 67);
  m.material_name = "AlMgSi1";
  m.material_alpha_um_per_m_K = 23.4;
  m.ttp.z_paths = 9;
  m.ttp.facets_per_segment = 9;
  m.ttp.eq_7_10_alpha_um_per_m_K = 22;
  m.ttp.eq_7_10_radius_mm = 97.5;
  m.ttp.cmm.mpe_constant_um = 1.2;
  m.ttp.cmm_plan = "cmm_points.csv";
  const auto t = loadThermalTestPiece(shipped());
  for (const auto& f : nominalFeatures(t)) {
    ManifestFeature x;
    x.nominal = f;
    x.cycle = f.index == 5 ? 0 : -1;
    x.position = static_cast<int>(m.features.size()) + 1;
    m.features.push_back(x);
  }
  m.cut_cycles.push_back({0, "reference", 0, 900, 935, 5, 5, 60.5, 29.5});
  m.cuts.push_back({"c0.X1", "test.ngc", "X1_5", 0, 3, 60.5, 905, 910, Eigen::Vector3d(103.5, 45, 54.9),
                    Eigen::Vector3d(103.5, -45, 54.9)});
  ManifestPoint p;
  p.feature = "X1_5";
  p.position = m.feature("X1_5")->position;
  p.point = 1;
  p.contact_mm = Eigen::Vector3d(100.5, -3, 64);
  p.approach = Eigen::Vector3d(-1, 0, 0);
  p.c_deg = 60.5;
  m.points.push_back(p);
  m.evaluation = thermalTestPieceEvaluation();
  m.cycles = 1;
  m.cycle_start_s = {29900};
  const auto path = fs::temp_directory_path() / ("probeloop-manifest-" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << manifestToJson(m);
  const auto r = readManifest(path.string());
  PlanManifest r2 = r;
  r2.file = m.file;
  EXPECT_EQ(manifestToJson(r2), manifestToJson(m));
  ASSERT_NE(r.program("inspection"), nullptr);
  EXPECT_EQ(r.program("inspection")->log_file, "ttp_probe.log");
  EXPECT_EQ(r.featureAtPosition(p.position)->nominal.id, "X1_5");
  EXPECT_NEAR(r.feature("X1_5")->nominal.angle_deg, facetNormalAngle(t, FacetSide::X1, 5), 1e-12);
}

}  // namespace
}  // namespace probeloop::parts
