// The truth of a machined thermal test piece (truth.json: as-cut features, datum frame,
// E_X ... E_TTP per cutting cycle). A reduced test, written here as G-code: pre-machining
// (face the top, the datum band by turning C, the large X notch), then the reference cycle
// (Z path 5 and facet 5 of each side), an hour's wait, and cycle 1 (Z path 1, facet 1), cut
// as the thesis cuts them: X1 on the machine's +X side of the C axis moving -Y, Y1 on +Y
// moving -X, X2 on -X, Y2 on -Y, each facet indexed to face its side (seed 004 Fig. 7.4).
// Every expectation is derived from the effect's definition.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <fstream>
#include <sstream>

#include "core/csv.hpp"
#include "core/units.hpp"
#include "parts/test_piece.hpp"
#include "sim/test_support.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::sim {
namespace {

using Eigen::Vector3d;
using parts::FacetSide;
using test::src;
using test::truthFrom;

constexpr double kUm = 1e-6;  // um: the as-cut surfaces are exact, the fits of exact points too

struct Setup {
  parts::Machine machine = parts::loadMachine(src("parts/machines/nmv5000.yaml"));
  parts::TestPiece piece;
  const parts::ThermalTestPiece& ttp() const { return *piece.thermalTestPiece(); }
  std::string pre, test;
};

// The shipped piece. Reduced (the default): two cutting cycles (reference: path/facet 5;
// cycle 1: 1), pre-machining only what the datums need, without cutting forces (their
// deflection differs between facets clipped differently by the notch, an effect of its own).
// Forces off unless asked for. Full: the shipped nine cycles with the shipped load between them (an hour of C at 1200 rpm
// as G1 C+-72000 moves with the tool waiting at (-130, 0) at the cutting height, or an hour's
// NC hold), all four bands, the mark, both notches and the 36 pre-cut facets, forces on, and
// a ring move (G2 about the axis at 130 mm) to the waiting position after each cycle.
Setup setup(bool full = false, bool forces = false) {
  Setup s;
  auto t = parts::loadThermalTestPiece(src("parts/thermal_test_piece.yaml"));
  if (!full) {
    t.order = {5, 1};
    t.load = {{"warm_up", 1, 1200}};
  }
  if (!forces) t.material.radial_force_ratio = 0;
  s.piece.kind = "thermal_test_piece";
  s.piece.features = parts::nominalFeatures(t);
  s.piece.stock = parts::thermalTestPieceWorkpiece(t);
  s.piece.description = t;
  const Vector3d o = parts::partOriginOnMachine(t, s.machine.c_axis_centre_mm, s.machine.table_surface_z_mm);
  const double sense = s.machine.c.positive_is_clockwise ? -1.0 : 1.0;  // part angle th shows at th + sense C
  auto X = [&](double x) { return " X" + formatNumber(x + o.x(), 6); };
  auto Y = [&](double y) { return " Y" + formatNumber(y + o.y(), 6); };
  auto Z = [&](double z) { return " Z" + formatNumber(z + o.z(), 6); };
  const std::string head = "G21 G90 G17 G94\nG10 L2 P6 X0 Y0 Z0 C0\nG59\n";
  const double up = 10;
  struct Side {
    FacetSide side;
    double faces_deg;  // the machine direction the facet's normal faces when it is cut
    double x0, y0, x1, y1;
  };
  // The four sides' cuts for a tool centre at distance c from the axis, +-L along the chord.
  auto sides = [](double c, double L) {
    return std::vector<Side>{{FacetSide::X1, 0, c, L, c, -L},
                             {FacetSide::Y1, 90, L, c, -L, c},
                             {FacetSide::X2, 180, -c, L, -c, -L},
                             {FacetSide::Y2, 270, L, -c, -L, -c}};
  };
  auto facet = [&](std::ostringstream& o_, const Side& sd, int k, double z) {
    const double c_deg = (sd.faces_deg - parts::facetNormalAngle(t, sd.side, k)) / sense;
    o_ << "G0 C" << formatNumber(c_deg, 6) << "\nG0" << X(sd.x0) << Y(sd.y0) << "\nG0" << Z(z) << "\nG1" << X(sd.x1) << Y(sd.y1)
       << " F1500\nG0" << Z(up) << "\n";
  };

  // Pre-machining with the d16 (T1): face to z 0; the bands by one turn of C each with the
  // tool at D/2 + 8 (600 mm/min at the edge: 600 / (pi D) turns/min), from the lowest up (the
  // reduced piece: only the datum band Ø201 from z -19); the X notch 110 wide, 12 deep in seven
  // passes (flanks at y = +-55 by the passes at +-47).
  std::ostringstream p;
  p << head << "T1 M6\nG43 H1\nS6000 M3\nG0" << X(-115) << Y(-104) << Z(up) << "\nG0" << Z(0) << "\n";
  for (int k = 0; k <= 17; ++k) {
    p << "G1" << X(k % 2 ? -115 : 115) << " F1500\n";
    if (k < 17) p << "G1" << Y(-104 + 12 * (k + 1)) << "\n";
  }
  p << "G0" << Z(up) << "\n";
  std::vector<parts::TtpBand> bands;
  for (const auto& b : t.bands)
    if (full || std::fabs(b.diameter_mm - t.datum_band_diameter_mm) < 1e-9) bands.push_back(b);
  for (const auto& b : bands) {
    p << "G0" << X(b.diameter_mm / 2 + 8) << Y(0) << "\nG1" << Z(b.z_from_mm) << " F300\n";
    p << "G1 C360 F" << formatNumber(600 / (kPi * b.diameter_mm) * 360, 6) << "\nG0" << Z(up) << "\nG0 C0\n";
  }
  const double w = t.x_notch_width_mm / 2 - 8;
  p << "G0" << X(-115) << Y(-w) << "\nG0" << Z(-t.x_notch_depth_mm) << "\n";
  for (int k = 0; k < 7; ++k) {
    p << "G1" << X(k % 2 ? -115 : 115) << " F1500\n";
    if (k < 6) p << "G1" << Y(-w + 2 * w * (k + 1) / 6) << "\n";
  }
  p << "G0" << Z(up) << "\n";
  if (full) {
    // The 36 facets with their allowance, down to the notch floor.
    for (int k = 1; k <= t.facets_per_segment; ++k)
      for (const auto& sd : sides(t.facet_apothem_mm + t.facet_allowance_mm + 8, 45)) facet(p, sd, k, -t.x_notch_depth_mm);
    p << "G0 C0\nM5\n";
    // The Y notch (d8, two passes 10 wide, 13 deep) and the mark (engraving, 0.2 deep).
    p << "T2 M6\nG43 H2\nS6000 M3\nG0" << X(-1) << Y(-115) << "\nG0" << Z(-t.y_notch_depth_mm) << "\nG1" << Y(115)
      << " F1500\nG1" << X(1) << "\nG1" << Y(-115) << "\nG0" << Z(up) << "\nM5\n";
    p << "T4 M6\nG43 H4\nS6000 M3\nG0" << X(t.mark_from_mm.x()) << Y(t.mark_from_mm.y()) << "\nG1" << Z(-t.mark_depth_mm)
      << " F200\nG1" << X(t.mark_to_mm.x()) << Y(t.mark_to_mm.y()) << "\nG0" << Z(up) << "\n";
  }
  p << "M5\nM2\n";
  s.pre = p.str();

  // The test with the d12 (T3) at the cutting height.
  const double a = t.facet_apothem_mm, r = t.tool(t.test_tool)->diameter_mm / 2, zc = t.cuttingZ(), L = 45;
  const auto cycles = parts::cuttingCycles(t);
  std::ostringstream q;
  q << head << "T3 M6\nG43 H3\nS8000 M3\n";
  for (const auto& cc : cycles) {
    const int k = cc.z_path;
    if (cc.cycle > 0 && !full) q << "G4 P3600\n";
    if (cc.cycle > 0 && full) {
      // The hour before this cycle: C at its speed with the tool waiting (below the top),
      // or an NC hold.
      q << "G0 C0\nG0" << X(-130) << Y(0) << "\nG0" << Z(zc) << "\n";
      if (cc.c_axis_rpm_before > 0) {
        const double F = cc.c_axis_rpm_before * 360, turn = F / 60 * t.c_turn_move_s;
        for (int n = 0; n < static_cast<int>(t.wait_s / (2 * t.c_turn_move_s)); ++n)
          q << "G1 C" << formatNumber(turn, 6) << " F" << formatNumber(F, 6) << "\nG1 C0\n";
      } else {
        q << "G4 P" << formatNumber(t.wait_s) << "\n";
      }
      // Around the part on a ring at 130 mm and back (G2 chords), then up.
      q << "G2" << X(130) << Y(0) << " I130 J0 F1500\nG2" << X(-130) << Y(0) << " I-130 J0\nG0" << Z(up) << "\n";
    }
    q << "G0 C0\nG0" << X(-115) << Y(parts::zPathY(t, k)) << Z(up) << "\nG0" << Z(zc) << "\nG1" << X(115) << " F1500\nG0" << Z(up)
      << "\n";
    for (const auto& sd : sides(a + r, L)) facet(q, sd, cc.facet, zc);
  }
  q << "M5\nM2\n";
  s.test = q.str();
  return s;
}

nlohmann::json simulate(const Setup& s, const MachineTruth& truth, SimulationOutputs* keep = nullptr) {
  SimulationPart part;
  part.test_piece = &s.piece;
  const auto out = simulatePrograms({{"pre.ngc", s.pre}, {"test.ngc", s.test}}, s.machine, part, truth, 1);
  if (keep) *keep = out;
  return nlohmann::json::parse(out.truth_json);
}

const nlohmann::json& feature(const nlohmann::json& truth, const std::string& id) {
  for (const auto& f : truth["features"])
    if (f["id"] == id) return f;
  throw std::runtime_error("no feature " + id);
}

double cutTime(const nlohmann::json& truth, const std::string& id) { return feature(truth, id)["cut_time_s"].get<double>(); }

// The time between the reference cycle and cycle 1, when the tests change the machine: after
// the last cut of cycle 0, before the first of cycle 1 (checked on the run without effects).
struct Gap {
  double from_s, to_s;
};
Gap gap(const nlohmann::json& truth) {
  double last0 = 0, first1 = 1e300;
  for (const auto& side : {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2}) {
    last0 = std::max(last0, cutTime(truth, parts::facetId(side, 5)));
    first1 = std::min(first1, cutTime(truth, parts::facetId(side, 1)));
  }
  last0 = std::max(last0, cutTime(truth, "Z5"));
  first1 = std::min(first1, cutTime(truth, "Z1"));
  return {last0, first1};
}

TEST(TtpTruth, WithoutEffectsEveryErrorIsZero) {
  const auto s = setup();
  const auto j = simulate(s, truthFrom(""));
  // The datum frame is the part frame: origin on the axis in the faced top, axes along X, Y, Z.
  const auto& d = j["datum_frame"];
  ASSERT_TRUE(d.contains("origin_mm")) << d.dump();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(d["origin_mm"][k].get<double>(), 0, 1e-9);
    EXPECT_NEAR(d["x"][k].get<double>(), k == 0, 1e-12);
    EXPECT_NEAR(d["y"][k].get<double>(), k == 1, 1e-12);
    EXPECT_NEAR(d["z"][k].get<double>(), k == 2, 1e-12);
  }
  // The datum band: radius 100.5, cut by the turn (not the blank).
  EXPECT_NEAR(feature(j, "CYL")["as_cut"]["radius_mm"].get<double>(), 100.5, 1e-9);
  EXPECT_GE(feature(j, "CYL")["cut_index"].get<int>(), 0);
  // The cut facets lie at the apothem, the cut Z paths 12.1 below the top.
  for (const auto& side : {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2})
    for (int k : {5, 1}) EXPECT_NEAR(feature(j, parts::facetId(side, k))["as_cut"]["d_mm"].get<double>(), 97.5, 1e-9);
  for (const char* id : {"Z5", "Z1"}) EXPECT_NEAR(feature(j, id)["as_cut"]["depth_mm"].get<double>(), 12.1, 1e-9);
  ASSERT_EQ(j["ttp_cycles"].size(), 2u);
  const auto& c1 = j["ttp_cycles"][1];
  for (const char* e : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "ETTP_7_9_um"})
    EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
  const Gap g = gap(j);
  EXPECT_GT(g.to_s - g.from_s, 3600);  // the hour's wait lies between the cycles
  EXPECT_LT(j["ttp_cycles"][0]["time_s"].get<double>(), c1["time_s"].get<double>());
}

