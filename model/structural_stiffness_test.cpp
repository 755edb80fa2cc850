// Seed 003 (Yang's gantry thesis) Sec. 5.2 reproduced: tests T003-1..4 of notes
// seeds001-003.md §4.1, the inconsistent printed values (eqs. 63, 74, Table 5's Z "21.7 %")
// pinned against their independent recomputation, and docs/seed003-stiffness.md's table
// checked against the code so the doc cannot drift.
//
// Tolerances: a printed value is reproduced when ours lies within half a unit of its last
// printed digit (0.005075 mm: +-5e-7 mm; 1.65e-08 rad: +-5e-11 rad). "From the rounded angle":
// the thesis multiplied its printed (rounded) angle by the arm; we round our angle to the
// printed digits first, and say so.
#include <gtest/gtest.h>

#include <cmath>
#include <Eigen/Geometry>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "model/structural_stiffness.hpp"

using namespace probeloop::model;
using Eigen::Vector3d;

namespace {

const Seed003Stiffness K;  // Table 4
const Seed003Geometry G;

// Half a unit of the last printed digit of a value printed with `decimals` decimals.
double half(int decimals) { return 0.5 * std::pow(10.0, -decimals); }
double roundTo(double v, int decimals) { return std::round(v * std::pow(10.0, decimals)) / std::pow(10.0, decimals); }

Twist crossbeam(const Vector3d& F) { return unitTwist(seed003Gantry()[0], F); }
Twist bed(const Vector3d& F) { return unitTwist(seed003Gantry()[1], F); }
const Vector3d Fx(100, 0, 0), Fy(0, 100, 0), Fz(0, 0, 100);

}  // namespace

// T003-1: translations F/(4k), eqs. 61, 65, 76, 78.
TEST(Seed003, T003_1_Translations) {
  EXPECT_NEAR(shearTranslation_mm(100, K.k_cby), 0.005075, half(6));  // eq. 61
  EXPECT_NEAR(shearTranslation_mm(100, K.k_cbx), 0.005343, half(6));  // eq. 65
  EXPECT_NEAR(shearTranslation_mm(100, K.k_mby), 0.000294, half(6));  // eq. 76
  EXPECT_NEAR(shearTranslation_mm(100, K.k_mbz), 0.00067, half(5));   // eq. 78
  // The same through the units' twists (each along its force, nothing else translates).
  EXPECT_NEAR(crossbeam(Fy).delta_mm.y(), 0.005075, half(6));
  EXPECT_NEAR(crossbeam(Fx).delta_mm.x(), 0.005343, half(6));
  EXPECT_EQ(crossbeam(Fz).delta_mm, Vector3d::Zero());  // eq. 23: the guide screws carry it
  EXPECT_NEAR(bed(Fy).delta_mm.y(), 0.000294, half(6));
  EXPECT_NEAR(bed(Fz).delta_mm.z(), 0.00067, half(5));
  EXPECT_EQ(bed(Fx).delta_mm, Vector3d::Zero());  // L526: the beam slides in X
}

// T003-2: rotations F R/(k D^2), eqs. 62, 66, 73, 77, 79, 80, with the printed signs.
TEST(Seed003, T003_2_Rotations) {
  EXPECT_NEAR(momentRotation_rad(100, G.R_cby, K.k_cby, G.D_cb), 0.000152, half(6));  // eq. 62
  EXPECT_NEAR(momentRotation_rad(100, G.R_cbx, K.k_cbx, G.D_cb), 0.000085, half(6));  // eq. 66
  EXPECT_NEAR(crossbeam(Fy).eps_rad.z(), 0.000152, half(6));                           // eq. 62, about Z
  EXPECT_NEAR(crossbeam(Fx).eps_rad.z(), 0.000085, half(6));                           // eq. 66
  EXPECT_NEAR(bed(Fx).eps_rad.z(), -0.000016, half(6));                                // eq. 73
  EXPECT_NEAR(bed(Fy).eps_rad.z(), -0.000009, half(6));                                // eq. 77
  EXPECT_NEAR(bed(Fz).eps_rad.x(), 1.65e-08, 0.5e-10);                                 // eq. 79
  EXPECT_NEAR(bed(Fz).eps_rad.y(), 6.2e-08, 0.5e-9);                                   // eq. 80
  // Independent arithmetic of the substitutions as printed (eq. 62: 100*75/(4926*100^2)).
  EXPECT_DOUBLE_EQ(crossbeam(Fy).eps_rad.z(), 100.0 * 75 / (4926.0 * 100 * 100));
  EXPECT_DOUBLE_EQ(bed(Fz).eps_rad.y(), 100.0 * 75 / (37341.0 * 1800 * 1800));
  // A Y force turns the beam about Z only (no other axis in this path).
  EXPECT_EQ(crossbeam(Fy).eps_rad.x(), 0);
  EXPECT_EQ(crossbeam(Fy).eps_rad.y(), 0);
}

