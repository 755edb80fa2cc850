// Machining on the virtual machine and the CMM stage: a block is faced and side-milled by a
// hand-written LinuxCNC program, then measured on the CMM; every expectation is derived here
// from the effect's definition (translation, Eq. 3.16 + F/k, alpha dT L), not read back.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unistd.h>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "sim/material_removal.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::sim {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

std::string src(const std::string& rel) { return std::string(PROBELOOP_SOURCE_DIR) + "/" + rel; }

std::string writeTemp(const std::string& name, const std::string& text) {
  static std::atomic<int> n{0};
  const fs::path d = fs::temp_directory_path() / ("probeloop-mach-" + std::to_string(::getpid()) + "-" + std::to_string(n++));
  fs::create_directories(d);
  std::ofstream(d / name) << text;
  return (d / name).string();
}

MachineTruth truthFrom(const std::string& yaml) {
  return loadMachineTruth(writeTemp("truth.yaml", "kind: machine_truth\n" + yaml));
}

// Face the top to z 38 (passes along X, 8 mm stepover), then side-mill the +X wall to x 35
// down to z 30 along +Y; all in tip (program) coordinates on the LinuxCNC mill.
const std::string kProgram = R"(G21 G90 G17 G94
G10 L2 P6 X0 Y0 Z0 C0
G59
T1 M6
G43 H1
S8000 M3
G0 X-50 Y-34 Z60
G0 Z38
G1 X50 F800
G1 Y-26
G1 X-50
G1 Y-18
G1 X50
G1 Y-10
G1 X-50
G1 Y-2
G1 X50
G1 Y6
G1 X-50
G1 Y14
G1 X50
G1 Y22
G1 X-50
G1 Y30
G1 X50
G1 Y38
G0 Z60
G0 X40 Y-40
G0 Z30
G1 Y-30 F600
G1 Y30
G1 Y40
G0 Z60
M5
M2
)";

struct Result {
  SimulationOutputs out;
  std::vector<Vector3d> cmm;
  nlohmann::json cuts;
};

std::vector<CmmPoint> plannedPoints() {
  std::vector<CmmPoint> pts;
  int k = 0;
  for (double x : {-30.0, 0.0, 25.0})
    for (double y : {-20.0, 0.0, 20.0}) pts.push_back({"TOP", ++k, 0, Vector3d(x, y, 38), Vector3d(0, 0, 1)});
  k = 0;
  for (double y : {-20.0, 0.0, 20.0})
    for (double z : {32.0, 36.0}) pts.push_back({"WALL", ++k, 0, Vector3d(35, y, z), Vector3d(1, 0, 0)});
  return pts;
}

// The CMM export has 4 decimals (0.1 um): every comparison with it allows half of that.
constexpr double kCmmDigit = 0.5e-4 + 1e-12;

Result machine(const MachineTruth& truth, parts::Workpiece w, const std::string& program = kProgram,
               std::vector<CmmPoint> pts = plannedPoints(),
               const std::string& machine_file = "parts/machines/linuxcnc_rotary_mill.yaml") {
  const auto m = parts::loadMachine(src(machine_file));
  SimulationPart part;
  part.workpiece = &w;
  part.cmm_points = std::move(pts);
  Result r;
  r.out = simulateProgram("mill.ngc", program, m, part, truth, 1);
  if (r.out.cmm_csv.empty()) {
    r.cuts = nlohmann::json::parse(r.out.cuts_json);
    return r;
  }
  const CsvTable t = parseCsv(r.out.cmm_csv, "cmm");
  for (const auto& row : t.rows)
    r.cmm.emplace_back(t.number(row, t.column("x_mm")), t.number(row, t.column("y_mm")), t.number(row, t.column("z_mm")));
  r.cuts = nlohmann::json::parse(r.out.cuts_json);
  return r;
}

parts::Workpiece block(double radial_ratio, double mpe_um = 0) {
  auto w = parts::loadWorkpiece(src("examples/workpiece_block.yaml"));
  w.material.radial_force_ratio = radial_ratio;
  w.cmm.mpe_constant_um = mpe_um;
  w.cmm.mpe_length_mm = 0;
  return w;
}

TEST(Machining, WithoutErrorsTheCutSurfacesAreNominal) {
  const auto r = machine(truthFrom(""), block(0.0));
  ASSERT_EQ(r.cmm.size(), 15u);
  const auto pts = plannedPoints();
  for (std::size_t i = 0; i < pts.size(); ++i)
    EXPECT_LT((r.cmm[i] - pts[i].nominal_mm).cwiseAbs().maxCoeff(), kCmmDigit) << pts[i].feature << " " << pts[i].point;
}

