// Seed 000's tables reproduced by the project's own code: the printed equations come from
// examples/stepped_workpiece/yaqoob2017_components.yaml, the separation and prediction rules
// from evaluate/stepped_separation; the reference numbers are typed from the thesis's tables
// (notes/seed000.md §6), never taken from the code. Measured agreement and what cannot be
// reproduced: docs/stepped-workpiece.md#separation-and-the-thesiss-tables.
//
// The cut times are NOT printed in the thesis: the Temp states of Table 5.7 (W2 2/36/74/114,
// W5 4/40/73/105 min) and the T_i lists of Tables 6.4 and 6.6 were derived in the notes by
// inverting the printed equations (notes §2.4, §6). They are inputs here, not results.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.hpp"
#include "evaluate/stepped_separation.hpp"

using namespace probeloop;
using namespace probeloop::evaluate::stepped;

namespace {

const parts::ComponentModel& thesisModel() {
  static const parts::ComponentModel m =
      parts::loadComponentModel(std::string(PROBELOOP_SOURCE_DIR) + "/examples/stepped_workpiece/yaqoob2017_components.yaml");
  return m;
}
double eq(const char* id, double x) { return thesisModel().equation(id)(x); }

// A printed value and half a unit of its last printed digit ("1.13377E-05" -> 5e-11).
struct Printed {
  double value, half_unit;
};
Printed printed(const std::string& s) {
  const auto e = s.find_first_of("eE");
  const std::string mant = s.substr(0, e);
  const int exp10 = e == std::string::npos ? 0 : std::stoi(s.substr(e + 1));
  const auto dot = mant.find('.');
  const int decimals = dot == std::string::npos ? 0 : static_cast<int>(mant.size() - dot - 1);
  return {std::stod(s), 0.5 * std::pow(10.0, exp10 - decimals)};
}

// The largest |computed - printed| of a column, and whether each is within tol (or half a unit of
// its printed last digit when tol < 0).
struct Agreement {
  double max_abs_diff = 0;
  int within = 0, n = 0;
};
template <class F>
Agreement compare(const std::vector<std::string>& column, F computed, double tol, const char* name) {
  Agreement a;
  for (std::size_t i = 0; i < column.size(); ++i) {
    const Printed p = printed(column[i]);
    const double c = computed(i), d = std::abs(c - p.value);
    const double t = tol < 0 ? p.half_unit : tol;
    a.max_abs_diff = std::max(a.max_abs_diff, d);
    ++a.n;
    a.within += d <= t;
    EXPECT_LE(d, t) << name << " row " << i + 1 << ": computed " << c << ", printed " << column[i];
  }
  ::testing::Test::RecordProperty(name, std::to_string(a.max_abs_diff));
  std::printf("  %-10s max |computed - printed| = %.3g over %d values\n", name, a.max_abs_diff, a.n);
  return a;
}

// Ch. 6 (Case 2, S = 4500 rpm, feed 200 mm/min) derived Temp states (notes §6).
const std::vector<double> kT64 = {0.5, 0.85, 1.23, 1.59, 1.955, 2.32, 2.685, 3.05, 3.415, 3.78, 4.145, 4.51, 4.875, 5.24};
// Table 6.6's times are whole and half seconds (6, 15, 27, 37 s, then every 10.5 s); the notes'
// four-decimal minutes (0.6167, 0.7917, ...) leave 4e-8 mm in e_pt_x, the seconds 5e-10.
const std::vector<double> kT66 = [] {
  std::vector<double> t;
  for (double s : {6.0, 15.0, 27.0, 37.0, 47.5, 58.0, 68.5, 79.0, 89.5, 100.0, 110.5, 121.0, 131.5, 142.0, 152.5}) t.push_back(s / 60);
  return t;
}();
// Table 6.2: the measured X and Y coordinates (mm), the distances Table 6.7 evaluates at.
const std::vector<double> kX62 = {10.102, 15.546, 22.291, 25.56, 24.923, 18.255, 7.785, 0.839,
                                  1.35,   6.447,  13.705, 17.28, 21.566, 25.512, 26.278};
const std::vector<double> kY62 = {1.161,  0.905, 4.383, 9.375, 19.656, 25.827, 25.618, 17.72,
                                  8.252, 2.694, 0.769, 1.373, 3.719, 9.192,  14.747};

}  // namespace

