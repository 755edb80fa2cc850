// Cutting while C turns, obstacles, rotary feeds and the C-axis load, turning the table with
// the tool below the top, several programs on one machine, and the CMM room's temperature.
// Hand-written LinuxCNC programs on the NMV 5000 (C at 1200 rpm in turning mode, +C turns the
// table clockwise); every expected number is derived here.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "parts/piece_kinds.hpp"
#include "sim/test_support.hpp"
#include "sim/virtual_machine.hpp"

namespace probeloop::sim {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using test::src;
using test::truthFrom;

constexpr double kCmmDigit = 0.5e-4 + 1e-12;  // the CMM export has 4 decimals
const double kCmmRadius = std::hypot(kCmmDigit, kCmmDigit);  // a radius from two rounded coordinates

parts::Machine nmv() { return parts::loadMachine(src("parts/machines/nmv5000.yaml")); }

// A Ø100 x 30 mm cylinder on an adapter, its part frame's origin in its top face on the C
// axis, 40 mm above the table; a clamp stands beside it at (70, 0).
parts::Workpiece cylinder(double radial_ratio = 0) {
  parts::Workpiece w;
  w.name = "cylinder";
  w.stock_min_mm = Vector3d(-50, -50, -30);
  w.stock_max_mm = Vector3d(50, 50, 0);
  w.cylindrical = true;
  w.frame_origin_mm = Vector3d(0, 0, 40);
  w.obstacles.push_back({Vector2d(0, 0), 30, -40, -30, "adapter"});
  w.obstacles.push_back({Vector2d(70, 0), 5, -30, -5, "clamp 1"});
  w.material = {.name = "aluminium", .alpha_per_K = 23.4e-6, .specific_cutting_force_N_per_mm2 = 700,
                .radial_force_ratio = radial_ratio, .alpha_um_per_m_K = 23.4};
  parts::CuttingTool t;
  t.number = 1;
  t.diameter_mm = 10;
  t.length_mm = 120;
  t.stickout_mm = 40;
  t.flute_length_mm = 25;
  t.youngs_modulus_N_per_mm2 = 600e3;
  t.flutes = 3;
  w.tools.push_back(t);
  return w;
}

const std::string kHead = "G21 G90 G17 G94\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT1 M6\nG43 H1\n";

// Radial CMM points at height z (part frame), every `step` degrees from `from`.
std::vector<CmmPoint> ring(double radius, double z, double from_deg, double step_deg, int n) {
  std::vector<CmmPoint> pts;
  for (int k = 0; k < n; ++k) {
    const double th = degToRad(from_deg + k * step_deg);
    const Vector3d nrm(std::cos(th), std::sin(th), 0);
    pts.push_back({"RING", k + 1, 0, Vector3d(0, 0, z) + radius * nrm, nrm});
  }
  return pts;
}

std::vector<double> cmmRadii(const SimulationOutputs& out) {
  const CsvTable t = parseCsv(out.cmm_csv, "cmm");
  std::vector<double> r;
  for (const auto& row : t.rows) r.push_back(std::hypot(t.number(row, t.column("x_mm")), t.number(row, t.column("y_mm"))));
  return r;
}

SimulationOutputs run(const std::string& program, const parts::Workpiece& w, const MachineTruth& truth,
                      std::vector<CmmPoint> pts = {}) {
  SimulationPart part;
  part.workpiece = &w;
  part.cmm_points = std::move(pts);
  return simulateProgram("mill.ngc", program, nmv(), part, truth, 1);
}

// The tool (r = 5) at radius 53 plunges to part z -5 and C turns once: a cylinder of radius
// 53 - 5 = 48 is left above z -5, the blank's 50 below.
TEST(RotaryCut, AFullTurnLeavesTheCylinderRhoMinusR) {
  const auto w = cylinder();
  const std::string prog = kHead + "S8000 M3\nG0 X53 Y0 Z50\nG1 Z35 F300\nG1 C360 F3600\nG0 Z50\nM5\nM2\n";
  auto pts = ring(48, -2, 0, 30, 12);
  const auto lower = ring(50, -8, 15, 30, 12);
  pts.insert(pts.end(), lower.begin(), lower.end());
  const auto out = run(prog, w, truthFrom(""), pts);
  const auto r = cmmRadii(out);
  ASSERT_EQ(r.size(), 24u);
  for (int k = 0; k < 12; ++k) EXPECT_NEAR(r[k], 48, kCmmRadius) << k;
  for (int k = 12; k < 24; ++k) EXPECT_NEAR(r[k], 50, kCmmRadius) << k;
  // cuts.json says it is an arc: centre on the axis (the part frame's origin), path radius 53,
  // one turn, z -5.
  const auto cuts = nlohmann::json::parse(out.cuts_json);
  const nlohmann::json* arc = nullptr;
  for (const auto& c : cuts)
    if (c.contains("kind") && c["kind"] == "arc") arc = &c;
  ASSERT_NE(arc, nullptr);
  EXPECT_NEAR((*arc)["centre_mm"][0].get<double>(), 0, 1e-12);
  EXPECT_NEAR((*arc)["path_radius_mm"].get<double>(), 53, 1e-9);
  EXPECT_NEAR((*arc)["sweep_deg"].get<double>(), 360, 1e-9);
  EXPECT_NEAR((*arc)["z_mm"].get<double>(), -5, 1e-9);
  // The clock: the tool change (6 s on the NMV); the rapid from the start (gauge line at the
  // top of Z, 660, above the axis) to X53 Y0 and the gauge line at Z 50 + 120 (tool length)
  // = 170, the slowest axis Z over 490 mm at 6000 mm/min: 4.9 s; the plunge of 15 mm at
  // F300: 3 s; 360 deg at F3600 deg/min: 6 s; the rapid up 15 mm: 0.15 s.
  EXPECT_NEAR(out.end_time_s, 6 + 4.9 + 3 + 6 + 0.15, 1e-9);
}

// +C turns the table clockwise (the NMV's positive_rotation), so the part turns clockwise
// under the still tool, which moves counterclockwise over it: G1 C90 from part angle 0 cuts
// the sector 0..90 deg; 135 and -45 deg keep the blank's radius.
TEST(RotaryCut, APartialTurnCutsTheSectorOnTheRightSide) {
  const auto w = cylinder();
  const std::string prog = kHead + "S8000 M3\nG0 X53 Y0 Z50\nG1 Z35 F300\nG1 C90 F3600\nG0 Z50\nM5\nM2\n";
  std::vector<CmmPoint> pts;
  for (double deg : {20.0, 45.0, 70.0, 135.0, 225.0, -45.0}) {
    const auto p = ring(49, -2, deg, 0, 1);
    pts.push_back(p[0]);
  }
  const auto r = cmmRadii(run(prog, w, truthFrom(""), pts));
  ASSERT_EQ(r.size(), 6u);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(r[k], 48, kCmmRadius) << k;
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(r[k], 50, kCmmRadius) << k;
}

// The radial force of an arc cut pushes the tool away from the material, which lies inside
// the circle: outward. F_t = k_c Q / v_c with Q the ring's volume less the plunge's lens over
// the turn's time; the band is left proud by F_n (C_tool + 1/k_x) (the tool stands on the
// machine's +X side: the push is along +X).
TEST(RotaryCut, TheRadialForcePushesTheToolOutward) {
  const auto w = cylinder(0.4);
  const std::string prog = kHead + "S8000 M3\nG0 X53 Y0 Z50\nG1 Z35 F300\nG1 C360 F3600\nG0 Z50\nM5\nM2\n";
  const auto out = run(prog, w, truthFrom("structure: {stiffness_x_N_per_um: 20, stiffness_y_N_per_um: 20}\n"),
                       ring(48, -2, 10, 40, 9));
  const auto cuts = nlohmann::json::parse(out.cuts_json);
  const nlohmann::json* arc = nullptr;
  for (const auto& c : cuts)
    if (c.contains("kind") && c["kind"] == "arc") arc = &c;
  ASSERT_NE(arc, nullptr);
  // Lens of the plunge: circles R = 50 (blank) and r = 5 at d = 53.
  const double R = 50, r = 5, d = 53;
  const double lens = r * r * std::acos((d * d + r * r - R * R) / (2 * d * r)) + R * R * std::acos((d * d + R * R - r * r) / (2 * d * R)) -
                      0.5 * std::sqrt((-d + r + R) * (d + r - R) * (d - r + R) * (d + r + R));
  const double V = (kPi * (R * R - 48.0 * 48) - lens) * 5;  // mm^3 over 5 mm height
  const double dt = 360.0 / 3600 * 60;                      // s
  const double vc = kPi * 10 * 8000 / 60.0;                 // mm/s
  const double Ft = 700.0 * (V / dt) / vc;
  EXPECT_NEAR((*arc)["Ft_N"].get<double>(), Ft, 0.02 * Ft);  // 0.25 mm cells
  const double Fn = (*arc)["Fn_N"].get<double>();
  EXPECT_NEAR(Fn, 0.4 * (*arc)["Ft_N"].get<double>(), 1e-9);
  const double L1 = 25, L2 = 40, E = 600e3, I = kPi * std::pow(10.0, 4) / 64;
  const double c_tool = (std::pow(L1, 3) / 3 + L1 * (L2 - L1) * (L2 + L1) / 6 + L2 * (L2 - L1) * (2 * L2 + L1) / 6) / (E * I);
  const double defl_mm = Fn * (c_tool + 1e-3 / 20.0);
  EXPECT_NEAR((*arc)["radial_deflection_um"].get<double>(), defl_mm * 1e3, 1e-9);
  EXPECT_GT(defl_mm, 0.001);
  for (double radius : cmmRadii(out)) EXPECT_NEAR(radius, 48 + defl_mm, kCmmRadius);
}

// Seed 003's structure on an arc cut (docs/seed003-stiffness.md): the radial component of
// the unit's tip displacement under F_n along +X joins the tool's: F_n/(4 k_x) + theta 40 mm,
// theta = F_n 40/(k_x 100^2) (eqs. 30, 31, by hand here).
TEST(RotaryCut, Seed003StructureAddsItsRadialDisplacement) {
  const auto w = cylinder(0.4);
  const std::string prog = kHead + "S8000 M3\nG0 X53 Y0 Z50\nG1 Z35 F300\nG1 C360 F3600\nG0 Z50\nM5\nM2\n";
  const auto out = run(prog, w, truthFrom(R"(
structure:
  units:
    - {name: crossbeam, k_N_per_mm: [4679, 4926, 142857], shear: [x, y], arm_mm: [0, 5, -40],
       moments: [{force: x, lever: -z, R: 40 mm, spacing: 100 mm}]}
)"), ring(48, -2, 10, 40, 9));
  const auto cuts = nlohmann::json::parse(out.cuts_json);
  const nlohmann::json* arc = nullptr;
  for (const auto& c : cuts)
    if (c.contains("kind") && c["kind"] == "arc") arc = &c;
  ASSERT_NE(arc, nullptr);
  const double Fn = (*arc)["Fn_N"].get<double>();
  ASSERT_GT(Fn, 1);
  const double L1 = 25, L2 = 40, E = 600e3, I = kPi * std::pow(10.0, 4) / 64;
  const double c_tool = (std::pow(L1, 3) / 3 + L1 * (L2 - L1) * (L2 + L1) / 6 + L2 * (L2 - L1) * (2 * L2 + L1) / 6) / (E * I);
  const double defl_mm = Fn * (c_tool + 1 / (4 * 4679.0) + 40.0 * 40 / (4679.0 * 100 * 100));
  EXPECT_NEAR((*arc)["radial_deflection_um"].get<double>(), defl_mm * 1e3, 1e-9);
  for (double radius : cmmRadii(out)) EXPECT_NEAR(radius, 48 + defl_mm, kCmmRadius);
}

void expectRefusal(const std::function<void()>& f, const std::string& want) {
  try {
    f();
    FAIL() << "accepted; expected " << want;
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(RotaryCut, ObstaclesMayNotBeTouched) {
  const auto w = cylinder();
  const auto t = truthFrom("");
  // Down beside the part onto the clamp (top at part z -5): the tool at z -8 (machine 32).
  expectRefusal([&] { run(kHead + "G0 X70 Y0 Z50\nG0 Z32\nM2\n", w, t); },
                "mill.ngc:7: rapid (G0) would touch the clamp 1 (an obstacle)");
  // Beside the clamp, clear of it (30 mm > 5 + 5), then turn the table so that the clamp
  // passes under the tool: the tool at part angle 23.2 deg, radius 76.2; C -40 sweeps it
  // clockwise over the part through angle 0, 6.2 mm from the clamp's centre.
  expectRefusal([&] { run(kHead + "G0 X70 Y30 Z50\nG0 Z32\nG0 C-40\nM2\n", w, t); },
                "mill.ngc:8: rapid (G0) turns the table so that the tool would touch the clamp 1");
  // The same turn the other way (+40: counterclockwise over the part) does not meet it.
  EXPECT_NO_THROW(run(kHead + "G0 X70 Y30 Z50\nG0 Z32\nG0 C40\nM2\n", w, t));
  // A cut into the clamp.
  expectRefusal([&] { run(kHead + "S8000 M3\nG0 X90 Y0 Z50\nG0 Z32\nG1 X60 F500\nM5\nM2\n", w, t); },
                "mill.ngc:9: feed move (G1/G2/G3) would touch the clamp 1");
}

// A move of X/Y/Z together with C: in the part frame the tool follows a curve, which the
// path checks do not follow. Below the top of the part it is refused as not modelled, even
// where the curve would be clear (here beside the part, at z -8 below its top z 0); above the
// top (z +10) nothing can be met: allowed, rapid and feed alike.
TEST(TableTurn, XYZTogetherWithCBelowTheTopIsNotModelled) {
  const auto w = cylinder();
  const auto t = truthFrom("");
  expectRefusal([&] { run(kHead + "G0 X80 Y30 Z50\nG0 Z32\nG0 X85 C20\nM2\n", w, t); },
                "mill.ngc:8: rapid (G0) moves X/Y/Z and C together below the top of the part: not modelled");
  expectRefusal([&] { run(kHead + "G0 X80 Y30 Z50\nG0 Z32\nG1 Y40 C-20 F500\nM2\n", w, t); },
                "mill.ngc:8: feed move (G1/G2/G3) with the spindle stopped moves X/Y/Z and C together below the top of the part: "
                "not modelled");
  // Ending below the top counts too (the tool's bottom at the lower end).
  expectRefusal([&] { run(kHead + "G0 X80 Y30 Z50\nG0 X85 Z32 C20\nM2\n", w, t); },
                "mill.ngc:7: rapid (G0) moves X/Y/Z and C together below the top of the part");
  EXPECT_NO_THROW(run(kHead + "G0 X80 Y30 Z50\nG0 X-40 Y10 C120\nG1 X40 C0 F500\nM2\n", w, t));
}

// F in deg/min for a move of C alone: 432000 deg/min is 1200 rpm, the NMV's turning speed;
// 432360 is 1201 rpm.
TEST(RotaryFeed, FasterThanTheTurningSpeedIsRefused) {
  const auto w = cylinder();
  const auto t = truthFrom("");
  EXPECT_NO_THROW(run(kHead + "G0 Z80\nG1 C72000 F432000\nM2\n", w, t));
  expectRefusal([&] { run(kHead + "G0 Z80\nG1 C72000 F432360\nM2\n", w, t); },
                "mill.ngc:7: rotary feed F432360 deg/min (1201 rpm) exceeds the C axis's maximum turning speed 1200 rpm");
  // An XYZ feed is still limited by the axes' 6000 mm/min.
  expectRefusal([&] { run(kHead + "G0 Z80\nG1 X10 F7000\nM2\n", w, t); }, "exceeds the machine's maximum feed 6000");
}

// The test's load: C turned by feed moves at 1200 rpm (G1 C72000 F432000: 200 turns in 10 s)
// heats the C-axis node with W_per_rpm x 1200 = 80 W; the node (C = 6000 J/K, G = 4 W/K,
// tau = 1500 s) follows dT = Q/G (1 - exp(-t/tau)) for 1200 s, then cools for 600 s of dwell.
// inputs.csv's c_rpm reads 1200 while C turns and 0 in the dwell (no duty in this truth).
TEST(RotaryFeed, TheCLoadHeatsTheCAxisNode) {
  const auto w = cylinder();
  std::string prog = "G21 G90\n";
  for (int k = 0; k < 60; ++k) prog += "G1 C72000 F432000\nG1 C0\n";
  prog += "G4 P600\nM2\n";
  const auto out = run(prog, w, truthFrom(R"(
thermal:
  environment: {mean_C: 20}
  nodes: [{name: c_axis, capacity_J_per_K: 6000, to_environment_W_per_K: 4}]
  sources: [{node: c_axis, input: c_axis_speed, W_per_rpm: 0.0667}]
  sensors: [{column: T_caxis_C, node: c_axis}]
inputs_rate: 60 s
)"));
  EXPECT_NEAR(out.end_time_s, 1800, 1e-6);
  const CsvTable t = parseCsv(out.inputs_csv, "inputs");
  const double Q = 0.0667 * 1200, G = 4, tau = 6000 / G, t_load = 1200;
  const double dT_end = Q / G * (1 - std::exp(-t_load / tau));
  int load_rows = 0, dwell_rows = 0;
  for (const auto& row : t.rows) {
    const double time = t.number(row, t.column("time_s"));
    const double rpm = t.number(row, t.column("c_rpm"));
    const double dT = time <= t_load ? Q / G * (1 - std::exp(-time / tau)) : dT_end * std::exp(-(time - t_load) / tau);
    EXPECT_NEAR(t.number(row, t.column("T_caxis_C")), 20 + dT, 6e-4) << time;
    if (time > 0 && time <= t_load) {
      EXPECT_EQ(rpm, 1200) << time;
      ++load_rows;
    } else if (time > t_load) {
      EXPECT_EQ(rpm, 0) << time;
      ++dwell_rows;
    }
  }
  EXPECT_EQ(load_rows, 20);
  EXPECT_EQ(dwell_rows, 10);
}

// The thermal test piece on the NMV: the test tool (d12) waits at (-130, 0) at the cutting
// height z -12.1, below the top, while the table turns: its edge at 124 mm is clear of the
// material (radius <= 101.5) by far more than 0.5 mm. At (-100, 0), in a slot cut along -X,
// the segments beside the slot would sweep into it: refused. The slot is cut by a first
// program, the turns are a second one (the stock carries over).
TEST(TableTurn, BelowTheTopOnlyClearOfTheMaterial) {
  const auto piece = parts::loadTestPiece(src("parts/thermal_test_piece.yaml"));
  const auto m = nmv();
  const Vector3d o = parts::partOriginOnMachine(*piece.thermalTestPiece(), m.c_axis_centre_mm, m.table_surface_z_mm);
  ASSERT_NEAR(o.z(), 40 + 3 + 24, 1e-12);  // adapter + washer + finished height
  auto z = [&](double part_z) { return formatNumber(part_z + o.z(), 4); };
  const std::string slot = "G21 G90 G17\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT1 M6\nG43 H1\nS6000 M3\nG0 X-115 Y0 Z" + z(10) +
                           "\nG0 Z" + z(-12) + "\nG1 X-60 F1500\nG1 X-115\nG0 Z" + z(10) + "\nM5\nM2\n";
  const std::string wait = "G21 G90 G17\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT3 M6\nG43 H3\nG0 X-130 Y0 Z" + z(10) + "\nG0 Z" +
                           z(-12.1) + "\nG0 C90\nS8000 M3\nG1 C72000 F432000\nG1 C0\nM5\n";
  SimulationPart part;
  part.test_piece = &piece;
  const auto truth = truthFrom("");
  const auto out = simulatePrograms({{"slot.ngc", slot}, {"wait.ngc", wait + "M2\n"}}, m, part, truth, 1);
  EXPECT_GT(out.end_time_s, 10);  // the 200 turns took 10 s
  const std::string into = wait + "G0 Z" + z(-11) + "\nG0 X-100\nG0 C10\nM2\n";
  expectRefusal([&] { simulatePrograms({{"slot.ngc", slot}, {"wait.ngc", into}}, m, part, truth, 1); },
                "wait.ngc:15: rapid (G0) turns the table with the tool below the top of the stock and within reach of its material");
}

// Two programs on one machine: the clock, the stock and the position carry on; each
// LinuxCNC program writes its own log; the points of both are in points.csv (P<position> for
// a part that is not a sphere artifact); the trace names the program.
TEST(SeveralPrograms, RunBackToBackOnOneMachine) {
  const auto w = cylinder();
  auto probe = [](const std::string& log, int point) {
    return "G21 G90\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT99 M6\nG43 H99\nG0 X10 Y0 Z60\n(LOGOPEN," + log + ")\nG38.2 Z30 F100\n(LOG,PT 1 1 " +
           std::to_string(point) + " #5061 #5062 #5063)\nG0 Z60\nG4 P100\nM2\n";
  };
  SimulationPart part;
  part.workpiece = &w;
  part.trace = true;
  const auto truth = truthFrom("");
  const auto one = simulatePrograms({{"a.ngc", probe("a.log", 1)}}, nmv(), part, truth, 1);
  const auto two = simulatePrograms({{"a.ngc", probe("a.log", 1)}, {"b.ngc", probe("b.log", 2)}}, nmv(), part, truth, 1);
  ASSERT_EQ(two.logs.size(), 2u);
  EXPECT_EQ(two.logs[0].name, "a.log");
  EXPECT_EQ(two.logs[1].name, "b.log");
  // The probe's tip centre (r 3) meets the top (machine z 40) at 43.
  EXPECT_EQ(two.logs[0].text, "PT 1 1 1 10.000000 0.000000 43.000000\n");
  EXPECT_EQ(two.logs[1].text, "PT 1 1 2 10.000000 0.000000 43.000000\n");
  // b starts where a ended: its clock runs on, and its probe stands where a left it. a's first
  // rapid brought the probe down from the start height (gauge 660 mm) to Z 60 + 150 = 210 at
  // 6000 mm/min: 4.5 s that b does not need; b's own tool change and the rest take as long.
  const double first_rapid_s = (660.0 - 210.0) / 6000 * 60;
  EXPECT_NEAR(two.end_time_s, 2 * one.end_time_s - first_rapid_s, 1e-9);
  const CsvTable pts = parseCsv(two.points_csv, "points");
  ASSERT_EQ(pts.rows.size(), 2u);
  EXPECT_EQ(pts.rows[0].fields[3], "P1");
  EXPECT_EQ(pts.rows[1].fields[3], "P1");
  EXPECT_NEAR(pts.number(pts.rows[1], 0) - pts.number(pts.rows[0], 0), one.end_time_s - first_rapid_s, 1e-3);
  const CsvTable tr = parseCsv(two.trace_csv, "trace");
  ASSERT_GE(tr.column("program"), 0);
  EXPECT_EQ(tr.rows.front().fields[static_cast<std::size_t>(tr.column("program"))], "a.ngc");
  EXPECT_EQ(tr.rows.back().fields[static_cast<std::size_t>(tr.column("program"))], "b.ngc");
  EXPECT_EQ(parseCsv(one.trace_csv, "trace").column("program"), -1);  // one program: the trace as it was
  // A log name an earlier program wrote would be overwritten by LinuxCNC: refused.
  expectRefusal([&] { simulatePrograms({{"a.ngc", probe("a.log", 1)}, {"b.ngc", probe("a.log", 2)}}, nmv(), part, truth, 1); },
                "b.ngc:7: LOGOPEN,a.log: an earlier program of this run (a.ngc) wrote this log");
  // Fanuc: all DPRNT output of the run in one dprnt.txt, as the DPRNT device collects it.
  const std::string fanuc = "G21 G90\nPOPEN\nDPRNT[HELLO]\nPCLOS\nM30\n";
  const auto f = simulatePrograms({{"a.nc", fanuc}, {"b.nc", fanuc}}, nmv(), part, truth, 1);
  ASSERT_EQ(f.logs.size(), 1u);
  EXPECT_EQ(f.logs[0].name, "dprnt.txt");
  EXPECT_EQ(f.logs[0].text, "%\nHELLO\n%\n%\nHELLO\n%\n");
  // Same inputs, same seed: the same bytes.
  const auto again = simulatePrograms({{"a.ngc", probe("a.log", 1)}, {"b.ngc", probe("b.log", 2)}}, nmv(), part, truth, 1);
  EXPECT_EQ(again.points_csv, two.points_csv);
  EXPECT_EQ(again.truth_json, two.truth_json);
  EXPECT_EQ(again.trace_csv, two.trace_csv);
  EXPECT_EQ(again.inputs_csv, two.inputs_csv);
}

// The CMM room: the part is measured at 20 C + dT, dT drawn within +-0.3 K and printed; an
// uncorrecting CMM finds every point scaled about the datum (the block's bottom centre at
// z 0) by 1 + alpha dT: the top at 38 reads 38 (1 + 23.4e-6 dT).
TEST(CmmRoom, ThePartsTemperatureScalesThePoints) {
  auto w = parts::loadWorkpiece(src("examples/workpiece_block.yaml"));
  w.material.radial_force_ratio = 0;
  w.cmm.mpe_constant_um = 0;
  w.cmm.mpe_length_mm = 0;
  w.cmm.temperature_half_width_K = 0.3;
  std::string prog = "G21 G90\nG10 L2 P6 X0 Y0 Z0 C0\nG59\nT1 M6\nG43 H1\nS8000 M3\nG0 X-50 Y-34 Z60\nG0 Z38\n";
  for (int k = 0; k < 10; ++k) prog += "G1 X" + std::string(k % 2 ? "-50" : "50") + " F800\nG1 Y" + std::to_string(-26 + 8 * k) + "\n";
  prog += "G0 Z60\nM5\nM2\n";
  std::vector<CmmPoint> pts;
  for (double x : {-30.0, 0.0, 25.0}) pts.push_back({"TOP", static_cast<int>(pts.size()) + 1, 0, Vector3d(x, 5, 38), Vector3d(0, 0, 1)});
  SimulationPart part;
  part.workpiece = &w;
  part.cmm_points = pts;
  const auto m = parts::loadMachine(src("parts/machines/linuxcnc_rotary_mill.yaml"));
  auto dTof = [](const std::string& csv) {
    const auto at = csv.find("dT = ");
    EXPECT_NE(at, std::string::npos) << csv;
    return std::stod(csv.substr(at + 5));
  };
  const auto out = simulateProgram("block.ngc", prog, m, part, truthFrom(""), 1);
  const double dT = dTof(out.cmm_csv);
  EXPECT_LE(std::fabs(dT), 0.3);
  EXPECT_GT(std::fabs(dT), 0);
  const CsvTable t = parseCsv(out.cmm_csv, "cmm");
  for (const auto& row : t.rows) EXPECT_NEAR(t.number(row, t.column("z_mm")), 38 * (1 + 23.4e-6 * dT), kCmmDigit);
  // Its own stream: seeded, and another seed draws another temperature.
  EXPECT_EQ(dTof(simulateProgram("block.ngc", prog, m, part, truthFrom(""), 1).cmm_csv), dT);
  EXPECT_NE(dTof(simulateProgram("block.ngc", prog, m, part, truthFrom(""), 2).cmm_csv), dT);
}

}  // namespace
}  // namespace probeloop::sim