// EX0C steps by +e = 4 um between the cycles. X1 is cut on the machine's +X side with the
// tool still in X: the table shifted +e brings the facet e closer to the axis (d_X1 - e); X2
// on the -X side lies e farther (d_X2 + e); the Y facets are cut along X, which the shift
// only moves along themselves. E_X = (dd_X2 - dd_X1) / 2 = +e; E_Y, E_Z, E_B, E_TTP stay 0.
TEST(TtpTruth, ATableShiftInXIsEX) {
  const auto s = setup();
  const Gap g = gap(simulate(s, truthFrom("")));
  const double t = g.from_s + 600;
  ASSERT_LT(t + 1, g.to_s);
  const auto j = simulate(s, truthFrom("location_keyframes: [{time: " + formatNumber(t) + " s}, {time: " + formatNumber(t + 1) +
                                       " s, EX0C_um: 4}]\n"));
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["EX_um"].get<double>(), 4, kUm);
  for (const char* e : {"EY_um", "EZ_um", "EB_urad", "ETTP_um", "ETTP_7_9_um"}) EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
  EXPECT_NEAR(feature(j, "X1_1")["as_cut"]["d_mm"].get<double>(), 97.5 - 0.004, 1e-9);
  EXPECT_NEAR(feature(j, "X2_1")["as_cut"]["d_mm"].get<double>(), 97.5 + 0.004, 1e-9);
  // The machine state of the cut that made X1_1 carries the step.
  EXPECT_NEAR(feature(j, "X1_1")["machine"]["EX0C_um"].get<double>(), 4, 1e-12);
  EXPECT_NEAR(feature(j, "X1_5")["machine"]["EX0C_um"].get<double>(), 0, 1e-12);
}