// Table 5.7 (L1744-1750), all 40 values, to half a unit of each printed last digit.
TEST(SteppedTables, Table57AllFortyValues) {
  const std::vector<double> d = {29, 44, 79, 99};
  const std::vector<double> feed_w2 = {200, 400, 800, 1600}, feed_w5 = {100, 200, 400, 800};  // Table 4.1
  const std::vector<double> T_w2 = {2, 36, 74, 114}, T_w5 = {4, 40, 73, 105};                  // derived (notes §2.4)
  int n = 0;
  // e_pf are the two-wall values (not halved); e_pt the stage-1 functions: W2/W5 ran at 3500 rpm.
  n += compare({"0.000191988", "0.002923753", "0.017652045", "0.025052323"}, [&](std::size_t i) { return eq("e_pf_x", feed_w2[i]); }, -1, "e_pf_xw2").within;
  n += compare({"1.13377E-05", "0.000191988", "0.002923753", "0.017652045"}, [&](std::size_t i) { return eq("e_pf_x", feed_w5[i]); }, -1, "e_pf_xw5").within;
  n += compare({"0.00097635", "0.005849463", "0.007162287", "0.007221811"}, [&](std::size_t i) { return eq("e_pf_y", feed_w2[i]); }, -1, "e_pf_yw2").within;
  n += compare({"4.12225E-05", "0.00097635", "0.005849463", "0.007162287"}, [&](std::size_t i) { return eq("e_pf_y", feed_w5[i]); }, -1, "e_pf_yw5").within;
  auto pt = [&](const char* c, double T) { return thermalComponent(thesisModel(), c, T, 3500); };
  n += compare({"0.001235877", "0.016447688", "0.025097789", "0.02946674"}, [&](std::size_t i) { return pt("e_pt_x", T_w2[i]); }, -1, "e_pt_xw2").within;
  n += compare({"0.002425937", "0.017676739", "0.024940679", "0.028749516"}, [&](std::size_t i) { return pt("e_pt_x", T_w5[i]); }, -1, "e_pt_xw5").within;
  n += compare({"0.001950791", "0.003031592", "0.008246326", "0.014513989"}, [&](std::size_t i) { return pt("e_pt_y", T_w2[i]); }, -1, "e_pt_yw2").within;
  n += compare({"0.001952618", "0.003386255", "0.008075374", "0.013288542"}, [&](std::size_t i) { return pt("e_pt_y", T_w5[i]); }, -1, "e_pt_yw5").within;
  n += compare({"0.006423335", "0.009114022", "0.01371726", "0.015294803"}, [&](std::size_t i) { return eq("e_pos_x", d[i]); }, -1, "e_pos_x").within;
  n += compare({"0.009789383", "0.013855253", "0.020697125", "0.022944093"}, [&](std::size_t i) { return eq("e_pos_y", d[i]); }, -1, "e_pos_y").within;
  EXPECT_EQ(n, 40);
  // The thesis's printed (swapped) weights would return the stage-3 function at 3500 rpm: they
  // cannot have produced this table (the erratum is flagged, not used, at the measured speeds).
  EXPECT_GT(std::abs(thermalComponent(thesisModel(), "e_pt_x", 36, 3500, SpeedWeights::ThesisPrintedWeights) - 0.016447688), 1e-3);
}

// Table 6.4 (L1889-1905), every column, within 1e-9 mm (slope).
TEST(SteppedTables, Table64AllColumns) {
  const std::size_t N = kT64.size();
  auto at = [&](const char* c) { return [c](std::size_t i) { return thermalComponent(thesisModel(), c, kT64[i], 4500); }; };
  compare(std::vector<std::string>(N, "-0.001753"), [](std::size_t) { return eq("e_pos_z", 9); }, 1e-9, "e_posz");
  compare({"7.09248E-05", "0.000120239", "0.000173471", "0.000223607", "0.000274149", "0.000324399", "0.00037436",
           "0.000424034", "0.000473422", "0.000522526", "0.000571348", "0.00061989", "0.000668152", "0.000716138"},
          at("e_splz"), 1e-9, "e_splz");
  compare({"-1.3743E-05", "-2.07342E-05", "-2.67417E-05", "-3.13453E-05", "-3.52168E-05", "-3.84782E-05", "-4.12652E-05",
           "-4.36758E-05", "-4.57831E-05", "-4.76421E-05", "-4.92954E-05", "-5.07764E-05", "-5.21117E-05", "-5.33224E-05"},
          at("e_tt_y"), 1e-9, "e_tty");
  compare({"-6.63161E-05", "-6.65992E-05", "-6.69046E-05", "-6.7192E-05", "-6.74815E-05", "-6.77691E-05", "-6.80549E-05",
           "-6.83387E-05", "-6.86207E-05", "-6.89008E-05", "-6.91791E-05", "-6.94555E-05", "-6.97301E-05", "-7.00029E-05"},
          at("e_tt_x"), 1e-9, "e_tt_x");
  compare({"-0.000408544", "-0.000409144", "-0.000409675", "-0.000410062", "-0.000410341", "-0.000410506", "-0.00041056",
           "-0.000410502", "-0.000410335", "-0.000410058", "-0.000409674", "-0.000409183", "-0.000408585", "-0.000407883"},
          at("e_spd_x"), 1e-9, "e_spd_x");
  // e_spd_y is the stage-1 function with weight 1 (no stage-3 term): Table 6.4 does not follow
  // Eq. 5.29's 0.5/0.5 at 4500 rpm here (notes §6). The stage function is used directly.
  const std::vector<std::string> spdy = {"6.1541E-05",  "8.21389E-05", "0.000100431", "0.000115486", "0.000129229",
                                         "0.000141843", "0.00015358",  "0.000164609", "0.00017505",  "0.000184994",
                                         "0.000194508", "0.000203648", "0.000212456", "0.000220968"};
  compare(spdy, [](std::size_t i) { return eq("e_spd_y_s1", kT64[i]); }, 1e-9, "e_spd_y");
  EXPECT_GT(std::abs(thermalComponent(thesisModel(), "e_spd_y", kT64[0], 4500) - printed(spdy[0]).value), 1e-6);
  // Eq. 5.37/5.38's printed + sign of the stage-1 e_tty term does not reproduce the e_tty column.
  const double w = 0.5;
  const double plus = w * eq("e_tt_y_s1_eq537_printed", kT64[13]) + w * eq("e_tt_y_s3", kT64[13]);
  EXPECT_GT(std::abs(plus - -5.33224E-05), 1e-6);
}