// The table 5 um up (EZ0T) and the tool tip 3 um up (tool_Z): the tool cuts 5 - 3 = 2 um
// deeper into the workpiece, and the CMM finds the faced top at 38 - 0.002 mm.
TEST(Machining, TranslationsOfTableAndToolMoveTheFloor) {
  const auto r = machine(truthFrom("static: {EZ0T_um: 5, tool_Z_um: 3, EX0C_um: 4}\n"), block(0.0));
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(r.cmm[i].z(), 38 - 0.002, kCmmDigit);
  // EX0C: the table 4 um to +X -> the tool path sits 4 um further -X on the workpiece.
  for (int i = 9; i < 15; ++i) EXPECT_NEAR(r.cmm[i].x(), 35 - 0.004, kCmmDigit);
}

// Side milling pushes the tool away from the material (+X here): the wall stays proud by
// F_n (C_tool + 1/k_x), C_tool from seed 000 Eq. 3.16 with I = pi d^4 / 64 (derived here).
TEST(Machining, ForceDeflectionLeavesTheWallProud) {
  const auto w = block(0.4);
  const auto r = machine(truthFrom("structure: {stiffness_x_N_per_um: 20, stiffness_y_N_per_um: 20}\n"), w);
  const auto& t = w.tools[0];
  const double L1 = 25, L2 = 40, E = 600e3, I = M_PI * std::pow(10.0, 4) / 64;
  ASSERT_DOUBLE_EQ(t.flute_length_mm, L1);
  const double c_tool = (std::pow(L1, 3) / 3 + L1 * (L2 - L1) * (L2 + L1) / 6 + L2 * (L2 - L1) * (2 * L2 + L1) / 6) / (E * I);
  EXPECT_NEAR(c_tool, 6.7131e-5, 1e-8);  // mm/N, by hand: 19770.8 / (600e3 * 490.874)
  // The full-engagement move (Y -30 -> 30 at X 40): ae = 5 mm, ap = 8 mm (38 after facing
  // down to 30), vf = 10 mm/s for 6 s; the quarter disk (pi 25 / 4 mm^2) at Y -30 went with
  // the entry move. Mean tangential force = k_c x removal rate / cutting speed.
  const nlohmann::json* full = nullptr;
  for (const auto& c : r.cuts)
    if (std::fabs(c["p0_mm"][1].get<double>() + 30) < 1e-6 && std::fabs(c["p1_mm"][1].get<double>() - 30) < 1e-6) full = &c;
  ASSERT_NE(full, nullptr);
  const double vc = M_PI * 10 * 8000 / 60.0;                    // mm/s
  const double removed = (5 * 60 - M_PI * 25 / 4) * 8;            // mm^3
  const double Ft_textbook = 700.0 * (removed / 6.0) / vc;        // = 62.5 N
  const double Ft = (*full)["Ft_N"], Fn = (*full)["Fn_N"];
  EXPECT_NEAR(Ft, Ft_textbook, 0.01 * Ft_textbook);  // height field of 0.25 mm cells
  EXPECT_NEAR(Fn, 0.4 * Ft, 1e-9);
  const double defl_mm = Fn * (c_tool + 1e-3 / 20.0);
  EXPECT_NEAR((*full)["deflection_um"][0].get<double>(), defl_mm * 1e3, 1e-9);
  EXPECT_GT(defl_mm, 0.002);  // a few micrometres: visible on a CMM
  for (int i = 9; i < 15; ++i) EXPECT_NEAR(r.cmm[i].x(), 35 + defl_mm, kCmmDigit) << i;
  // Facing along X removes material on both sides of the path in the first pass only.
  EXPECT_NEAR(r.cmm[4].z(), 38, kCmmDigit);
}