// The tool grows 5 um along +Z between the cycles (a column node following a +1 K step of
// the hall within milliseconds, 5 um/K): Z path 1 is cut 5 um shallower, E_Z = d_Z(t1) -
// d_Z(t0) = -5 um; the facets, cut by the tool's flank, do not move.
TEST(TtpTruth, ToolGrowthIsMinusEZ) {
  const auto s = setup();
  const Gap g = gap(simulate(s, truthFrom("")));
  const double t = g.from_s + 600;
  const auto j = simulate(s, truthFrom(R"(
thermal:
  environment: {mean_C: 20, events: [{at: )" + formatNumber(t) + R"( s, change_K: 1, ramp: 1 s}]}
  nodes: [{name: column, capacity_J_per_K: 1, to_environment_W_per_K: 1000,
           displacement_per_K: {tool_Z_um_per_K: 5}}]
)"));
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["EZ_um"].get<double>(), -5, kUm);
  for (const char* e : {"EX_um", "EY_um", "EB_urad", "ETTP_um"}) EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
  EXPECT_NEAR(feature(j, "Z1")["machine"]["tool_um"][2].get<double>(), 5, 1e-9);
}

// The part is dT = 5 K warm when cycle 1 is cut (its node follows the hall's +5 K step), the
// reference was cut at 20 C. Cut warm and measured at 20 C, the tool centre at a + r from the
// axis (radius r) leaves a facet at a / k, k = 1 + alpha dT (expansion about the datum on the
// axis): each facet comes a alpha dT / k closer, so Eq. 7.3's E_TTP = (dl_X + dl_Y) / 2 =
// -2 a alpha dT / k (-2 alpha dT a to first order, 2.7 nm apart), Eq. 7.9 half of it, E_X =
// E_Y = 0. The Z path, cut with the tool's bottom 11.9 mm above the datum (the blank's bottom,
// z -24), comes out at -24 + 11.9 / k: 11.9 alpha dT / k deeper below the (cold) top: E_Z > 0.
TEST(TtpTruth, AWarmPartIsMinusTwoAlphaDTa) {
  const auto s = setup();
  const Gap g = gap(simulate(s, truthFrom("")));
  const double t = g.from_s + 600;
  const auto j = simulate(s, truthFrom(R"(
thermal:
  environment: {mean_C: 20, events: [{at: )" + formatNumber(t) + R"( s, change_K: 5, ramp: 1 s}]}
  nodes: [{name: part, capacity_J_per_K: 1, to_environment_W_per_K: 1000}]
artifact: {node: part, alpha_um_per_m_K: 23.4}
)"));
  const double a = 97.5, alpha = 23.4e-6, dT = 5, k = 1 + alpha * dT;
  ASSERT_DOUBLE_EQ(s.ttp().facet_apothem_mm, a);
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["ETTP_um"].get<double>(), -2 * a * alpha * dT / k * 1e3, kUm);
  EXPECT_NEAR(c1["ETTP_um"].get<double>(), -2 * alpha * dT * a * 1e3, 3e-3);
  EXPECT_NEAR(c1["ETTP_7_9_um"].get<double>(), -a * alpha * dT / k * 1e3, kUm);
  EXPECT_NEAR(c1["EX_um"].get<double>(), 0, kUm);
  EXPECT_NEAR(c1["EY_um"].get<double>(), 0, kUm);
  const double above_datum = s.ttp().finishedHeight() + s.ttp().cuttingZ();  // 24 - 12.1 = 11.9
  EXPECT_NEAR(c1["EZ_um"].get<double>(), above_datum * alpha * dT / k * 1e3, kUm);
  EXPECT_NEAR(feature(j, "X1_1")["machine"]["part_dT_K"].get<double>(), dT, 1e-9);
}