// Table 6.5 (L1907-1923): Eq. 5.46 at 100 mm/min and the Table 6.4 tilts at lever arms of 10 mm
// (table) and 9 mm (spindle). The thesis swaps the table-tilt names (e_ztty = 10 x e_tt_x) and
// gives e_zspd_x the opposite sign of e_zspdy; the rule here is the one that reproduces it.
TEST(SteppedTables, Table65TiltsAtLeverArms) {
  const std::size_t N = kT64.size();
  auto th = [](const char* c, std::size_t i) { return thermalComponent(thesisModel(), c, kT64[i], 4500); };
  compare(std::vector<std::string>(N, "-0.0026296"), [](std::size_t) { return eq("e_splf_z", 100); }, -1, "e_splf_z");
  compare({"-0.000663161", "-0.000665992", "-0.000669046", "-0.00067192", "-0.000674815", "-0.000677691", "-0.000680549",
           "-0.000683387", "-0.000686207", "-0.000689008", "-0.000691791", "-0.000694555", "-0.000697301", "-0.000700029"},
          [&](std::size_t i) { return tiltToZ_mm(th("e_tt_x", i), 10); }, 1e-8, "e_ztty");
  compare({"-0.00013743", "-0.000207342", "-0.000267417", "-0.000313453", "-0.000352168", "-0.000384782", "-0.000412652",
           "-0.000436758", "-0.000457831", "-0.000476421", "-0.000492954", "-0.000507764", "-0.000521117", "-0.000533224"},
          [&](std::size_t i) { return tiltToZ_mm(th("e_tt_y", i), 10); }, 1e-8, "e_zttx");
  compare({"0.003676901", "0.0036823", "0.003687072", "0.003690555", "0.003693065", "0.003694557", "0.003695039",
           "0.003694522", "0.003693014", "0.003690525", "0.003687065", "0.003682643", "0.003677268", "0.003670951"},
          [&](std::size_t i) { return tiltToZ_mm(th("e_spd_x", i), -9); }, 1e-8, "e_zspd_x");
  compare({"0.000553869", "0.00073925", "0.000903878", "0.001039373", "0.001163062", "0.001276589", "0.001382219",
           "0.001481477", "0.00157545", "0.001664944", "0.001750575", "0.001832832", "0.001912105", "0.001988715"},
          [&](std::size_t i) { return tiltToZ_mm(eq("e_spd_y_s1", kT64[i]), 9); }, 1e-8, "e_zspdy");
}

// Table 6.6 (L1935-1952): e_pt_x exactly; e_pt_y within 1.4e-5 mm (the derived times fit e_pt_x,
// and e_pt_y's own inversion drifts to 2.561 min at point 15); e_pf halved for one wall.
TEST(SteppedTables, Table66ThermalAndProcess) {
  const std::size_t N = kT66.size();
  auto th = [](const char* c, std::size_t i) { return thermalComponent(thesisModel(), c, kT66[i], 4500); };
  compare({"0.000129393", "0.000322412", "0.000577789", "0.000788888", "0.001008878", "0.001227177", "0.001443801", "0.001658763",
           "0.001872078", "0.002083759", "0.002293821", "0.002502276", "0.00270914", "0.002914425", "0.003118144"},
          [&](std::size_t i) { return th("e_pt_x", i); }, 1e-9, "e_pt_x");
  const Agreement y = compare({"0.001098012", "0.001276625", "0.001504983", "0.001687246", "0.001871247", "0.002048137", "0.002218329",
                               "0.002382207", "0.002540128", "0.002692422", "0.002839395", "0.002981332", "0.003118499", "0.003251142",
                               "0.003379493"},
                              [&](std::size_t i) { return th("e_pt_y", i); }, 1.4e-5, "e_pt_y");
  EXPECT_GT(y.max_abs_diff, 1e-6);  // the drift is real: a tighter claim would be wrong
  compare(std::vector<std::string>(N, "9.5994E-05"), [](std::size_t) { return processErrorOneWall_mm(eq("e_pf_x", 200)); }, -1, "e_pf_x");
  compare(std::vector<std::string>(N, "0.000488175"), [](std::size_t) { return processErrorOneWall_mm(eq("e_pf_y", 200)); }, -1, "e_pf_y");
  // At 4500 rpm the printed and the correct weights agree (both 0.5/0.5).
  const StageWeights a = stageWeights(4500), b = stageWeights(4500, SpeedWeights::ThesisPrintedWeights);
  EXPECT_EQ(a.stage_3500_rpm, 0.5);
  EXPECT_EQ(a.stage_5500_rpm, 0.5);
  EXPECT_EQ(b.stage_3500_rpm, 0.5);
  EXPECT_EQ(b.stage_5500_rpm, 0.5);
}