// T003-3: eqs. 69, 72 with the inferred L_cb = 50, R_cbz2 = 40, R_cbz1 = 75 (notes §3.9).
TEST(Seed003, T003_3_CrossbeamUnderZ) {
  EXPECT_NEAR(crossbeam(Fz).eps_rad.x(), 0.000011, half(6));   // eq. 69
  EXPECT_NEAR(crossbeam(Fz).eps_rad.y(), -0.000021, half(6));  // eq. 72
  EXPECT_DOUBLE_EQ(crossbeam(Fz).eps_rad.x(), 100.0 * 40 / (142857.0 * 50 * 50));
  EXPECT_EQ(crossbeam(Fz).eps_rad.z(), 0);
}

// T003-4: an angle times its arm, eqs. 64, 68, 70, 71, 75.
TEST(Seed003, T003_4_LeverDisplacements) {
  const double g_cby = crossbeam(Fy).eps_rad.z(), g_cbx = crossbeam(Fx).eps_rad.z();
  const double a_cbz = crossbeam(Fz).eps_rad.x(), g_mbx = bed(Fx).eps_rad.z();
  // eq. 68 holds unrounded; eqs. 64, 70, 71, 75 from the printed (rounded) angle.
  EXPECT_NEAR(leverDisplacement_mm(g_cbx, 40), 0.0034, half(4));                         // eq. 68
  EXPECT_NEAR(leverDisplacement_mm(roundTo(g_cby, 6), 40), 0.00608, half(5));            // eq. 64
  EXPECT_NEAR(leverDisplacement_mm(roundTo(a_cbz, 6), 75), 0.000825, half(6));           // eq. 70
  EXPECT_NEAR(leverDisplacement_mm(roundTo(a_cbz, 6), 40), 0.00044, half(5));            // eq. 71
  EXPECT_NEAR(std::fabs(leverDisplacement_mm(roundTo(g_mbx, 6), 20)), 0.00032, half(5));  // eq. 75
  // Unrounded they miss the printed digits (the doc's status says so).
  EXPECT_GT(std::fabs(leverDisplacement_mm(g_cby, 40) - 0.00608), half(5));   // 0.0060901
  EXPECT_GT(std::fabs(leverDisplacement_mm(a_cbz, 75) - 0.000825), half(6));  // 0.00084
  // The vector form (one arm per unit, seed003Gantry): eqs. 64, 68, 71, 75 by components.
  const auto units = seed003Gantry();
  const Vector3d cy = tcpDisplacement_mm(Twist{Vector3d::Zero(), crossbeam(Fy).eps_rad}, units[0].arm_mm);
  EXPECT_DOUBLE_EQ(cy.x(), 100.0 * 75 / (4926.0 * 1e4) * 40);  // eq. 64 unrounded
  const Vector3d cz = tcpDisplacement_mm(Twist{Vector3d::Zero(), Vector3d(crossbeam(Fz).eps_rad.x(), 0, 0)}, units[0].arm_mm);
  EXPECT_DOUBLE_EQ(cz.y(), 100.0 * 40 / (142857.0 * 2500) * 40);  // eq. 71 unrounded
  // eq. 70 (Z: alpha x 75) is not what one arm gives: alpha x a_y = -alpha x 40.
  EXPECT_DOUBLE_EQ(cz.z(), -100.0 * 40 / (142857.0 * 2500) * 40);
  const Vector3d bx = tcpDisplacement_mm(bed(Fx), units[1].arm_mm);
  EXPECT_DOUBLE_EQ(bx.x(), 100.0 * 10 / (6079.0 * 1e4) * 20);  // eq. 75 unrounded, positive as printed
}

