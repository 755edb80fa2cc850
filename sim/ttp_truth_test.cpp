// The truth of a machined thermal test piece (truth.json: as-cut features, datum frame,
// E_X ... E_TTP per cutting cycle). A reduced test, written here as G-code: pre-machining
// (face the top, the datum band by turning C, the large X notch), then the reference cycle
// (Z path 5 and facet 5 of each side), an hour's wait, and cycle 1 (Z path 1, facet 1), cut
// as the thesis cuts them: X1 on the machine's +X side of the C axis moving -Y, Y1 on +Y
// moving -X, X2 on -X, Y2 on -Y, each facet indexed to face its side (seed 004 Fig. 7.4).
// Every expectation is derived from the effect's definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "core/csv.hpp"
#include "core/units.hpp"
#include "parts/piece_kinds.hpp"
#include "sim/test_support.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::sim {
namespace {

using Eigen::Vector3d;
using parts::FacetSide;
using test::src;
using test::truthFrom;

constexpr double kUm = 1e-6;  // um: the as-cut surfaces are exact, the fits of exact points too

// Under the sanitizers (ASan + UBSan, a Debug build: ~50x slower) the whole test waits 10 min
// between its cutting cycles instead of the shipped hour: the same code paths (pre-machining,
// the C load's feed moves with the tool waiting below the top, the NC hold, the rings, nine
// cycles) with a sixth of the load moves. A Release build runs the full 8 h.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kShortWait = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kShortWait = true;
#else
constexpr bool kShortWait = false;
#endif
#else
constexpr bool kShortWait = false;
#endif

struct Setup {
  parts::Machine machine = parts::loadMachine(src("parts/machines/nmv5000.yaml"));
  parts::TestPiece piece;
  const parts::ThermalTestPiece& ttp() const { return *piece.thermalTestPiece(); }
  std::string pre, test;
};

// The shipped piece. Reduced (the default): two cutting cycles (reference: path/facet 5;
// cycle 1: 1), pre-machining only what the datums need, without cutting forces (their
// deflection differs between facets clipped differently by the notch, an effect of its own).
// Forces off unless asked for. Full: the shipped nine cycles with the shipped load between
// them (the description's wait, an hour, 10 min under the sanitizers (kShortWait): C at 1200
// rpm as incremental G91 G1 C+-72000 moves with the tool waiting at (-130, 0) at the cutting height, or an NC
// hold), all four bands, the mark, both notches and the 36 pre-cut facets, and a ring move
// (G2 about the axis at 130 mm) to the waiting position after each cycle.
Setup setup(bool full = false, bool forces = false) {
  Setup s;
  std::string description_file = src("parts/thermal_test_piece.yaml");
  if (full && kShortWait) {
    // The description's own text with the shorter wait (the loader checks it as any other).
    std::ifstream in(description_file);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string from = "wait: 1 h", to = "wait: 10 min";
    const auto at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("no '" + from + "' in " + description_file);
    description_file = test::writeTemp("thermal_test_piece.yaml", text.replace(at, from.size(), to));
  }
  auto t = parts::loadThermalTestPiece(description_file);
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
  const double sense = parts::tableTurnSign(s.machine.c.positive_is_clockwise);  // part angle th shows at th + sense C
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

// 10 min into the wait between the reference cycle and cycle 1, from a run without errors:
// a step there reaches every cut of cycle 1 and none of the reference.
double betweenTheCycles_s(const Setup& s) {
  const Gap g = gap(simulate(s, truthFrom("")));
  const double t = g.from_s + 600;
  if (!(t + 1 < g.to_s)) throw std::logic_error("the wait between the reference and cycle 1 is under 10 min");
  return t;
}

// A location error stepping from 0 to `error` (e.g. "EX0C_um: 4") within 1 s at t.
std::string locationStep(double t, const std::string& error) {
  return "location_keyframes: [{time: " + formatNumber(t) + " s}, {time: " + formatNumber(t + 1) + " s, " + error + "}]\n";
}

// How much deeper than a ramp tilted by theta along its path a flat end mill that stays
// horizontal in the part frame leaves the floor, per unit theta, as the truth's plane fit
// sees it (the EB0C test): the mean of sqrt(r^2 - y^2) over its sample rows, y = 0 and
// +-0.8 of the path's nominal half width (three rows: the half width, r, is under 10 mm).
double floorRowsDepth(const Setup& s) {
  const double r = s.ttp().tool(s.ttp().test_tool)->diameter_mm / 2;
  double half_v = 0;
  for (const auto& f : s.piece.features)
    if (f.id == "Z1") half_v = f.half_v_mm;
  EXPECT_NEAR(half_v, r, 1e-12);
  const double y = 0.8 * half_v;
  return (2 * std::sqrt(r * r - y * y) + r) / 3;
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
  const auto j = simulate(s, truthFrom(locationStep(betweenTheCycles_s(s), "EX0C_um: 4")));
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["EX_um"].get<double>(), 4, kUm);
  for (const char* e : {"EY_um", "EZ_um", "EB_urad", "ETTP_um", "ETTP_7_9_um"}) EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
  EXPECT_NEAR(feature(j, "X1_1")["as_cut"]["d_mm"].get<double>(), 97.5 - 0.004, 1e-9);
  EXPECT_NEAR(feature(j, "X2_1")["as_cut"]["d_mm"].get<double>(), 97.5 + 0.004, 1e-9);
  // The machine state of the cut that made X1_1 carries the step.
  EXPECT_NEAR(feature(j, "X1_1")["machine"]["EX0C_um"].get<double>(), 4, 1e-12);
  EXPECT_NEAR(feature(j, "X1_5")["machine"]["EX0C_um"].get<double>(), 0, 1e-12);
}

// EY0C steps by +e = 4 um between the cycles. Y1 is cut on the machine's +Y side moving -X:
// the table shifted +e in Y brings it e closer to the axis (d_Y1 - e); Y2 on the -Y side lies
// e farther (d_Y2 + e); the X facets are cut along Y, which the shift only moves along
// themselves, and the Z path along X keeps its depth. E_Y = (dd_Y2 - dd_Y1) / 2 = +e (Eq. 7.2
// sign corrected); E_X, E_Z, E_B, E_TTP stay 0.
TEST(TtpTruth, ATableShiftInYIsEY) {
  const auto s = setup();
  const auto j = simulate(s, truthFrom(locationStep(betweenTheCycles_s(s), "EY0C_um: 4")));
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["EY_um"].get<double>(), 4, kUm);
  for (const char* e : {"EX_um", "EZ_um", "EB_urad", "ETTP_um", "ETTP_7_9_um"}) EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
  EXPECT_NEAR(feature(j, "Y1_1")["as_cut"]["d_mm"].get<double>(), 97.5 - 0.004, 1e-9);
  EXPECT_NEAR(feature(j, "Y2_1")["as_cut"]["d_mm"].get<double>(), 97.5 + 0.004, 1e-9);
  EXPECT_NEAR(feature(j, "Y1_1")["machine"]["EY0C_um"].get<double>(), 4, 1e-12);
}