// Table 6.7 (L1954-1971): e_pos at the measured coordinates of Table 6.2, e_cpr_x = Eq. 5.56 at
// 200, e_ctrl_y = Eq. 5.54 as Table 6.7 reads it, e_cpr_y Table 6.7's constant. e_ctrl_x is not
// reproducible (notes §9.2 row 5): Eq. 5.55 read either way is far from the column.
TEST(SteppedTables, Table67PositionAndControl) {
  compare({"0.002420265", "0.003643546", "0.005080473", "0.005745554", "0.005617561", "0.004231126", "0.001882417", "0.000208449",
           "0.000334746", "0.001567144", "0.003236218", "0.004021268", "0.0049302", "0.005735937", "0.005888892"},
          [](std::size_t i) { return eq("e_pos_x", kX62[i]); }, -1, "e_pos_x");
  compare({"0.000440767", "0.000343928", "0.001642634", "0.003442767", "0.00691279", "0.008842157", "0.008778696", "0.006283775",
           "0.003044377", "0.001016519", "0.000292402", "0.000520811", "0.001397517", "0.003378107", "0.005295775"},
          [](std::size_t i) { return eq("e_pos_y", kY62[i]); }, -1, "e_pos_y");
  compare({"-3.40518E-05", "-2.80264E-05", "-3.81553E-05", "0.00021796", "0.001750544", "0.003320328", "0.003259186", "0.00135853",
           "0.000132532", "-5.25782E-05", "-2.44841E-05", "-3.84065E-05", "-4.8182E-05", "0.000202938", "0.000849957"},
          [](std::size_t i) { return controlErrorY_mm(thesisModel(), kY62[i], 200, ControlYReading::Table67); }, 1e-9, "e_ctrl_y");
  compare(std::vector<std::string>(15, "0.001662412"), [](std::size_t) { return eq("e_cpr_x", 200); }, -1, "e_cpr_x");
  compare(std::vector<std::string>(15, "-4.1528E-05"), [](std::size_t) { return eq("e_cpr_y", 200); }, -1, "e_cpr_y");
  // Eq. 5.54 with the factor on the whole bracket (Eq. 3.13) keeps 100/2300 x 0.0167701 = 0.73 um.
  EXPECT_GT(std::abs(controlErrorY_mm(thesisModel(), kY62[0], 200, ControlYReading::WholeBracket) - -3.40518E-05), 5e-4);
  // e_ctrl_x: Table 6.7 prints ~0.007 mm everywhere; Eq. 5.55 as Eq. 3.14 gives ~0 at x = 10 mm.
  EXPECT_GT(std::abs(controlErrorX_mm(thesisModel(), kX62[0], 200) - 0.006999993), 5e-3);
}

// Table 6.3 (L1871-1887): the model columns, printed to 3 significant digits.
TEST(SteppedTables, Table63ZComponents) {
  compare(std::vector<std::string>(14, "-0.00263"), [](std::size_t) { return eq("e_splf_z", 100); }, -1, "e_splf_z");
  compare(std::vector<std::string>(14, "-0.00175"), [](std::size_t) { return eq("e_pos_z", 9); }, -1, "e_posz");
  // The thermal columns repeat Table 6.4 rounded; 5e-7 covers the rounding of "0.00012".
  compare({"7.09E-05", "0.00012", "0.000173", "0.000224", "0.000274", "0.000324", "0.000374", "0.000424", "0.000473",
           "0.000523", "0.000571", "0.00062", "0.000668", "0.000716"},
          [](std::size_t i) { return thermalComponent(thesisModel(), "e_splz", kT64[i], 4500); }, 5e-7, "e_splz");
  // Table 6.3 evaluates Eq. 5.46 at its "Feed Z" column (100): the prediction takes the Z feed.
  PredictionPoint p;
  p.z_mm = 9, p.T_min = kT64[0], p.spindle_rpm = 4500, p.feed_x_mm_per_min = p.feed_y_mm_per_min = 200, p.feed_z_mm_per_min = 100;
  const auto z = predict(thesisModel(), p)[2];
  EXPECT_NEAR(z.components[2].value_mm, -0.0026296, 5e-8);
}