// The whole test as the thesis runs it (9 cycles, 4 h of C at 1200 rpm = 1440 rotary feed
// moves with the tool waiting below the top, 4 h hold, ring moves of ~1200 chords each): the
// simulator carries it (in seconds in a Release build) and, without effects, every cycle's
// errors are 0 and every facet and Z path of the test lies where the drawing puts it.
TEST(TtpTruth, TheWholeTestWithoutEffectsIsNominal) {
  const auto s = setup(true);
  SimulationOutputs out;
  auto truth = truthFrom("");
  const auto j = simulate(s, truth, &out);
  EXPECT_GT(out.end_time_s, 8 * 3600);
  ASSERT_EQ(j["ttp_cycles"].size(), 9u);
  for (const auto& c : j["ttp_cycles"]) {
    ASSERT_TRUE(c.contains("EX_um")) << c.dump();
    for (const char* e : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}) EXPECT_NEAR(c[e].get<double>(), 0, kUm) << c["cycle"] << e;
    EXPECT_NEAR(c["d_X1_mm"].get<double>(), 97.5, 1e-9);
    EXPECT_NEAR(c["d_Z_mm"].get<double>(), 12.1, 1e-9);
  }
  // The C load: 1200 rpm in the inputs while the table turns in the warm-up hours.
  const CsvTable in = parseCsv(out.inputs_csv, "inputs");
  int turning = 0;
  for (const auto& row : in.rows) turning += in.number(row, in.column("c_rpm")) == 1200;
  EXPECT_GE(turning, 4 * 59);
  // The top, sampled on a grid that crosses the engraved mark (0.2 mm deep) and the notches,
  // is the faced plane z 0.
  EXPECT_NEAR(feature(j, "TOP")["as_cut"]["point_mm"][2].get<double>(), 0, 1e-9);
}