// EB0C steps by theta = 20 urad between the cycles: the table (and the part) tilted right-
// handedly about +Y through the C axis at the table surface. A point h above the pivot at
// machine x lies in the table at x' = x cos(theta) - h sin(theta), z' = x sin(theta) +
// h cos(theta) (R_y(-theta) applied to it). The tool tip cuts at h = H = adapter 40 + washers
// 3 + finished height 24 - 12.1 = 54.9 mm above the table:
// - the Z path, cut along +X, rises by theta per mm of x in the part: its floor's normal is
//   (-theta, 0, 1), beta = atan2(n_x, n_z) = -theta, so E_B = -theta (docs/thermal-test-
//   piece.md §4). The tool's flat bottom stays horizontal in the part frame (the simulator
//   does not tilt the tool with the table, docs/simulator.md §5), so at a distance y from the
//   path's centre line the floor is the lowest point of the ramp within sqrt(r^2 - y^2) of
//   x: theta sqrt(r^2 - y^2) deeper than the ramp. The truth samples the floor on three rows
//   (the path's nominal half width is r = 6 mm, < 10 mm) at y = 0, +-0.8 r = +-4.8 mm
//   (sqrt(36 - 4.8^2) = 3.6): the fitted plane lies theta (3.6 + 6 + 3.6) / 3 = 4.4 theta
//   deeper at the centre, E_Z = 4.4 mm x theta = 0.088 um, less up to delta (below); the
//   tip's own height at x' = 0 moves by H (1/cos(theta) - 1), 1e-8 um;
// - X1, cut at x = a + r, comes H sin(theta) closer to the axis, X2 at -(a + r) as much
//   farther: E_X = H sin(theta) = 1.098 um, an Abbe offset of the tilt (the lever from the
//   pivot to the tip); both come (a + r)(1 - cos(theta)) = 2e-5 um closer: the E_TTP of it;
// - the Y facets, cut along X, do not move (y' = y).
// The floor is a ramp in the part, stored as horizontal pieces at their upper Z, each
// changing z by at most delta = 1e-5 mm (docs/simulator.md §2.4): a least-squares slope
// through such a staircase on sample points x_i is off by at most
// (delta / 2) sum |x_i - mean| / sum (x_i - mean)^2, for samples evenly spread over a span L
// 1.5 delta / L; the reference's floor is flat. The depth lies up to delta higher (pieces at
// their upper Z).
TEST(TtpTruth, ATableTiltAboutYIsMinusEB) {
  const auto s = setup();
  const double theta = 20e-6;
  const auto j = simulate(s, truthFrom(locationStep(betweenTheCycles_s(s), "EB0C_urad: 20")));
  const double H = 40 + 3 + 24 - 12.1, a = 97.5, r = 6, delta = 1e-5;
  ASSERT_NEAR(s.ttp().supportHeight() + s.ttp().finishedHeight() + s.ttp().cuttingZ(), H, 1e-12);
  double half_u = 0;  // Z1's half length: the samples span 80 % of it each way
  for (const auto& f : s.piece.features)
    if (f.id == "Z1") half_u = f.half_u_mm;
  const double slope_bound = 1.5 * delta / (1.6 * half_u);
  const double rows = floorRowsDepth(s);
  EXPECT_NEAR(rows, 4.4, 1e-12);
  const auto& c1 = j["ttp_cycles"][1];
  EXPECT_NEAR(c1["EB_urad"].get<double>(), -theta * 1e6, slope_bound * 1e6);
  EXPECT_NEAR(c1["EX_um"].get<double>(), H * std::sin(theta) * 1e3, kUm);
  EXPECT_NEAR(c1["ETTP_um"].get<double>(), (a + r) * (std::cos(theta) - 1) * 1e3, kUm);
  EXPECT_NEAR(c1["EY_um"].get<double>(), 0, kUm);
  EXPECT_NEAR(c1["EZ_um"].get<double>(), (rows * theta - delta / 2) * 1e3, delta / 2 * 1e3);
  EXPECT_NEAR(feature(j, "Z1")["machine"]["EB0C_urad"].get<double>(), 20, 1e-12);
}