// The e_prog mapping (notes §4.8, §9.2 row 19): e_prog = k x Feed with one k for four pairs of
// printed coefficients, and the e_prog equations then give the feed equations back.
TEST(SteppedTables, EProgIsLinearInFeed) {
  const auto& m = thesisModel();
  auto x0 = [&](const char* id) { return m.equation(id).function.p.back(); };
  const double k1 = x0("e_pf_y_prog") / x0("e_pf_y");                                        // 5.88564e-6 / 295.209
  const double k2 = m.equation("e_splf_z_prog").function.p[1] / m.equation("e_splf_z").function.p[1];  // 1.05316e-5 / 528.24
  const double k3 = x0("e_pf_x_prog") / x0("e_pf_x");                                        // 1.32e-5 / 660.765 (3 digits)
  const double k4 = -m.equation("e_cpr_x").function.p[1] / -m.equation("e_cpr_x_prog").function.p[1];  // 3.85058e-5 / 1931.35
  const double k5 = std::sqrt(m.equation("e_cpr_x").function.p[2] / m.equation("e_cpr_x_prog").function.p[2]);
  for (double k : {k1, k2, k4, k5}) EXPECT_NEAR(k / kEProgPerFeed, 1, 2e-5) << k;
  EXPECT_NEAR(k3 / kEProgPerFeed, 1, 2e-3) << k3;  // 1.32e-5 is printed to 3 digits
  // With k to its 5 printed digits the e_prog equations give the feed equations back within 1e-4
  // relative (the Hill exponent 4.77 amplifies k's 1e-5).
  for (double F : {100.0, 200.0, 400.0, 800.0, 1600.0}) {
    const double e = eProgFromFeed(F);
    // Eq. 5.49 is per wall: half of Eq. 5.47 (0.00361205 = 0.0072241 / 2).
    EXPECT_NEAR(eq("e_pf_y_prog", e), eq("e_pf_y", F) / 2, 1e-4 * eq("e_pf_y", F) / 2) << F;
    EXPECT_NEAR(eq("e_splf_z_prog", e), eq("e_splf_z", F), 1e-4 * std::abs(eq("e_splf_z", F))) << F;
    // e_cpr_x changes sign between 200 and 800 mm/min: 1e-4 of the size of its terms.
    EXPECT_NEAR(eq("e_cpr_x_prog", e), eq("e_cpr_x", F), 1e-4 * (0.007907 + 3.85058e-5 * F + 3.64143e-8 * F * F)) << F;
  }
  // Eq. 5.50 is not an exact half of the feed-based e_pfx: amplitude 0.012827 against
  // 0.0257241 / 2 = 0.01286205, exponent 4.14033 against 4.09199 (a refit, not a rescaling).
  EXPECT_GT(std::abs(eq("e_pf_x_prog", eProgFromFeed(800)) - eq("e_pf_x", 800) / 2), 1e-5);
  EXPECT_THROW(eProgFromFeed(-1), GeometryError);
}

// Table 5.3's CMM widths from Table 5.2's points (notes §6): X1/X2 = Y12 - Y11 at level 1/2 and
// Y1/Y2 = X12 - X11 (the X/Y labels are swapped between the tables). 37 of 48 agree exactly; the
// 11 exceptions are listed with their differences (Table 5.3 minus the width from the points).
TEST(SteppedTables, Table53WidthsFromTable52Points) {
  // Table 5.2, per step, per row: Y11-1, Y11-2, Y12-1, Y12-2, X11-1, X11-2, X12-1, X12-2.
  const double t52[4][3][8] = {
      {{0.053, 0.043, 30.086, 30.096, -0.026, -0.035, 30.013, 30.025},
       {0.192, 0.184, 30.226, 30.239, -0.167, -0.179, 29.873, 29.886},
       {0.333, 0.328, 30.369, 30.382, -0.308, -0.32, 29.731, 29.741}},
      {{-7.524, -7.527, 37.517, 37.528, -7.462, -7.469, 37.588, 37.598},
       {-7.311, -7.321, 37.729, 37.74, -7.674, -7.684, 37.382, 37.39},
       {-7.101, -7.107, 37.942, 37.951, -7.886, -7.892, 37.17, 37.181}},
      {{-25.14, -25.149, 54.911, 54.924, -24.849, -24.86, 55.216, 55.228},
       {-24.989, -24.998, 55.066, 55.074, -25.006, -25.013, 55.062, 55.076},
       {-24.641, -24.647, 55.413, 55.425, -25.358, -25.366, 54.706, 54.717}},
      {{-34.821, -34.839, 64.243, 64.266, -34.176, -34.197, 64.891, 64.915},
       {-34.492, -34.512, 64.571, 64.593, -34.508, -34.526, 64.561, 64.587},
       {-34.141, -34.159, 64.919, 64.943, -34.86, -34.879, 64.209, 64.23}}};
  // Table 5.3 CMM, per step, per observation: Y1, Y2, X1, X2.
  const double t53[4][3][4] = {{{30.048, 30.06, 30.035, 30.052}, {30.052, 30.065, 30.034, 30.055}, {30.051, 30.061, 30.036, 30.054}},
                               {{45.05, 45.067, 45.041, 45.055}, {45.056, 45.074, 45.04, 45.061}, {45.056, 45.073, 45.043, 45.058}},
                               {{80.076, 80.088, 80.051, 80.073}, {80.075, 80.089, 80.055, 80.072}, {80.072, 80.083, 80.054, 80.072}},
                               {{99.084, 99.112, 99.064, 99.105}, {99.079, 99.113, 99.063, 99.105}, {99.082, 99.109, 99.06, 99.102}}};
  struct Exception {
    int step, row;
    const char* column;
    double diff_mm;  // Table 5.3 - width from the points
  };
  const std::vector<Exception> exceptions = {
      {1, 1, "Y1", 0.009}, {1, 1, "X1", 0.002},  {1, 1, "X2", -0.001}, {1, 2, "Y1", 0.012}, {1, 3, "Y1", 0.012}, {3, 1, "Y1", 0.011},
      {3, 2, "Y1", 0.007}, {3, 3, "Y1", 0.008}, {4, 1, "Y1", 0.017},  {4, 2, "Y1", 0.010}, {4, 3, "Y1", 0.013}};
  const char* names[4] = {"Y1", "Y2", "X1", "X2"};
  int exact = 0;
  std::vector<Exception> found;
  for (int s = 0; s < 4; ++s) {
    std::vector<std::vector<double>> x_low, x_high, y_low, y_high;
    for (int r = 0; r < 3; ++r) {
      y_low.push_back({t52[s][r][0], t52[s][r][1]}), y_high.push_back({t52[s][r][2], t52[s][r][3]});
      x_low.push_back({t52[s][r][4], t52[s][r][5]}), x_high.push_back({t52[s][r][6], t52[s][r][7]});
    }
    const auto wy = faceToFaceWidths(y_low, y_high, 0.001), wx = faceToFaceWidths(x_low, x_high, 0.001);
    for (int r = 0; r < 3; ++r) {
      // Table 5.3's "Y" widths are the X faces' and its "X" widths the Y faces'.
      const double w[4] = {wx[r][0].value, wx[r][1].value, wy[r][0].value, wy[r][1].value};
      for (int c = 0; c < 4; ++c) {
        const double d = t53[s][r][c] - w[c];
        if (std::abs(d) < 1e-9)
          ++exact;
        else
          found.push_back({s + 1, r + 1, names[c], d});
      }
      EXPECT_NEAR(wx[r][0].u, std::sqrt(2.0) * 0.001, 1e-15);
    }
  }
  EXPECT_EQ(exact, 37);
  ASSERT_EQ(found.size(), exceptions.size());
  for (std::size_t i = 0; i < found.size(); ++i) {
    EXPECT_EQ(found[i].step, exceptions[i].step);
    EXPECT_EQ(found[i].row, exceptions[i].row);
    EXPECT_STREQ(found[i].column, exceptions[i].column);
    EXPECT_NEAR(found[i].diff_mm, exceptions[i].diff_mm, 1e-9);
  }
}