// The printed values that are not reproducible: ours pinned to the independent
// recomputation, and the printed value shown not to follow from the thesis's own inputs.
TEST(Seed003, InconsistentPrintedValues) {
  const double g_cby = crossbeam(Fy).eps_rad.z(), g_cbx = crossbeam(Fx).eps_rad.z(), g_mbx = bed(Fx).eps_rad.z();
  // eq. 63: Y = gamma_cby x 75 mm, printed 0.0108 mm.
  const double eq63 = leverDisplacement_mm(g_cby, 75);
  EXPECT_NEAR(eq63, 100.0 * 75 / (4926.0 * 100 * 100) * 75, 1e-15);
  EXPECT_NEAR(eq63, 0.011419, half(6));
  EXPECT_GT(std::fabs(eq63 - 0.0108), half(4));
  EXPECT_GT(std::fabs(leverDisplacement_mm(0.000152, 75) - 0.0108), half(4));  // not even from the rounded angle (0.0114)
  // eq. 74: Y = gamma_mbx x 75 mm, printed 0.006375 mm (a copy of eq. 67).
  const double eq74 = std::fabs(leverDisplacement_mm(g_mbx, 75));
  EXPECT_NEAR(eq74, 100.0 * 10 / (6079.0 * 100 * 100) * 75, 1e-15);
  EXPECT_NEAR(eq74, 0.001234, half(6));
  EXPECT_GT(std::fabs(eq74 - 0.006375), half(6));
  EXPECT_NEAR(leverDisplacement_mm(roundTo(g_cbx, 6), 75), 0.006375, half(6));  // eq. 67, which eq. 74 repeats
  // Table 5, Z: printed 21.7 %; |sim - theory| / theory = 35.3 %, / sim = 26.1 %.
  const double th = 0.0015, sim = 0.00203;
  EXPECT_NEAR(100 * (sim - th) / th, 35.3, 0.05);
  EXPECT_NEAR(100 * (sim - th) / sim, 26.1, 0.05);
  EXPECT_GT(std::fabs(100 * (sim - th) / th - 21.7), 0.05);
  EXPECT_GT(std::fabs(100 * (sim - th) / sim - 21.7), 0.05);
  EXPECT_GT(std::fabs(100 * (0.002027 - th) / 0.002027 - 21.7), 0.05);  // with the unrounded FE value: 26.0 %
  // X and Y are consistent: 14.5 %, 25.86 %.
  EXPECT_NEAR(100 * (0.01736 - 0.01516) / 0.01516, 14.5, 0.05);
  EXPECT_NEAR(100 * (0.022 - 0.01631) / 0.022, 25.86, 0.005);
}

// Table 5's theory totals as the notes reconstruct them (§3.10): sums of selected terms.
TEST(Seed003, Table5TotalsReconstructed) {
  const double X = shearTranslation_mm(100, K.k_cbx) + leverDisplacement_mm(crossbeam(Fy).eps_rad.z(), 40) +
                   leverDisplacement_mm(crossbeam(Fx).eps_rad.z(), 40) + std::fabs(leverDisplacement_mm(bed(Fx).eps_rad.z(), 20));
  EXPECT_NEAR(0.005343 + 0.00608 + 0.0034 + 0.00032, 0.015143, 1e-12);  // the printed terms
  EXPECT_NEAR(X, 0.015182, half(6));                                     // ours, unrounded
  EXPECT_NEAR(X, 0.01516, 5e-5);    // printed 0.01516: close, not at its 5 digits
  EXPECT_GT(std::fabs(X - 0.01516), half(5));
  const double Y = shearTranslation_mm(100, K.k_cby) + leverDisplacement_mm(crossbeam(Fy).eps_rad.z(), 75) +
                   leverDisplacement_mm(crossbeam(Fx).eps_rad.z(), 75);
  EXPECT_NEAR(0.005075 + 0.0108 + 0.006375, 0.02225, 1e-12);  // printed terms, printed 0.022
  EXPECT_NEAR(Y, 0.022906, half(6));                           // with the correct eq. 63
  EXPECT_GT(std::fabs(Y - 0.022), half(3));                    // 0.022 needs the printed eq. 63
  const double Z = shearTranslation_mm(100, K.k_mbz) + leverDisplacement_mm(crossbeam(Fz).eps_rad.x(), 75);
  EXPECT_NEAR(0.00067 + 0.000825, 0.001495, 1e-12);
  EXPECT_NEAR(Z, 0.0015, half(4));  // printed 0.0015: reproduced at its rounding (0.0015095)
}

// The vector form: both units under F = (100, 100, 100) N, first order, our arms and signs.
TEST(Seed003, GantryTcpDisplacementAllForces) {
  const Vector3d d = tcpDisplacement_mm(seed003Gantry(), Vector3d(100, 100, 100));
  // Independent arithmetic: crossbeam gamma = 100*75/(4926e4) + 100*40/(4679e4), alpha =
  // 100*40/(142857*2500), beta = -100*75/(142857*2500), arm (75, -40, -40); bed gamma =
  // -100*10/(6079e4) - 100*75/(84962e4), alpha = 100*20/(37341*1800^2), beta = 100*75/(37341*1800^2), arm (-75, 20, 0).
  const double g = 100.0 * 75 / 4926e4 + 100.0 * 40 / 4679e4, a = 100.0 * 40 / (142857.0 * 2500), b = -100.0 * 75 / (142857.0 * 2500);
  const double gm = -100.0 * 10 / 6079e4 - 100.0 * 75 / 84962e4, am = 100.0 * 20 / (37341.0 * 1800 * 1800),
               bm = 100.0 * 75 / (37341.0 * 1800 * 1800);
  // eps x r = (e_y r_z - e_z r_y, e_z r_x - e_x r_z, e_x r_y - e_y r_x)
  const double x = 100 / (4 * 4679.0) + (b * -40 - g * -40) + (bm * 0 - gm * 20);
  const double y = 100 / (4 * 4926.0) + (g * 75 - a * -40) + 100 / (4 * 84962.0) + (gm * -75 - am * 0);
  const double z = (a * -40 - b * 75) + 100 / (4 * 37341.0) + (am * 20 - bm * -75);
  EXPECT_NEAR(d.x(), x, 1e-15);
  EXPECT_NEAR(d.y(), y, 1e-15);
  EXPECT_NEAR(d.z(), z, 1e-15);
  EXPECT_NEAR(d.x(), 0.016198, half(6));
  EXPECT_NEAR(d.y(), 0.025544, half(6));
  EXPECT_NEAR(d.z(), 0.001801, half(6));
}