// The tool grows 5 um along +Z between the cycles (a column node following a +1 K step of
// the hall within milliseconds, 5 um/K): Z path 1 is cut 5 um shallower, E_Z = d_Z(t1) -
// d_Z(t0) = -5 um; the facets, cut by the tool's flank, do not move.
TEST(TtpTruth, ToolGrowthIsMinusEZ) {
  const auto s = setup();
  const double t = betweenTheCycles_s(s);
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
// E_Y = 0. The Z path: the tool's tip is H = S + h = 54.9 mm above the table, S = adapter 40
// + washers 3 = 43 mm, h = 24 - 12.1 = 11.9 mm the path's height above the piece's bottom
// (the datum). The support (the part's alloy, at its temperature) has lifted the bottom by
// alpha dT S and the part has grown about it by k: the tool cuts H - S k above the warm
// bottom, which is H / k - S above it at 20 C. The cold top is 24 above the bottom, so the
// path's depth is 24 + S - H / k against the cold reference's 24 + S - H: E_Z = H (1 - 1/k)
// = alpha dT (S + h) / k, the path lies deeper at 20 C (the lever parts::expansionLevers
// gives for E_Z).
TEST(TtpTruth, AWarmPartIsMinusTwoAlphaDTa) {
  const auto s = setup();
  const double t = betweenTheCycles_s(s);
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
  const double S = 40 + 3, h = 24 - 12.1;
  ASSERT_NEAR(s.ttp().supportHeight(), S, 1e-12);
  ASSERT_NEAR(s.ttp().finishedHeight() + s.ttp().cuttingZ(), h, 1e-12);
  EXPECT_NEAR(c1["EZ_um"].get<double>(), alpha * dT * (S + h) / k * 1e3, kUm);
  EXPECT_NEAR(parts::expansionLevers(s.piece).length_mm.at("EZ"), S + h, 1e-12);
  EXPECT_NEAR(feature(j, "X1_1")["machine"]["part_above_20C_K"].get<double>(), dT, 1e-9);
  EXPECT_NEAR(feature(j, "X1_5")["machine"]["part_above_20C_K"].get<double>(), 0, 1e-9);
}

// A hall at 21 C all along (the part's node starts there and stays: it rises by 0 K): every
// cut is made with the part 1 K above 20 C, which the machine state records
// (part_above_20C_K = 1, the temperature its expansion follows, not the rise since t = 0).
// Measured at 20 C, k = 1 + alpha: the facets lie at a / k, the datum circle at 100.5 / k. A
// cut made with the tip H' above the table lies at z = H' / k - S - 24 in the part frame at
// 20 C (the bottom at -24, lifted by S (k - 1) and grown about by k, as in the warm-part
// test): the top, faced at H' = S + 24 = 67, at 67 / k - 67, the Z paths (H' = 54.9) at
// 54.9 / k - 67, so their depth is 12.1 / k. Every cycle is cut at the same temperature:
// every E is 0.
TEST(TtpTruth, APartCutAt21CIsMeasuredAt20C) {
  const auto s = setup();
  const auto j = simulate(s, truthFrom(R"(
thermal:
  environment: {mean_C: 21}
  nodes: [{name: part, capacity_J_per_K: 1, to_environment_W_per_K: 1000}]
artifact: {node: part, alpha_um_per_m_K: 23.4}
)"));
  const double k = 1 + 23.4e-6;
  for (const char* id : {"X1_5", "Y2_1", "Z1", "TOP", "CYL"})
    EXPECT_NEAR(feature(j, id)["machine"]["part_above_20C_K"].get<double>(), 1, 1e-9) << id;
  for (const auto& side : {FacetSide::X1, FacetSide::Y1, FacetSide::X2, FacetSide::Y2})
    for (int f : {5, 1}) EXPECT_NEAR(feature(j, parts::facetId(side, f))["as_cut"]["d_mm"].get<double>(), 97.5 / k, 1e-9);
  EXPECT_NEAR(feature(j, "CYL")["as_cut"]["radius_mm"].get<double>(), 100.5 / k, 1e-9);
  for (const char* id : {"Z5", "Z1"}) EXPECT_NEAR(feature(j, id)["as_cut"]["depth_mm"].get<double>(), 12.1 / k, 1e-9);
  const auto& c1 = j["ttp_cycles"][1];
  for (const char* e : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}) EXPECT_NEAR(c1[e].get<double>(), 0, kUm) << e;
}

// The whole test as the thesis runs it (9 cycles, 4 h of C at 1200 rpm = 1440 rotary feed
// moves with the tool waiting below the top, 4 h hold, ring moves of ~1200 chords each; under
// the sanitizers 10 min waits): the simulator carries it (in a fraction of a second in a
// Release build) and, without effects, every cycle's errors are 0 and every facet and Z path
// of the test lies where the drawing puts it.
TEST(TtpTruth, TheWholeTestWithoutEffectsIsNominal) {
  const auto s = setup(true);
  SimulationOutputs out;
  auto truth = truthFrom("");
  const auto j = simulate(s, truth, &out);
  const double wait = s.ttp().wait_s;
  ASSERT_EQ(wait, kShortWait ? 600 : 3600);
  EXPECT_GT(out.end_time_s, 8 * wait);
  ASSERT_EQ(j["ttp_cycles"].size(), 9u);
  for (const auto& c : j["ttp_cycles"]) {
    ASSERT_TRUE(c.contains("EX_um")) << c.dump();
    for (const char* e : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}) EXPECT_NEAR(c[e].get<double>(), 0, kUm) << c["cycle"] << e;
    EXPECT_NEAR(c["d_X1_mm"].get<double>(), 97.5, 1e-9);
    EXPECT_NEAR(c["d_Z_mm"].get<double>(), 12.1, 1e-9);
  }
  // The C load: 1200 rpm in the inputs (every 60 s) while the table turns in the four
  // warm-up waits, all but the sample at a wait's edge.
  const CsvTable in = parseCsv(out.inputs_csv, "inputs");
  int turning = 0;
  for (const auto& row : in.rows) turning += in.number(row, in.column("c_rpm")) == 1200;
  EXPECT_GE(turning, 4 * (static_cast<int>(wait / 60) - 1));
  // The top, sampled on a grid that crosses the engraved mark (0.2 mm deep) and the notches,
  // is the faced plane z 0.
  EXPECT_NEAR(feature(j, "TOP")["as_cut"]["point_mm"][2].get<double>(), 0, 1e-9);
}