// Notes §9.2 row 14: the printed equations against the thesis's words.
TEST(SteppedTables, TextChecks) {
  // L1222: "expands up to approximately 8 micrometers in the first 50 minutes ... over the next
  // 70 minutes ... only expands by a value of approximately 3 micrometers". Eq. 5.4: 7.88 um at 50 min
  // and 3.0 um from 50 to 120 min.
  const double at50_um = 1000 * eq("e_splz_s1", 50), next70_um = 1000 * (eq("e_splz_s1", 120) - eq("e_splz_s1", 50));
  EXPECT_NEAR(at50_um, 7.88, 0.005);
  EXPECT_NEAR(next70_um, 3.0, 0.005);
  EXPECT_NEAR(at50_um, 8, 0.5);
  EXPECT_NEAR(next70_um, 3, 0.5);
  // L1300: Y position error at the final state "about 9 micrometers as opposed to 14 micrometers
  // ... in first temperature stage": Eq. 5.5 at 114 min (W2's last cut) 14.5 um, Eq. 5.12 at 130 min 9.6 um.
  EXPECT_NEAR(1000 * eq("e_pt_y_s1", 114), 14.5, 0.05);
  EXPECT_NEAR(1000 * eq("e_pt_y_s2", 130), 9.6, 0.05);
  EXPECT_NEAR(1000 * eq("e_pt_y_s1", 114), 14, 1);
  EXPECT_NEAR(1000 * eq("e_pt_y_s2", 130), 9, 1);
  // L1364/L1503: stage-3 spindle growth smaller than stage 1's; X/Y errors larger.
  EXPECT_LT(eq("e_splz_s3", 130), eq("e_splz_s1", 130));
  EXPECT_GT(eq("e_pt_x_s3", 130), eq("e_pt_x_s1", 130));
  EXPECT_GT(eq("e_pt_y_s3", 130), eq("e_pt_y_s1", 130));
}

