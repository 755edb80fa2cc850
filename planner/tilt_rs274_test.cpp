// Sphere cycles that tilt the table, through LinuxCNC's own interpreter (rs274, linuxcnc-uspace;
// scripts/setup.sh installs it) and our safety verifier, on the LinuxCNC B/C trunnion mill and
// the table-table A/C machine (issue 33: "rs274 accepts the generalised sphere cycle for the
// B/C and A/C machines").
//
// Hand-built: the probing program is made here from ProbeProgram ops (gcode/probe_program.hpp)
// and written by the project's LinuxCNC writer, the sphere placed at each (tilt, C) pose by the
// chain written out below (not by the planner): a table point p turns about C (C' clockwise
// seen from +Z: by -C about +Z), then the tilting body turns it about its axis line by +q
// about -Y (B) or -X (A), clockwise seen from +Y / +X (parts/machine_chain.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "gcode/probe_program.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "verify/safety.hpp"

namespace probeloop {
namespace {

constexpr double kPi = 3.14159265358979323846;
const std::string kSrc = PROBELOOP_SOURCE_DIR;

struct Pose {
  double q_deg, c_deg;  // the tilting axis (A or B), C
};

// The sphere centre of parts/sphere_artifact.yaml (160 mm from C at 180 deg, 75 mm above the
// table) at a pose, machine (tip) coordinates.
Eigen::Vector3d sphereAt(const parts::Machine& m, const Pose& p) {
  const double c = p.c_deg * kPi / 180, q = p.q_deg * kPi / 180;
  // C' clockwise: the part angle 180 deg shows at 180 - C.
  const double th = kPi - c;
  Eigen::Vector3d x(160 * std::cos(th), 160 * std::sin(th), 75);
  if (m.b.present) {  // by -q about +Y through (X0, Z0)
    const double cx = m.b_axis_centre_xz_mm->x(), cz = m.b_axis_centre_xz_mm->y();
    const double dx = x.x() - cx, dz = x.z() - cz;
    x.x() = cx + dx * std::cos(q) - dz * std::sin(q);
    x.z() = cz + dx * std::sin(q) + dz * std::cos(q);
  } else {  // by -q about +X through (Y0, Z0)
    const double cy = m.a_axis_centre_yz_mm->x(), cz = m.a_axis_centre_yz_mm->y();
    const double dy = x.y() - cy, dz = x.z() - cz;
    x.y() = cy + dy * std::cos(q) + dz * std::sin(q);
    x.z() = cz - dy * std::sin(q) + dz * std::cos(q);
  }
  return x;
}

gcode::Op tilt(const parts::Machine& m, double q) {
  return m.b.present ? gcode::Op{gcode::RotateB{q}} : gcode::Op{gcode::RotateA{q}};
}

// Every pose: up to the safe height over the C axis, tilt, turn, over the sphere, a protected
// descent to 3 mm above its top, the measuring move 2 mm past the top, back up.
constexpr double kSafeZ = 200, kApproach = 3, kOvertravel = 2, kTipR = 3, kSphereR = 15;
gcode::ProbeProgram program(const parts::Machine& m, const std::vector<Pose>& poses) {
  gcode::ProbeProgram p;
  p.title = "tilted sphere cycle (hand-built)";
  p.work_offset = m.work_offset;
  p.has_a_axis = m.a.present;
  p.has_b_axis = m.b.present;
  p.log_file = "tilt.log";
  p.before_cycles = {gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{m.probe.tool, true},
                     gcode::Rapid{0.0, 0.0, kSafeZ}};
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Vector3d s = sphereAt(m, poses[k]);
    const double top = s.z() + kSphereR + kTipR;
    for (const gcode::Op& op : {gcode::Op{gcode::Rapid{std::nullopt, std::nullopt, kSafeZ}}, gcode::Op{gcode::Rapid{0.0, 0.0, std::nullopt}},
                                tilt(m, poses[k].q_deg), gcode::Op{gcode::RotateC{poses[k].c_deg}},
                                gcode::Op{gcode::Rapid{s.x(), s.y(), std::nullopt}},
                                gcode::Op{gcode::ProtectedMove{s.x(), s.y(), top + kApproach, 1000}},
                                gcode::Op{gcode::ProbeMove{s.x(), s.y(), top - kOvertravel, 200, static_cast<int>(k) + 1, 1}},
                                gcode::Op{gcode::Rapid{s.x(), s.y(), top + kApproach}}})
      p.cycle_body.push_back(op);
  }
  p.after_cycles = {gcode::Rapid{std::nullopt, std::nullopt, kSafeZ}, gcode::Rapid{0.0, 0.0, std::nullopt}, tilt(m, 0),
                    gcode::RotateC{0}, gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{0, false}};
  return p;
}

std::vector<std::vector<double>> calls(const std::string& canon, const std::string& name) {
  std::vector<std::vector<double>> out;
  const std::regex re(name + "\\(([-0-9., ]+)\\)");
  for (auto it = std::sregex_iterator(canon.begin(), canon.end(), re); it != std::sregex_iterator(); ++it) {
    std::vector<double> v;
    std::stringstream s((*it)[1].str());
    for (std::string f; std::getline(s, f, ',');) v.push_back(std::stod(f));
    out.push_back(v);
  }
  return out;
}

void checkMachine(const std::string& machine_file, const std::vector<Pose>& poses) {
  namespace fs = std::filesystem;
  SCOPED_TRACE(machine_file);
  const auto m = parts::loadMachine(kSrc + "/parts/machines/" + machine_file);
  const auto piece = parts::loadTestPiece(kSrc + "/parts/sphere_artifact.yaml");
  const std::string text = gcode::writeLinuxCnc(program(m, poses));
  // Our verifier accepts it: every swing at the safe height over the C axis, the probing on the
  // tilted sphere's top.
  const auto rep = verify::checkPrograms({{"tilt.ngc", text}}, m, piece);
  EXPECT_TRUE(rep.safe()) << verify::reportText(rep);

  ASSERT_EQ(std::system("command -v rs274 >/dev/null 2>&1"), 0)
      << "LinuxCNC's rs274 is not installed (linuxcnc-uspace; run scripts/setup.sh)";
  const fs::path dir = fs::temp_directory_path() / ("probeloop_tilt_rs274_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  // rs274 standalone reads tool lengths in inches: the probe's 150 mm.
  std::ofstream(dir / "tool.tbl") << "T99 P99 Z5.905511811 D0.236220472 ;probe\n";
  std::ofstream(dir / "tilt.ngc") << text;
  const std::string cmd = "cd '" + dir.string() + "' && rs274 -t tool.tbl -g tilt.ngc > canon.txt 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::stringstream s;
  s << std::ifstream(dir / "canon.txt").rdbuf();
  const std::string canon = s.str();
  fs::remove_all(dir);
  EXPECT_NE(canon.find("PROGRAM_END()"), std::string::npos) << canon.substr(canon.size() > 2000 ? canon.size() - 2000 : 0);
  EXPECT_EQ(canon.find("ABORT"), std::string::npos);
  // Two probe moves per pose (protected, measuring), the measuring one at the target this file
  // derived, with the rotary axes where the pose put them (canonical order X Y Z A B C).
  const auto probes = calls(canon, "STRAIGHT_PROBE");
  ASSERT_EQ(probes.size(), 2 * poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto& p = probes[2 * k + 1];
    ASSERT_GE(p.size(), 6u);
    const Eigen::Vector3d c = sphereAt(m, poses[k]);
    EXPECT_NEAR(p[0], c.x(), 6e-5) << k;
    EXPECT_NEAR(p[1], c.y(), 6e-5) << k;
    EXPECT_NEAR(p[2], c.z() + kSphereR + kTipR - kOvertravel, 6e-5) << k;
    EXPECT_NEAR(p[m.b.present ? 4 : 3], poses[k].q_deg, 5e-4) << k;
    EXPECT_NEAR(p[5], poses[k].c_deg, 5e-4) << k;
  }
  std::size_t logs = 0;
  for (auto at = canon.find("LOG(\"PT "); at != std::string::npos; at = canon.find("LOG(\"PT ", at + 1)) ++logs;
  EXPECT_EQ(logs, poses.size());
  // Every move of A, B or C is made with the tip at the safe height.
  const auto moves = calls(canon, "STRAIGHT_TRAVERSE");
  int rotary_moves = 0;
  for (std::size_t i = 1; i < moves.size(); ++i) {
    if (moves[i].size() < 6) continue;
    bool rotary = false;
    for (int a = 3; a < 6; ++a) rotary = rotary || std::fabs(moves[i][a] - moves[i - 1][a]) > 1e-9;
    if (!rotary) continue;
    ++rotary_moves;
    EXPECT_NEAR(moves[i][2], kSafeZ, 1e-4) << "rotary move " << i;
    EXPECT_NEAR(moves[i - 1][2], kSafeZ, 1e-4) << "rotary move " << i;
  }
  EXPECT_GE(rotary_moves, static_cast<int>(poses.size()));
}

TEST(TiltRs274, HandBuiltTiltedCycleOnTheBCTrunnion) {
  // B -30 deg lifts the sphere at C 0 to (-101.1, 0, 145.0); B +30 at C 180 to (101.1, 0, 145.0).
  checkMachine("linuxcnc_trunnion_bc.yaml", {{0, 0}, {-30, 0}, {-30, 90}, {30, 180}, {30, 270}, {0, 360}});
}

TEST(TiltRs274, HandBuiltTiltedCycleOnTheACMachine) {
  // A +30 deg carries the sphere at C 0, 125 mm above the A line, to (-160, 62.5, 58.3).
  checkMachine("table_table_ac.yaml", {{0, 0}, {30, 0}, {-30, 90}, {30, 180}, {-30, 270}, {0, 360}});
}

}  // namespace
}  // namespace probeloop