// With the demo physics (examples/truth_thermal_test.yaml) and the cutting forces on: every
// cycle is evaluated, the runs are byte-identical, and the printout is the 8 h series the
// evaluation of the simulated CMM and on-machine data will be compared with.
TEST(TtpTruth, TheWholeTestWithTheDemoPhysics) {
  const auto s = setup(true, true);
  const auto truth = loadMachineTruth(src("examples/truth_thermal_test.yaml"));
  SimulationOutputs a, b;
  const auto j = simulate(s, truth, &a);
  simulate(s, truth, &b);
  EXPECT_EQ(a.truth_json, b.truth_json);
  EXPECT_EQ(a.cuts_json, b.cuts_json);
  EXPECT_EQ(a.inputs_csv, b.inputs_csv);
  if (const char* dir = std::getenv("PROBELOOP_TTP_DUMP")) {  // for a look at the files
    for (const auto& [name, text] : {std::pair{"truth.json", a.truth_json}, {"cuts.json", a.cuts_json}, {"inputs.csv", a.inputs_csv},
                                     {"pre.ngc", s.pre}, {"test.ngc", s.test}})
      std::ofstream(std::string(dir) + "/" + name) << text;
  }
  ASSERT_EQ(j["ttp_cycles"].size(), 9u);
  for (const auto& c : j["ttp_cycles"]) {
    ASSERT_TRUE(c.contains("ETTP_um")) << c.dump();
    std::printf("cycle %d t %7.0f s  EX %7.3f  EY %7.3f  EZ %7.3f  EB %7.3f  ETTP %7.3f um\n", c["cycle"].get<int>(),
                c["time_s"].get<double>(), c["EX_um"].get<double>(), c["EY_um"].get<double>(), c["EZ_um"].get<double>(),
                c["EB_urad"].get<double>(), c["ETTP_um"].get<double>());
  }
}

}  // namespace
}  // namespace probeloop::sim