// With the demo physics (examples/truth_thermal_test.yaml: the C axis and the table warm
// while C turns, the part follows the table through the adapter, the column grows with the
// spindle) and the cutting forces on: the runs are byte-identical, and every cycle's
// surfaces are where the machine's state at their cuts puts them. From the simulator's
// definitions (docs/simulator.md §2.4), to first order in the location errors:
// - a facet cut facing the machine direction u (X1 +X, Y1 +Y, X2 -X, Y2 -Y) with the tool
//   centre at a + r from the axis: in the table's frame (R^T (q - t - pivot), the EB0C test)
//   the tool's line lies at rho = (a + r - s) cos(psi) - H sin(psi) u_psi from the axis, with
//   s = (table shift - tool shift) . u (EX0C, EY0C, tool_um), psi the tilt that turns u
//   toward Z (EB0C for the X sides, EA0C for the Y sides), H sin(psi) u_psi its Abbe offset at
//   the tip's height above the pivot at the table surface, H = 54.9 mm + tool_Z - EZ0T
//   (+H sin(EB0C) along X, -H sin(EA0C) along Y, projected on u); then
//   d = (rho - r) / k + delta_n - n . O with
//   k = 1 + alpha T, T = part_above_20C_K (the part and the tool's radius in it scale by 1/k
//   about the axis), delta_n the cut's deflection (cuts.json) along the facet's outward
//   normal n (the tool pushed off the material leaves it proud), O the datum frame's origin.
//   EC0C turns the line about the axis, which changes no distance. Neglected: the turn of
//   the line by the product of the two tilts (1e-9 rad) and of the shifts' own turn by the
//   tilts (EA0C x EX0C, 1e-10 mm);
// - a Z path cut at y_j with C at 0 lies at z = z' / k - 67 in the part frame (the warm-part
//   test), z' = H + (tool_Z - EZ0T) - y_j EA0C the tip's height above the table in the
//   table's own frame, less |EB0C| x 4.4 mm where the tool's horizontal bottom meets the
//   tilted path (the EB0C test). The depth is taken in the datum frame at (0, y_j): where
//   the datum's Y axis (its z component y_z: the TOP plane rises by y_z per mm of y, faced
//   pass by pass while the tool grew with the spindle's heat) reaches y_j, so
//   E_Z = z_0 - z_i + y_z (y_i - y_0),
//   within the staircase of a tilted floor (delta = 1e-5 mm, the EB0C test);
// - E_B = -(EB0C_i - EB0C_0), within the staircase's slope error 1.5 delta / L per floor.
// A part warmer at every facet cut than at the reference's makes the diameters smaller at
// 20 C: E_TTP < 0 (the facets' deflections, 0.01-0.03 um, differ far less).
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
  const auto cuts = nlohmann::json::parse(a.cuts_json);
  const auto& t = s.ttp();
  ASSERT_TRUE(truth.artifact.alpha_per_K);
  const double alpha = *truth.artifact.alpha_per_K, A = t.facet_apothem_mm;
  const double H = 40 + 3 + 24 - 12.1, delta = 1e-5;
  ASSERT_NEAR(t.supportHeight() + t.finishedHeight() + t.cuttingZ(), H, 1e-12);
  double half_u = 1e300;  // the shortest Z path (the outer ones)
  for (const auto& f : s.piece.features)
    if (f.role == "z_path") half_u = std::min(half_u, f.half_u_mm);
  const double slope_bound = 1.5 * delta / (1.6 * half_u);
  const double r = t.tool(t.test_tool)->diameter_mm / 2;
  const double rows = floorRowsDepth(s);  // 4.4 mm, the EB0C test
  ASSERT_TRUE(j["datum_frame"].contains("origin_mm"));
  const Eigen::Vector2d O(j["datum_frame"]["origin_mm"][0].get<double>(), j["datum_frame"]["origin_mm"][1].get<double>());
  const double y_z = j["datum_frame"]["y"][2].get<double>();
  auto num = [](const nlohmann::json& m, const char* key) { return m[key].get<double>(); };

  struct Sides {
    FacetSide side;
    const char* key;
    Eigen::Vector2d u;
  };
  const Sides sides[] = {{FacetSide::X1, "d_X1_mm", {1, 0}},
                         {FacetSide::X2, "d_X2_mm", {-1, 0}},
                         {FacetSide::Y1, "d_Y1_mm", {0, 1}},
                         {FacetSide::Y2, "d_Y2_mm", {0, -1}}};
  ASSERT_EQ(j["ttp_cycles"].size(), 9u);
  double z0 = 0, eb0 = 0, y0 = 0, T0[4] = {0, 0, 0, 0};
  int warmer_cycles = 0;
  for (const auto& c : j["ttp_cycles"]) {
    ASSERT_TRUE(c.contains("ETTP_um")) << c.dump();
    const int cyc = c["cycle"].get<int>(), k = c["facet"].get<int>(), path = c["z_path"].get<int>();
    bool warmer = cyc > 0;
    for (int i = 0; i < 4; ++i) {
      const auto& f = feature(j, parts::facetId(sides[i].side, k));
      const auto& m = f["machine"];
      const auto& cut = cuts.at(f["cut_index"].get<std::size_t>());
      const Eigen::Vector2d shift(num(m, "EX0C_um") - m["tool_um"][0].get<double>(), num(m, "EY0C_um") - m["tool_um"][1].get<double>());
      const double tilt_x = num(m, "EB0C_urad") * 1e-6, tilt_y = num(m, "EA0C_urad") * 1e-6;
      const double psi = sides[i].u.x() != 0 ? tilt_x : tilt_y;
      const double lever = H + (m["tool_um"][2].get<double>() - num(m, "EZ0T_um")) * 1e-3;  // the tip above the pivot
      const Eigen::Vector2d abbe(lever * std::sin(tilt_x), -lever * std::sin(tilt_y));
      const double rho = (A + r - shift.dot(sides[i].u) * 1e-3) * std::cos(psi) - abbe.dot(sides[i].u);
      const double T = num(m, "part_above_20C_K");
      const double phi = degToRad(parts::facetNormalAngle(t, sides[i].side, k));
      const Eigen::Vector2d n(std::cos(phi), std::sin(phi));
      const double defl_mm = (cut["deflection_um"][0].get<double>() * n.x() + cut["deflection_um"][1].get<double>() * n.y()) * 1e-3;
      const double d = (rho - r) / (1 + alpha * T) + defl_mm - n.dot(O);
      EXPECT_NEAR(c[sides[i].key].get<double>(), d, 1e-9) << "cycle " << cyc << " " << sides[i].key;
      if (cyc == 0) T0[i] = T;
      warmer = warmer && T > T0[i];
    }
    const auto& m = feature(j, parts::zPathId(path))["machine"];
    const double y_j = parts::zPathY(t, path);
    const double eb = num(m, "EB0C_urad");
    const double z = (H + (m["tool_um"][2].get<double>() - num(m, "EZ0T_um")) * 1e-3 - y_j * num(m, "EA0C_urad") * 1e-6) /
                         (1 + alpha * num(m, "part_above_20C_K")) -
                     std::fabs(eb) * 1e-6 * rows;
    if (cyc == 0) z0 = z, eb0 = eb, y0 = y_j;
    EXPECT_NEAR(c["EZ_um"].get<double>(), (z0 - z + y_z * (y_j - y0)) * 1e3, delta * 1e3) << "cycle " << cyc;
    EXPECT_NEAR(c["EB_urad"].get<double>(), -(eb - eb0), 2 * slope_bound * 1e6) << "cycle " << cyc;
    if (warmer) {
      ++warmer_cycles;
      EXPECT_LT(c["ETTP_um"].get<double>(), 0) << "cycle " << cyc;
    }
    std::printf("cycle %d t %7.0f s  EX %7.3f  EY %7.3f  EZ %7.3f  EB %7.3f  ETTP %7.3f um\n", cyc, c["time_s"].get<double>(),
                c["EX_um"].get<double>(), c["EY_um"].get<double>(), c["EZ_um"].get<double>(), c["EB_urad"].get<double>(),
                c["ETTP_um"].get<double>());
  }
  // The table heats the part through the adapter from the first load on, and it has not
  // cooled back to the reference's temperature by the end of the hold.
  EXPECT_EQ(warmer_cycles, 8);
}

}  // namespace
}  // namespace probeloop::sim