TEST(Seed003, RefusesAMomentPathWithoutStiffness) {
  StructuralUnit u;
  u.name = "beam";
  u.moments = {{1, Vector3d::UnitX(), 75, 100, ""}};
  EXPECT_ANY_THROW(unitTwist(u, Vector3d(0, 100, 0)));
  u.k_N_per_mm = Vector3d(1, 1, 1);
  u.moments[0].lever = Vector3d::UnitY();  // parallel to the force: no moment
  EXPECT_ANY_THROW(unitTwist(u, Vector3d(0, 100, 0)));
}

// docs/seed003-stiffness.md: every row of the §5.2 table carries our value as the code
// computes it (6 significant digits), and the printed value as the thesis prints it.
TEST(Seed003, DocTableMatchesTheCode) {
  const double g_cby = crossbeam(Fy).eps_rad.z(), g_cbx = crossbeam(Fx).eps_rad.z(), a_cbz = crossbeam(Fz).eps_rad.x();
  const double g_mbx = bed(Fx).eps_rad.z();
  const std::map<int, std::pair<double, double>> ours_printed = {
      {61, {crossbeam(Fy).delta_mm.y(), 0.005075}}, {62, {g_cby, 0.000152}},
      {63, {leverDisplacement_mm(g_cby, 75), 0.0108}}, {64, {leverDisplacement_mm(g_cby, 40), 0.00608}},
      {65, {crossbeam(Fx).delta_mm.x(), 0.005343}}, {66, {g_cbx, 0.000085}},
      {67, {leverDisplacement_mm(g_cbx, 75), 0.006375}}, {68, {leverDisplacement_mm(g_cbx, 40), 0.0034}},
      {69, {a_cbz, 0.000011}}, {70, {leverDisplacement_mm(a_cbz, 75), 0.000825}},
      {71, {leverDisplacement_mm(a_cbz, 40), 0.00044}}, {72, {crossbeam(Fz).eps_rad.y(), -0.000021}},
      {73, {g_mbx, -0.000016}}, {74, {std::fabs(leverDisplacement_mm(g_mbx, 75)), 0.006375}},
      {75, {std::fabs(leverDisplacement_mm(g_mbx, 20)), 0.00032}}, {76, {bed(Fy).delta_mm.y(), 0.000294}},
      {77, {bed(Fy).eps_rad.z(), -0.000009}}, {78, {bed(Fz).delta_mm.z(), 0.00067}},
      {79, {bed(Fz).eps_rad.x(), 1.65e-08}}, {80, {bed(Fz).eps_rad.y(), 6.2e-08}}};
  std::ifstream in(std::string(PROBELOOP_SOURCE_DIR) + "/docs/seed003-stiffness.md");
  ASSERT_TRUE(in) << "docs/seed003-stiffness.md";
  std::map<int, int> seen;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| ", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream s(line.substr(1));
    for (std::string c; std::getline(s, c, '|');) cells.push_back(c);
    if (cells.size() < 5) continue;
    char* end = nullptr;
    const long eq = std::strtol(cells[0].c_str(), &end, 10);
    if (end == cells[0].c_str() || !ours_printed.count(static_cast<int>(eq))) continue;
    const auto [ours, printed] = ours_printed.at(static_cast<int>(eq));
    const double doc_printed = std::strtod(cells[2].c_str(), nullptr), doc_ours = std::strtod(cells[3].c_str(), nullptr);
    EXPECT_EQ(doc_printed, printed) << "eq. " << eq << ": printed column";
    EXPECT_NEAR(doc_ours, ours, 5e-6 * std::fabs(ours)) << "eq. " << eq << ": ours column (6 significant digits)";
    ++seen[static_cast<int>(eq)];
  }
  for (const auto& [eq, v] : ours_printed) EXPECT_EQ(seen[eq], 1) << "eq. " << eq << " once in the doc's table";
}