// Seed 003's structure (docs/seed003-stiffness.md): a unit with the crossbeam's stiffness,
// shear in X and Y, the X force's moment on a 40 mm lever (-Z) over supports 100 mm apart,
// the tip at (10, 0, -40) mm from its pivot. Pushed +X by F_n, the tool moves by
// F_n/(4 k_x) + theta x 40 mm along X and theta x 10 mm along Z, theta = F_n 40/(k_x 100^2)
// (eqs. 30, 31; the arithmetic here, not model/structural_stiffness).
TEST(Machining, Seed003StructureTurnsTheToolUnderTheCuttingForce) {
  const auto w = block(0.4);
  const auto r = machine(truthFrom(R"(
structure:
  units:
    - name: crossbeam
      k_N_per_mm: [4679, 4926, 142857]
      shear: [x, y]
      moments: [{force: x, lever: -z, R: 40 mm, spacing: 100 mm}]
      arm_mm: [10, 0, -40]
)"), w);
  const double L1 = 25, L2 = 40, E = 600e3, I = M_PI * std::pow(10.0, 4) / 64;
  const double c_tool = (std::pow(L1, 3) / 3 + L1 * (L2 - L1) * (L2 + L1) / 6 + L2 * (L2 - L1) * (2 * L2 + L1) / 6) / (E * I);
  const nlohmann::json* full = nullptr;
  for (const auto& c : r.cuts)
    if (std::fabs(c["p0_mm"][1].get<double>() + 30) < 1e-6 && std::fabs(c["p1_mm"][1].get<double>() - 30) < 1e-6) full = &c;
  ASSERT_NE(full, nullptr);
  const double Fn = (*full)["Fn_N"];
  ASSERT_GT(Fn, 20);  // about 25 N (the test above pins the force)
  const double theta = Fn * 40 / (4679.0 * 100 * 100);
  const double dx = Fn * c_tool + Fn / (4 * 4679.0) + theta * 40, dz = theta * 10;
  ASSERT_EQ((*full)["deflection_um"].size(), 3u);
  EXPECT_NEAR((*full)["deflection_um"][0].get<double>(), dx * 1e3, 1e-9);
  EXPECT_NEAR((*full)["deflection_um"][1].get<double>(), 0, 1e-12);
  EXPECT_NEAR((*full)["deflection_um"][2].get<double>(), dz * 1e3, 1e-9);
  EXPECT_GT(theta * 40, 0.5 * Fn / (4 * 4679.0));  // the rotation term is of the shear's size
  for (int i = 9; i < 15; ++i) EXPECT_NEAR(r.cmm[i].x(), 35 + dx, kCmmDigit) << i;
  // A lever along its own force has no moment: refused with the file's line.
  EXPECT_THROW(truthFrom("structure:\n  units:\n    - {k_N_per_mm: [1, 1, 1], moments: [{force: x, lever: +x, R: 1 mm, spacing: 1 mm}]}\n"),
               InputError);
}

// examples/truth_gantry_seed003.yaml is seed003Gantry() in the machine's frame (Y and Z of the
// thesis swapped): for any force the tip moves as in the thesis's frame, relabelled (the swap
// is a reflection; eps = l x F and eps x arm each flip, so the displacement does not).
TEST(Machining, TheGantryTruthIsTheThesisGantry) {
  const auto truth = loadMachineTruth(src("examples/truth_gantry_seed003.yaml"));
  ASSERT_EQ(truth.structure_units.size(), 2u);
  const auto thesis = probeloop::model::seed003Gantry();
  for (const Vector3d F_t : {Vector3d(100, 0, 0), Vector3d(0, 100, 0), Vector3d(0, 0, 100), Vector3d(100, 100, 100), Vector3d(-30, 70, 10)}) {
    const Vector3d d_t = probeloop::model::tcpDisplacement_mm(thesis, F_t);
    const Vector3d d_m = probeloop::model::tcpDisplacement_mm(truth.structure_units, Vector3d(F_t.x(), F_t.z(), F_t.y()));
    EXPECT_NEAR(d_m.x(), d_t.x(), 1e-15) << F_t.transpose();
    EXPECT_NEAR(d_m.y(), d_t.z(), 1e-15) << F_t.transpose();
    EXPECT_NEAR(d_m.z(), d_t.y(), 1e-15) << F_t.transpose();
  }
}

// Cut warm, measured at 20 °C: the workpiece shrinks about its datum (bottom centre).
TEST(Machining, AWarmWorkpieceShrinksOnTheCmm) {
  const auto r = machine(truthFrom(R"(
thermal:
  environment: {mean_C: 26}
  nodes: [{name: part, capacity_J_per_K: 100, to_environment_W_per_K: 50}]
artifact: {node: part, alpha_um_per_m_K: 23.4}
)"), block(0.0));
  const double s = 1.0 / (1.0 + 23.4e-6 * 6.0);
  const auto pts = plannedPoints();
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(r.cmm[i].z(), 38 * s, kCmmDigit);
  for (int i = 9; i < 15; ++i) EXPECT_NEAR(r.cmm[i].x(), 35 * s, kCmmDigit);
}

TEST(Machining, CmmNoiseFollowsItsMpe) {
  std::vector<CmmPoint> pts;
  for (int k = 0; k < 400; ++k) pts.push_back({"TOP", k + 1, 0, Vector3d(-30 + (k % 20) * 2.5, -20 + (k / 20) * 2.0, 38), Vector3d(0, 0, 1)});
  const auto r = machine(truthFrom(""), block(0.0, 1.2), kProgram, pts);
  double ss = 0;
  for (const auto& p : r.cmm) ss += (p.z() - 38) * (p.z() - 38);
  const double sigma_um = std::sqrt(ss / r.cmm.size()) * 1e3;
  EXPECT_NEAR(sigma_um, 0.6, 0.6 * 0.15);  // MPE / 2; 400 draws: +-7 % (1 sigma)
}

TEST(Machining, TheProbeFindsTheCutFloor) {
  const std::string prog = kProgram.substr(0, kProgram.find("M5\n")) +
                           "M5\nT99 M6\nG43 H99\nG0 X0 Y0 Z50\nG38.2 Z30 F100\n(LOGOPEN,p.log)\n(LOG,#5063)\nM2\n";
  const auto r = machine(truthFrom(""), block(0.0), prog, {});
  // Tip centre at contact: the floor 38 + tip radius 3.
  EXPECT_EQ(r.out.log_text, "41.000000\n");
}

// The same pitch error EBX = 100 urad of the X axis, probing the stock's +X face 20 mm above
// the table with the 150 mm probe. On the VMC X moves the table (V[w X' Y' b Z t]): the table
// turns about its surface, lever +20 mm, the tip is displaced eps x (0,0,20): dx = +2 um. On
// the mill X moves the tool (V[w C' Y X Z t]): lever gauge line -> tip (0,0,-150): dx = -15 um.
// The tip meets the face (x 40) at tip centre 43, commanded 43 - dx.
TEST(Machining, AngularErrorsActThroughTheAbbeLeverOfTheirSide) {
  const std::string prog = "G21 G90\nT99 M6\nG43 H99\nG0 X50 Y0 Z60\nG0 Z20\nG38.2 X38 F100\n(LOGOPEN,p.log)\n(LOG,#5061)\nM2\n";
  const auto truth = truthFrom("axes: {X: {EBX_urad: [100]}}\n");
  const auto vmc = machine(truth, block(0.0), prog, {}, "parts/machines/vmc3.yaml");
  EXPECT_EQ(vmc.out.log_text, "42.998000\n");
  const auto mill = machine(truth, block(0.0), prog, {});
  EXPECT_EQ(mill.out.log_text, "43.015000\n");
  EXPECT_EQ(parts::workpieceSideAxes("V[w X' Y' b Z t]"), (std::array<bool, 3>{true, true, false}));
  EXPECT_EQ(parts::workpieceSideAxes("V[w C2' B' b [Y1 Y2] X [Z1 Z2] (C1) t]"), (std::array<bool, 3>{false, false, false}));
  EXPECT_EQ(parts::workpieceSideAxes("V[w Y' C' X Z t]"), (std::array<bool, 3>{false, true, false}));
  EXPECT_EQ(parts::workpieceSideAxes("V[w X\u2032 Y\u2032 Z t]"), (std::array<bool, 3>{true, true, false}));
  EXPECT_THROW(parts::workpieceSideAxes("w X Y Z t"), std::invalid_argument);
}

// A scale error of X (EXX = s x, s = 0.5 um/mm at the machine coordinate): the tip really is at
// x (1 + s 1e-3) when commanded to x, so it meets the face at tip centre 43 when commanded to
// 43 / 1.0005 = 42.978511 (the log's 6 decimals).
TEST(Machining, AScaleErrorStretchesTheAxisFromItsZero) {
  const std::string prog = "G21 G90\nT99 M6\nG43 H99\nG0 X50 Y0 Z60\nG0 Z20\nG38.2 X38 F100\n(LOGOPEN,p.log)\n(LOG,#5061)\nM2\n";
  const auto r = machine(truthFrom("static: {EXX_um_per_mm: 0.5}\n"), block(0.0), prog, {});
  EXPECT_EQ(r.out.log_text, "42.978511\n");
}

// A drive's lost motion grows with the axis's speed and is held while the axis stands: the +X
// wall (x 35, cut along +Y) reached by a -X move at F sits 5 um/(m/min) x F further out (the tip
// lags the command against the move), capped at 6 um; the CMM sees it (no MPE). The probe,
// calibrated at its feed, does not see its own approach's lag.
TEST(Machining, ADrivesLostMotionGrowsWithItsSpeedUpToItsCapAndIsHeld) {
  const auto truth = truthFrom("structure: {lost_motion_x_um_per_m_per_min: 5, lost_motion_max_um: 6}\n");
  const auto wallAfter = [&](const std::string& F) {
    const std::string prog = "G21 G90 G17 G94\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT1 M6\nG43 H1\nS8000 M3\nG0 X45 Y-40 Z60\nG0 Z30\n"
                             "G1 X40 F" + F + "\nG1 Y-30 F600\nG1 Y30\nG1 Y40\nG0 Z60\nM5\nM2\n";
    const auto r = machine(truth, block(0.0), prog);
    double x = 0;
    for (std::size_t i = 9; i < 15; ++i) x += r.cmm[i].x() / 6;  // the WALL points
    return x;
  };
  EXPECT_NEAR(wallAfter("100"), 35.0005, kCmmDigit);   // 0.1 m/min: 0.5 um
  EXPECT_NEAR(wallAfter("1000"), 35.005, kCmmDigit);   // 1 m/min: 5 um
  EXPECT_NEAR(wallAfter("3000"), 35.006, kCmmDigit);   // 15 um asked, 6 um held
  const std::string probe = "G21 G90\nT99 M6\nG43 H99\nG0 X50 Y0 Z60\nG0 Z20\nG38.2 X38 F3000\n(LOGOPEN,p.log)\n(LOG,#5061)\nM2\n";
  EXPECT_EQ(machine(truth, block(0.0), probe, {}).out.log_text, "43.000000\n");
  try {
    truthFrom("structure: {lost_motion_y_um_per_m_per_min: 4}\n");
    FAIL() << "a lost motion without its cap was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("lost_motion_max_um"), std::string::npos) << e.what();
  }
}

// Axis motion heats a node: 10 W per m/min at F1000 for 720 s of air moves; the node's
// sensor (no noise, no offset) follows dT = Q/G (1 - exp(-t G/C)), Q = 10 W, tau = 400 s.
TEST(Machining, AxisMotionIsAHeatSource) {
  std::string prog = "G21 G90\nG0 X-300 Y0 Z200\n";
  for (int k = 0; k < 10; ++k) prog += "G1 X300 F1000\nG1 X-300\n";  // 20 x 600 mm at 1 m/min = 720 s
  prog += "M2\n";
  const auto r = machine(truthFrom(R"(
thermal:
  environment: {mean_C: 20}
  nodes: [{name: screws, capacity_J_per_K: 4000, to_environment_W_per_K: 10}]
  sources: [{node: screws, input: axis_speed, W_per_m_per_min: 10}]
  sensors: [{column: T_screws_C, node: screws}]
inputs_rate: 60 s
)"), block(0.0), prog, {}, "parts/machines/vmc3.yaml");
  const CsvTable t = parseCsv(r.out.inputs_csv, "inputs");
  const int ct = t.column("time_s"), cT = t.column("T_screws_C"), cf = t.column("feed_mm_per_min");
  ASSERT_GE(cf, 0);
  // First the rapid from the start (gauge X 0 Z 550) to X -300 Z 200 at 10 m/min per axis:
  // 2.1 s (Z, 350 mm), path 460.98 mm, so 13.17 m/min and 131.7 W for 2.1 s; then 10 W.
  const double G = 10, tau = 4000.0 / G, t1 = 350.0 / 10000.0 * 60.0;
  const double Q1 = 10.0 * std::hypot(300.0, 350.0) / t1 * 60.0 / 1000.0, Q = 10.0;
  const double dT1 = Q1 / G * (1 - std::exp(-t1 / tau));
  int checked = 0;
  for (const auto& row : t.rows) {
    const double time = t.number(row, ct);
    if (time <= t1 || time >= t1 + 720) continue;
    const double dT = Q / G + (dT1 - Q / G) * std::exp(-(time - t1) / tau);
    EXPECT_NEAR(t.number(row, cT), 20 + dT, 6e-4) << time;  // 3 decimals in the CSV
    EXPECT_EQ(t.number(row, cf), 1000.0);
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

void expectRefusal(const std::string& prog, const std::string& want) {
  try {
    machine(truthFrom(""), block(0.0), prog, {});
    FAIL() << "accepted; expected " << want;
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

// Straight up from a floor just cut is allowed (the start may rest 2 um in the neighbouring
// floor), but a tool 0.3 mm longer than the active length offset starts 0.3 mm inside the
// floor: the retract is refused, though its end is clear.
TEST(Machining, RetractStraightUpFromInsideTheFloorIsCaught) {
  auto w = block(0.0);
  auto longer = w.tools[0];
  longer.number = 2;
  longer.length_mm += 0.3;
  w.tools.push_back(longer);
  const std::string cut = "G21 G90\nT1 M6\nG43 H1\nS5000 M3\nG0 X-60 Y0 Z60\nG0 Z38\nG1 X0 F500\n";
  EXPECT_NO_THROW(machine(truthFrom(""), w, cut + "G0 Z60\nM5\nM2\n", {}));
  try {
    machine(truthFrom(""), w, cut + "M5\nT2 M6\nG0 Z60\nM2\n", {});
    FAIL() << "accepted a retract that starts 0.3 mm inside the floor";
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("mill.ngc:10: rapid (G0) would move through the workpiece's material"), std::string::npos)
        << e.what();
  }
}

// Between programs with planned starts the machine is off: the spindle node cools toward the
// hall as its first-order law says (tau = C / G = 8e4 / 20 = 4000 s), with the spindle still.
TEST(Machining, TheMachineCoolsWhileOffBetweenPlannedPrograms) {
  const auto truth = truthFrom(
      "thermal:\n  environment: {mean_C: 20}\n  nodes:\n    - {name: spindle, capacity_J_per_K: 8.0e4, to_environment_W_per_K: 20}\n"
      "  sources:\n    - {node: spindle, input: spindle_speed, W_per_rpm: 0.02}\n"
      "  sensors:\n    - {column: T_spindle_C, node: spindle, noise_K: 0}\ninputs_rate: 10 s\n");
  const auto m = parts::loadMachine(src("parts/machines/linuxcnc_rotary_mill.yaml"));
  auto w = block(0.0);
  SimulationPart part;
  part.workpiece = &w;
  const std::string warm = "G21 G90\nT1 M6\nG43 H1\nS8000 M3\nG4 P3600\nM5\nM2\n", later = "G21 G90\nG4 P10\nM2\n";
  const auto out = simulatePrograms({{"warm.ngc", warm, 0.0}, {"later.ngc", later, 6.0 * 3600}}, m, part, truth, 1);
  EXPECT_NEAR(out.end_time_s, 6.0 * 3600 + 10, 1e-6);
  const CsvTable t = parseCsv(out.inputs_csv, "inputs");
  const int ct = t.column("T_spindle_C"), cs = t.column("spindle_rpm"), ctime = t.column("time_s");
  double Ta = NAN, Tb = NAN;
  for (const auto& row : t.rows) {
    const double time = t.number(row, ctime);
    if (time > 3700 && time < 6.0 * 3600) {
      EXPECT_EQ(t.number(row, cs), 0.0) << time;
    }
    if (std::fabs(time - 7200) < 1e-6) Ta = t.number(row, ct);
    if (std::fabs(time - 14400) < 1e-6) Tb = t.number(row, ct);
  }
  ASSERT_TRUE(std::isfinite(Ta) && std::isfinite(Tb));
  EXPECT_GT(Ta - 20, 1.0);  // warmed by the hour at 8000 rpm (160 W)
  EXPECT_NEAR(Tb - 20, (Ta - 20) * std::exp(-7200.0 / 4000.0), 2e-3);  // inputs.csv prints 3 decimals
  // Programs given out of their planned order are refused.
  EXPECT_THROW(simulatePrograms({{"later.ngc", later, 6.0 * 3600}, {"warm.ngc", warm, 0.0}}, m, part, truth, 1), InputError);
}

TEST(Machining, UnsafeMovesNameTheirLine) {
  const std::string head = "G21 G90\nT1 M6\nG43 H1\n";
  expectRefusal(head + "G0 X0 Y0 Z60\nG0 Z30\n", "mill.ngc:5: rapid (G0) would move through the workpiece's material");
  expectRefusal(head + "G0 X-60 Y0 Z30\nG1 X0 F500\n", "mill.ngc:5: feed move (G1/G2/G3) with the spindle stopped would move through");
  expectRefusal(head + "S5000 M3\nG0 X-60 Y0 Z30\nG1 Z-1 F500\n", "mill.ngc:6: feed move (G1/G2/G3) would cut into the table");
  expectRefusal(head + "S5000 M3\nT99 M6\n", "mill.ngc:5: tool change with the spindle turning");
}

}  // namespace
}  // namespace probeloop::sim