// Correct linear weights: the nodes return their own stage (typed here from the print, not read
// from the file), the weights sum to 1 between the nodes, and scale proportionally outside.
TEST(SteppedSeparation, SpeedInterpolationHasCorrectWeightsAndTheErratumIsFlagged) {
  auto s1 = [](double T) { return 0.0333374 - 0.0333374 * std::exp(-0.0188882 * T); };  // Eq. 5.6
  auto s2 = [](double T) { return 0.0308404 - 0.0308404 * std::exp(-0.0396475 * T); };  // Eq. 5.22's stage 2
  auto s3 = [](double T) { return 0.0375039 - 0.0375039 * std::exp(-0.0523651 * T); };  // Eq. 5.16
  const double T = 60;
  auto f = [&](double S, SpeedWeights w = SpeedWeights::Linear) { return thermalComponent(thesisModel(), "e_pt_x", T, S, w); };
  EXPECT_NEAR(f(1000), s2(T), 1e-15);
  EXPECT_NEAR(f(3500), s1(T), 1e-15);
  EXPECT_NEAR(f(5500), s3(T), 1e-15);
  EXPECT_NEAR(f(2000), 0.6 * s2(T) + 0.4 * s1(T), 1e-15);
  EXPECT_NEAR(f(4000), 0.75 * s1(T) + 0.25 * s3(T), 1e-15);
  EXPECT_NEAR(f(400), 0.4 * s2(T), 1e-15);
  EXPECT_NEAR(f(6600), 1.2 * s3(T), 1e-15);
  EXPECT_NEAR(f(0), 0, 0);
  // Continuity at the nodes.
  for (double S : {1000.0, 3500.0, 5500.0}) EXPECT_NEAR(f(S - 1e-9), f(S + 1e-9), 1e-12) << S;
  // The printed Eq. 3.7/3.8: stage 3 at 3500 rpm and stage 1 at 1000 and 5500 rpm (swapped);
  // Eq. 3.9 scales stage 1 below 1000.
  EXPECT_NEAR(f(3500, SpeedWeights::ThesisPrintedWeights), s3(T), 1e-15);
  EXPECT_NEAR(f(5500, SpeedWeights::ThesisPrintedWeights), s1(T), 1e-15);
  EXPECT_NEAR(f(1000, SpeedWeights::ThesisPrintedWeights), s1(T), 1e-15);
  EXPECT_NEAR(f(400, SpeedWeights::ThesisPrintedWeights), 0.4 * s1(T), 1e-15);
  EXPECT_NEAR(f(4500, SpeedWeights::ThesisPrintedWeights), f(4500), 1e-15);
  EXPECT_THROW(f(-1), GeometryError);
  EXPECT_THROW(thermalComponent(thesisModel(), "e_pt_x", -1, 3500), GeometryError);
  EXPECT_THROW(thermalComponent(thesisModel(), "e_pt_x", NAN, 3500), GeometryError);
  EXPECT_THROW(thermalComponent(thesisModel(), "e_pt_z", 1, 3500), std::out_of_range);
}

// The separation rules of Ch. 3 on numbers worked by hand.
TEST(SteppedSeparation, RulesOfChapter3) {
  // Eq. 3.5: a later step 45.060 (nominal 45) against the first 30.040 (nominal 30) with a
  // position error of 0.009 mm: 0.060 - 0.040 - 0.009 = 0.011 mm.
  EXPECT_NEAR(thermalPositionError_mm(45.060, 45, 30.040, 30, 0.009), 0.011, 1e-12);
  // L1629/L1639: process error = 0.030 - 0.012 - 0.008 = 0.010 (two walls), 0.005 per wall.
  EXPECT_NEAR(processErrorTwoWalls_mm(0.030, 0.012, 0.008), 0.010, 1e-15);
  EXPECT_NEAR(processErrorOneWall_mm(0.010), 0.005, 1e-15);
  // Eq. 3.11: (29.0486 - 29.0562) - (0.001 - 0.0005) - (0.002 - 0.003) - (0.0064 - 0.0064)
  //         = -0.0076 - 0.0005 + 0.001 - 0 = -0.0071.
  const StepTerms w2{29.0486, 0.001, 0.002, 0.0064}, w8{29.0562, 0.0005, 0.003, 0.0064}, w5{29.0237, 0.0002, 0.0025, 0.0064};
  EXPECT_NEAR(controlErrorFeedChange_mm(w2, w8), -0.0071, 1e-12);
  // Eq. 3.15: (29.0486 - 29.0237) - (0.001 - 0.0002) - (0.002 - 0.0025) - 0 - (-0.0071)
  //         = 0.0249 - 0.0008 + 0.0005 + 0.0071 = 0.0317.
  EXPECT_NEAR(controlErrorProcessForce_mm(w2, w5, -0.0071), 0.0317, 1e-12);
  // Eq. 3.13: (Feed - 100)/(2400 - 100); no control error at or below the 100 mm/min transitions.
  EXPECT_NEAR(controlFeedFactor(thesisModel(), 200), 100.0 / 2300, 1e-15);
  EXPECT_EQ(controlFeedFactor(thesisModel(), 2400), 1.0);
  EXPECT_EQ(controlFeedFactor(thesisModel(), 50), 0.0);
  EXPECT_NEAR(controlErrorY_mm(thesisModel(), 30, 2400, ControlYReading::WholeBracket), eq("e_ctrl_y_2400_100", 30), 1e-15);
  // Tilts (Sec. 3.4.1): a floor rising 0.001 mm over 18 mm is Table 5.4's 5.5556e-5 table tilt; a
  // wall leaning 0.007 mm over 7 mm is 0.001 + 5.5556e-5; the spindle's share is 0.001.
  const Separated tt = tableTilt(-9.000, -8.999, 18, 0.0005);
  EXPECT_NEAR(tt.value, 0.001 / 18, 1e-12);
  EXPECT_NEAR(tt.u, std::sqrt(2.0) * 0.0005 / 18, 1e-15);
  const Separated wall = wallInclination(0.007 + 7 * 0.001 / 18, -2, 0, -9, 0.0005);
  EXPECT_NEAR(wall.value, 0.001 + 0.001 / 18, 1e-12);
  const Separated sp = spindleTilt(wall, tt);
  EXPECT_NEAR(sp.value, 0.001, 1e-12);
  EXPECT_NEAR(sp.u, std::hypot(std::sqrt(2.0) * 0.0005 / 7, std::sqrt(2.0) * 0.0005 / 18), 1e-15);
  EXPECT_NEAR(spindleGrowth(9.011, 9.003, 0.001).value, 0.008, 1e-12);
  // Degenerate geometry is refused, not divided by zero.
  EXPECT_THROW(tableTilt(0, 0.001, 0, 0.001), GeometryError);
  EXPECT_THROW(wallInclination(0, -5, 0.001, -5, 0.001), GeometryError);
  EXPECT_THROW(faceToFaceWidths({{1, 2}}, {{3}}, 0.001), GeometryError);
  EXPECT_THROW(faceToFaceWidths({}, {}, 0.001), GeometryError);
  EXPECT_THROW(thermalPositionError_mm(NAN, 45, 30, 30, 0), GeometryError);
}

// Forward prediction at Ch. 6's first X/Y point: the components are Tables 6.6/6.7's columns (e_ctrl_x
// aside), the total is their sum, and the budget combines the uncertainties given.
TEST(SteppedSeparation, ForwardPredictionSumsTheComponentsWithABudget) {
  PredictionPoint p;
  p.x_mm = kX62[0], p.y_mm = kY62[0], p.z_mm = 9, p.T_min = kT66[0], p.spindle_rpm = 4500;
  p.feed_x_mm_per_min = p.feed_y_mm_per_min = 200, p.feed_z_mm_per_min = 100;
  p.u_mm = {{"e_pos_x", 0.001}, {"e_pt_x", 0.0005}, {"e_cpr_x", 0.0002}};
  const auto a = predict(thesisModel(), p);
  const auto& X = a[0];
  ASSERT_EQ(X.components.size(), 5u);
  EXPECT_NEAR(X.components[0].value_mm, 0.002420265, 5e-10);  // Table 6.7 e_pos_x
  EXPECT_NEAR(X.components[1].value_mm, 0.000129393, 1e-9);   // Table 6.6 e_pt_x
  EXPECT_NEAR(X.components[2].value_mm, 9.5994E-05, 5e-10);   // Table 6.6 e_pf_x
  EXPECT_NEAR(X.components[4].value_mm, 0.001662412, 5e-10);  // Table 6.7 e_cpr_x
  double sum = 0;
  for (const auto& c : X.components) sum += c.value_mm;
  EXPECT_NEAR(X.total_mm, sum, 1e-15);
  EXPECT_NEAR(X.budget.u_c, std::sqrt(0.001 * 0.001 + 0.0005 * 0.0005 + 0.0002 * 0.0002), 1e-15);
  EXPECT_EQ(X.budget.contributions.size(), 5u);
  const auto& Y = a[1];
  EXPECT_NEAR(Y.components[0].value_mm, 0.000440767, 5e-10);   // Table 6.7 e_pos_y
  EXPECT_NEAR(Y.components[1].value_mm, 0.001098012, 1.4e-5);  // Table 6.6 e_pt_y
  EXPECT_NEAR(Y.components[2].value_mm, 0.000488175, 5e-10);   // Table 6.6 e_pf_y
  EXPECT_NEAR(Y.components[3].value_mm, -3.40518E-05, 1e-9);   // Table 6.7 e_ctrl_y
  EXPECT_NEAR(Y.components[4].value_mm, -4.1528E-05, 5e-11);   // Table 6.7 e_cpr_y
  EXPECT_EQ(Y.budget.u_c, 0.0);                                 // nothing given: 0, and said so
  EXPECT_NE(Y.budget.contributions[0].basis.find("not stated"), std::string::npos);
  const auto& Z = a[2];
  ASSERT_EQ(Z.components.size(), 7u);
  EXPECT_NEAR(Z.components[0].value_mm, -0.001753, 1e-12);  // Table 6.4 e_posz
  // Feeds below the 100 mm/min transitions give no process or control error (L1658, L1629).
  p.feed_x_mm_per_min = p.feed_y_mm_per_min = p.feed_z_mm_per_min = 50;
  const auto slow = predict(thesisModel(), p);
  EXPECT_EQ(slow[0].components[2].value_mm, 0.0);
  EXPECT_EQ(slow[0].components[3].value_mm, 0.0);
  EXPECT_EQ(slow[2].components[2].value_mm, 0.0);
  p.u_mm = {{"e_pt_x", -1}};
  EXPECT_THROW(predict(thesisModel(), p), GeometryError);
  p.u_mm.clear();
  p.T_min = NAN;
  EXPECT_THROW(predict(thesisModel(), p), GeometryError);
}
