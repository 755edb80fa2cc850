// The thermal test piece's programs (seed 004 Ch. 7, docs/thermal-test-piece.md §5): the
// test's one Z, the cuts and their order, the C indices on both C senses, the cycle
// structure, the geometry of every move near the part, travel refusals, the probe points,
// the C load, and the emitted texts run through our interpreter with the simulator's clock.
#include "planner/thermal_test_piece.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "gcode/interpreter.hpp"

using namespace probeloop;
using namespace probeloop::planner;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;
parts::ThermalTestPiece piece() { return parts::loadThermalTestPiece(src + "/parts/thermal_test_piece.yaml"); }
parts::Machine nmv() { return parts::loadMachine(src + "/parts/machines/nmv5000.yaml"); }
parts::Machine mill() { return parts::loadMachine(src + "/parts/machines/linuxcnc_rotary_mill.yaml"); }

const NotedProgram& program(const ThermalTestPiecePlan& p, const std::string& role) {
  for (const auto& x : p.programs)
    if (x.role == role) return x;
  throw std::runtime_error("no program " + role);
}

std::vector<const parts::ManifestCut*> testCuts(const parts::PlanManifest& m) {
  std::vector<const parts::ManifestCut*> v;
  for (const auto& c : m.cuts)
    if (c.program == "test") v.push_back(&c);
  return v;
}

// The C that turns part direction `deg` to machine direction `to`, derived by hand: a table
// turning clockwise for +C (C') carries a part direction phi to phi - C, counterclockwise to
// phi + C.
double byHand(bool clockwise, double deg, double to) {
  double c = clockwise ? deg - to : to - deg;
  c = std::fmod(c, 360.0);
  return c < 0 ? c + 360 : c;
}

// A machine direction of a part direction at C (the simulator's convention, docs/conventions.md).
Vector2d atC(const Vector2d& v, double c_deg, bool clockwise) { return parts::turnedByTable(v, c_deg, clockwise); }

double segmentToOrigin(const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double s = ab.squaredNorm() > 0 ? std::clamp(-a.dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (a + s * ab).norm();
}
}  // namespace

TEST(ThermalTestPiecePlan, TheTestProgramHasNoZWordBetweenTheFirstAndTheLastCut) {
  const auto t = piece();
  for (auto d : {parts::Dialect::LinuxCnc, parts::Dialect::FanucMacroB}) {
    const auto plan = planThermalTestPiece(t, nmv(), d);
    const std::string text = ttpProgramText(program(plan, "test"), d);
    std::istringstream in(text);
    std::string line;
    std::vector<std::string> lines;
    while (std::getline(in, line)) lines.push_back(line);
    // Cuts are the feeds at the test feed; the one Z is the descent to the cutting height.
    const std::string feed = "F" + formatNumber(t.test_feed_mm_per_min, 3);
    int first = -1, last = -1, z_words = 0, z_set = -1;
    const std::regex z_word(R"(\bZ-?\d)");
    for (int i = 0; i < static_cast<int>(lines.size()); ++i) {
      const std::string code = lines[i].substr(0, lines[i].find('('));
      if (code.rfind("G1 ", 0) == 0 && code.find(feed) != std::string::npos) {
        if (first < 0) first = i;
        last = i;
      }
      if (std::regex_search(code, z_word)) {
        ++z_words;
        if (code.find("G53") == std::string::npos) z_set = i;
      }
    }
    ASSERT_GT(first, 0);
    int cuts = 0;
    for (int i = first; i <= last; ++i) {
      const std::string code = lines[i].substr(0, lines[i].find('('));
      EXPECT_FALSE(std::regex_search(code, z_word)) << "line " << i + 1 << ": " << lines[i];
      if (code.rfind("G1 ", 0) == 0 && code.find(feed) != std::string::npos) ++cuts;
    }
    EXPECT_EQ(cuts, 45);
    EXPECT_LT(z_set, first);
    // The Z words: the retracts at the start and the end (G53), the clearance plane, the cutting height.
    EXPECT_EQ(z_words, 5) << text.substr(0, 2000);
    EXPECT_NE(lines[static_cast<std::size_t>(z_set)].find("Z" + formatNumber(plan.test_cutting_z_mm, 4)), std::string::npos);
  }
}

TEST(ThermalTestPiecePlan, FortyFiveFinishingCutsReferencesFirstEachSideOnItsSide) {
  const auto t = piece();
  const auto m = nmv();
  const auto plan = planThermalTestPiece(t, m, parts::Dialect::FanucMacroB);
  const auto cuts = testCuts(plan.manifest);
  ASSERT_EQ(cuts.size(), 45u);
  const double r = t.tool(t.test_tool)->diameter_mm / 2, ap = t.facet_apothem_mm + r, L = t.facet_path_half_length_mm;
  const Vector3d O = plan.manifest.part_origin_mm;
  const char* sides[4] = {"X1", "Y1", "X2", "Y2"};
  for (int c = 0; c < 9; ++c) {
    const int k = t.order[static_cast<std::size_t>(c)];
    const auto* z = cuts[static_cast<std::size_t>(5 * c)];
    EXPECT_EQ(z->feature, "Z" + std::to_string(k));
    EXPECT_EQ(z->cycle, c);
    EXPECT_NEAR(z->from_mm.x() - O.x(), t.z_path_x_from_mm, 1e-9);  // along +X
    EXPECT_NEAR(z->to_mm.x() - O.x(), t.z_path_x_to_mm, 1e-9);
    EXPECT_NEAR(z->to_mm.y() - O.y(), parts::zPathY(t, k), 1e-9);
    for (int s = 0; s < 4; ++s) {
      const auto* f = cuts[static_cast<std::size_t>(5 * c + 1 + s)];
      EXPECT_EQ(f->feature, std::string(sides[s]) + "_" + std::to_string(k));
      EXPECT_EQ(f->cycle, c);
      const Vector2d a = (f->from_mm - O).head<2>(), b = (f->to_mm - O).head<2>();
      switch (s) {
        case 0:  // X1 on the machine's +X side, moving -Y
          EXPECT_NEAR(a.x(), ap, 1e-9); EXPECT_NEAR(b.x(), ap, 1e-9); EXPECT_NEAR(a.y(), L, 1e-9); EXPECT_NEAR(b.y(), -L, 1e-9);
          break;
        case 1:  // Y1 on +Y, moving -X
          EXPECT_NEAR(a.y(), ap, 1e-9); EXPECT_NEAR(b.y(), ap, 1e-9); EXPECT_NEAR(a.x(), L, 1e-9); EXPECT_NEAR(b.x(), -L, 1e-9);
          break;
        case 2:  // X2 on -X, moving -Y
          EXPECT_NEAR(a.x(), -ap, 1e-9); EXPECT_NEAR(b.x(), -ap, 1e-9); EXPECT_NEAR(b.y(), -L, 1e-9);
          break;
        case 3:  // Y2 on -Y, moving -X
          EXPECT_NEAR(a.y(), -ap, 1e-9); EXPECT_NEAR(b.y(), -ap, 1e-9); EXPECT_NEAR(b.x(), -L, 1e-9);
          break;
      }
      // Every cut of a side lies on the same machine line every hour (L1986): only C changes.
      const auto* ref = cuts[static_cast<std::size_t>(1 + s)];
      EXPECT_TRUE(f->from_mm.isApprox(ref->from_mm) && f->to_mm.isApprox(ref->to_mm));
    }
  }
  // All at the same Z, in the order of the clock.
  for (std::size_t i = 1; i < cuts.size(); ++i) {
    EXPECT_GT(cuts[i]->start_s, cuts[i - 1]->end_s - 1e-9);
    EXPECT_DOUBLE_EQ(cuts[i]->to_mm.z(), cuts[0]->from_mm.z());
  }
  EXPECT_NEAR(cuts[0]->from_mm.z(), O.z() + t.cuttingZ(), 1e-9);
}

TEST(ThermalTestPiecePlan, FacetIndicesTurnTheNormalsToMachinePlusXAndPlusYOnBothCSenses) {
  const auto t = piece();
  for (bool clockwise : {true, false}) {
    auto m = nmv();
    m.c.positive_is_clockwise = clockwise;
    const auto plan = planThermalTestPiece(t, m, parts::Dialect::FanucMacroB);
    ASSERT_EQ(plan.manifest.cut_cycles.size(), 9u);
    for (const auto& c : plan.manifest.cut_cycles) {
      const double phi = t.first_normal_angle_deg + (c.facet - 1) * t.facet_pitch_deg;  // X1_k normal
      EXPECT_NEAR(c.c_x_deg, byHand(clockwise, phi, 0), 1e-9);
      EXPECT_NEAR(c.c_y_deg, byHand(clockwise, 180 - phi, 90), 1e-9);  // Y1_k is X1_k mirrored about Y
      const auto nx = atC(Vector2d(std::cos(degToRad(phi)), std::sin(degToRad(phi))), c.c_x_deg, clockwise);
      EXPECT_NEAR(nx.x(), 1, 1e-12) << "cycle " << c.cycle;
      const auto ny = atC(Vector2d(std::cos(degToRad(180 - phi)), std::sin(degToRad(180 - phi))), c.c_y_deg, clockwise);
      EXPECT_NEAR(ny.y(), 1, 1e-12) << "cycle " << c.cycle;
      // X2 and Y2 are cut at the same indices, facing -X and -Y.
      const auto n2 = atC(Vector2d(std::cos(degToRad(phi + 180)), std::sin(degToRad(phi + 180))), c.c_x_deg, clockwise);
      EXPECT_NEAR(n2.x(), -1, 1e-12);
    }
    // By hand for the first facet: clockwise C 36.5 (and Y1_1 at 53.5), counterclockwise 323.5 (306.5).
    const auto& c1 = plan.manifest.cut_cycles[1];
    EXPECT_EQ(c1.facet, 1);
    EXPECT_NEAR(c1.c_x_deg, clockwise ? 36.5 : 323.5, 1e-9);
    EXPECT_NEAR(c1.c_y_deg, clockwise ? 53.5 : 306.5, 1e-9);
  }
}

TEST(ThermalTestPiecePlan, CutTimesFollowTheCycleStructure) {
  const auto t = piece();
  const auto plan = planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
  const auto& m = plan.manifest;
  const auto& cy = m.cut_cycles;
  ASSERT_EQ(cy.size(), 9u);
  const auto* test = m.program("test");
  ASSERT_TRUE(test);
  double cutting = 0;
  for (std::size_t c = 0; c < cy.size(); ++c) {
    EXPECT_EQ(cy[c].cycle, static_cast<int>(c));
    EXPECT_EQ(cy[c].phase, c == 0 ? "reference" : c <= 4 ? "warm_up" : "hold");
    EXPECT_EQ(cy[c].c_axis_rpm_before, c == 0 ? 0 : c <= 4 ? 1200 : 0);
    cutting += cy[c].end_s - cy[c].start_s;
    EXPECT_GT(cy[c].end_s - cy[c].start_s, 20);
    EXPECT_LT(cy[c].end_s - cy[c].start_s, 60);
    if (c > 0) {
      EXPECT_NEAR(cy[c].start_s - cy[c - 1].end_s, t.wait_s, 1e-6) << "wait before cycle " << c;
    }
    // The cycle's five surfaces are finished inside it.
    for (const auto& k : m.cuts)
      if (k.cycle == static_cast<int>(c)) {
        EXPECT_GE(k.start_s, cy[c].start_s);
        EXPECT_LE(k.end_s, cy[c].end_s);
        const auto* f = m.feature(k.feature);
        ASSERT_TRUE(f);
        EXPECT_EQ(f->cycle, static_cast<int>(c));
        EXPECT_NEAR(f->cut_time_s, (k.start_s + k.end_s) / 2, 1e-9);
      }
  }
  // The test: 8 waits + 9 cycles + setting up and leaving (< 1 min): the thesis's 8 h 5 min.
  const double span = cy.back().end_s - cy.front().start_s;
  EXPECT_NEAR(span, 8 * t.wait_s + cutting, 1e-6);
  EXPECT_GT(test->duration_s, span);
  EXPECT_LT(test->duration_s, span + 60);
  EXPECT_NEAR(test->duration_s, 8 * 3600 + 5 * 60, 60);
  // Programs back to back from 0; pre-machining about 15 min (L2018).
  EXPECT_EQ(m.programs[0].start_s, 0);
  EXPECT_NEAR(m.programs[1].start_s, m.programs[0].duration_s, 1e-9);
  EXPECT_NEAR(m.programs[2].start_s, m.programs[1].start_s + m.programs[1].duration_s, 1e-9);
  EXPECT_GT(m.programs[0].duration_s, 10 * 60);
  EXPECT_LT(m.programs[0].duration_s, 20 * 60);
  // Schedule: one inspection cycle.
  EXPECT_EQ(m.cycles, 1);
  EXPECT_EQ(m.cycle_start_s, std::vector<double>{m.programs[2].start_s});
  EXPECT_NEAR(m.cycle_time_s, m.programs[2].duration_s, 1e-9);
  // Datums are cut in pre-machining: TOP by the face passes, the flanks, the CYL band turn.
  for (const char* id : {"TOP", "FLANK_P", "FLANK_N", "CYL"}) {
    const auto* f = m.feature(id);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->cycle, -1);
    EXPECT_GT(f->cut_time_s, 0);
    EXPECT_LT(f->cut_time_s, m.programs[0].duration_s);
  }
}

TEST(ThermalTestPiecePlan, EveryMoveBelowTheTopStaysOutsideThePartAndCTurnsOnlyWithTheToolClear) {
  const auto t = piece();
  for (const auto& m : {nmv(), mill()}) {
    const auto plan = planThermalTestPiece(t, m, m.dialect);
    const Vector3d O = plan.manifest.part_origin_mm;
    const double R = t.blank_diameter_mm / 2;
    const bool cw = m.c.positive_is_clockwise;
    int checked = 0, c_turns = 0, in_notch = 0, at_facet = 0;
    for (const auto& p : plan.programs) {
      // Walk the ops: tip position (program = machine), C, tool radius, probe or not.
      Vector3d tip(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), m.z.max_mm);
      double c = 0, r = 0, len = 0;
      bool probe = false;
      const double top = p.role == "pre_machining" ? t.face_depth_mm : 0.0;
      for (std::size_t i = 0; i < p.program.ops.size(); ++i) {
        const auto& op = p.program.ops[i];
        const auto& note = p.notes[i];
        Vector3d to = tip;
        double c_to = c;
        bool motion = true;
        if (const auto* x = std::get_if<gcode::Rapid>(&op)) {
          if (x->x) to.x() = *x->x;
          if (x->y) to.y() = *x->y;
          if (x->z) to.z() = *x->z;
        } else if (const auto* x = std::get_if<gcode::Feed>(&op)) {
          if (x->x) to.x() = *x->x;
          if (x->y) to.y() = *x->y;
          if (x->z) to.z() = *x->z;
        } else if (const auto* x = std::get_if<gcode::TurnC>(&op)) {
          c_to = c + x->delta_deg;
        } else if (const auto* x = std::get_if<gcode::ProtectedMove>(&op)) {
          to = Vector3d(x->x, x->y, x->z);
        } else if (std::holds_alternative<gcode::ProbeMove>(op)) {
          tip = note.contact_mm;  // stops at contact
          continue;
        } else if (const auto* x = std::get_if<gcode::RapidMachineZ>(&op)) {
          to.z() = x->z_mm - len;
        } else if (const auto* x = std::get_if<gcode::RotateC>(&op)) {
          c_to = x->c_deg;
        } else if (const auto* x = std::get_if<gcode::ToolChange>(&op)) {
          probe = x->tool == m.probe.tool;
          r = probe ? m.probe.tip_diameter_mm / 2 : x->apply_length_offset ? t.tool(x->tool)->diameter_mm / 2 : 0;
          len = probe ? m.probe.length_mm : x->apply_length_offset ? t.tool(x->tool)->length_mm : 0;
          tip.z() = m.tool_change.z_mm - len;
          motion = false;
        } else {
          motion = false;
        }
        if (!motion) continue;
        const double bottom_a = tip.z() - O.z() - (probe ? r : 0), bottom_b = to.z() - O.z() - (probe ? r : 0);
        const Vector2d a = (tip - O).head<2>(), b = (to - O).head<2>();
        if (c_to != c) {
          ++c_turns;
          if (!note.cut) {
            EXPECT_TRUE(bottom_a >= top - 1e-9 || a.norm() >= R + r - 1e-9)
                << p.file << ": " << note.where << ": C turns with the tool at r = " << a.norm();
          }
        } else if (!note.cut && !note.retract && std::min(bottom_a, bottom_b) < top - 1e-9 &&
                   !((a - b).norm() < 1e-9 && to.z() >= tip.z())) {
          ++checked;
          const double d = segmentToOrigin(a, b);
          if (d < R + r - 1e-9) {
            // Only the probe comes nearer: into the notch at C 0 from above, or straight in
            // front of the facet it probes (its normal turned to +X), never below the floor.
            ASSERT_TRUE(probe) << p.file << ": " << note.where << ": " << d << " mm from the axis";
            EXPECT_GE(std::min(bottom_a, bottom_b), t.notchFloorZ() - 1e-9) << note.where;
            const Vector2d pa = atC(a, -c, cw), pb = atC(b, -c, cw);  // part frame
            if (std::fabs(c) < 1e-9 && std::max(std::fabs(pa.y()), std::fabs(pb.y())) <= t.x_notch_width_mm / 2 - r + 1e-9) {
              ++in_notch;
            } else {
              ++at_facet;
              EXPECT_NEAR(a.y(), b.y(), 1e-9) << note.where;  // in front of the facet, vertical moves only
              EXPECT_NEAR(a.x(), b.x(), 1e-9) << note.where;
              EXPECT_GE(a.x(), t.facet_apothem_mm + t.facet_allowance_mm + r - 1e-9) << note.where;
              EXPECT_LE(std::fabs(a.y()), 3.0 + 1e-9) << note.where;
            }
          }
        }
        tip = to;
        c = c_to;
      }
    }
    EXPECT_GT(checked, 500);
    EXPECT_GT(c_turns, 100);
    EXPECT_GT(in_notch, 100);  // flanks and Z paths
    EXPECT_EQ(at_facet, 36 * 6);  // 36 facets x 3 columns x (descent + next height)
  }
}

TEST(ThermalTestPiecePlan, TravelRefusalNamesTheProgramTheOperationAndTheAxis) {
  const auto t = piece();
  auto m = mill();
  m.x.max_mm = 100;
  try {
    planThermalTestPiece(t, m, parts::Dialect::LinuxCnc);
    FAIL() << "a 100 mm X travel cannot reach beside the 203 mm blank";
  } catch (const SafetyError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("pre_machining.ngc: bands: beside the blank on +X: rapid move needs X = 111.500"), std::string::npos) << w;
    EXPECT_NE(w.find("outside the X travel [-250.000, 100.000]"), std::string::npos) << w;
  }
  m = mill();
  m.x.min_mm = -125;  // everything of pre-machining fits; the test's waiting position at x -130 does not
  try {
    planThermalTestPiece(t, m, parts::Dialect::LinuxCnc);
    FAIL();
  } catch (const SafetyError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("thermal_test.ngc: test: above the waiting position: rapid move needs X = -130.000"), std::string::npos) << w;
  }
  m = mill();
  m.z.min_mm = 200;  // the probe at the datum circle: 67 - 16.5 + 150 = 200.5; the band at z -24: 163
  EXPECT_THROW(planThermalTestPiece(t, m, parts::Dialect::LinuxCnc), SafetyError);
  // No C axis: refused naming the machine file.
  const auto vmc = parts::loadMachine(src + "/parts/machines/vmc3.yaml");
  try {
    planThermalTestPiece(t, vmc, parts::Dialect::LinuxCnc);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vmc3.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("needs a rotary table"), std::string::npos) << e.what();
  }
}

TEST(ThermalTestPiecePlan, ATouchOutsideACutOrACTurnNearThePartIsRefused) {
  // A waiting position inside the blank: the descent to the cutting height would cut.
  auto t = piece();
  t.waiting_position_mm = Vector2d(-105, 0);
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const SafetyError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("thermal_test.nc: test: down to the cutting height beside the part (the one Z of the test): feed move"),
              std::string::npos)
        << w;
    EXPECT_NE(w.find("would take the tool T3 through the part"), std::string::npos) << w;
  }
  // A probe approach of 0.2 mm: the descent beside the datum band would come inside the
  // blank's circle (where C also turns between its points).
  t = piece();
  t.probing.approach_mm = 0.2;
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const SafetyError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("inspection.nc: inspection CYL point 1: protected move to the start: protected move from X103.700 Y0.000 "
                     "Z80.000 to X103.700 Y0.000 Z50.500 at C 0.000 would take the probe through the part"),
              std::string::npos)
        << w;
  }
  // Facet cuts that would start inside the blank are refused as a description error.
  t = piece();
  t.facet_path_half_length_mm = 20;
  EXPECT_THROW(planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB), InputError);
  // A ring that leaves a tool less than the margin outside the blank.
  t = piece();
  t.ring_radius_mm = 110;
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("test.ring_radius: 110 mm leaves tool T1"), std::string::npos) << e.what();
  }
}

TEST(ThermalTestPiecePlan, FeedsAboveTheMachinesMaximaAreRefused) {
  auto t = piece();
  t.test_feed_mm_per_min = 5000;  // above the mill's slowest axis (Z, 3000 mm/min)
  try {
    planThermalTestPiece(t, mill(), parts::Dialect::LinuxCnc);
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("thermal_test.ngc: test cycle 0, Z path Z5: cut at F5000.000 mm/min exceeds"), std::string::npos)
        << e.what();
  }
}

TEST(ThermalTestPiecePlan, ProbeContactsAreSurfacePointPlusTipRadiusAlongTheNormal) {
  const auto t = piece();
  for (bool clockwise : {true, false}) {
    auto m = nmv();
    m.c.positive_is_clockwise = clockwise;
    const auto plan = planThermalTestPiece(t, m, parts::Dialect::FanucMacroB);
    const auto& man = plan.manifest;
    const double rt = m.probe.tip_diameter_mm / 2;
    // The CMM plan carries the surface points and outward normals (part frame) in the same order.
    const CsvTable csv = parseCsv(plan.cmm_points_csv, "cmm_points.csv");
    ASSERT_EQ(csv.rows.size(), man.points.size());
    ASSERT_EQ(man.points.size(), 12u + 8 + 8 + 12 + 9 * 12 + 36 * 6);
    const auto& ins = program(plan, "inspection");
    std::vector<const gcode::ProbeMove*> moves;
    for (const auto& op : ins.program.ops)
      if (const auto* p = std::get_if<gcode::ProbeMove>(&op)) moves.push_back(p);
    ASSERT_EQ(moves.size(), man.points.size());
    std::map<std::string, int> last_point;
    for (std::size_t i = 0; i < man.points.size(); ++i) {
      const auto& p = man.points[i];
      const auto& row = csv.rows[i];
      EXPECT_EQ(row.fields[0], p.feature);
      EXPECT_EQ(std::stoi(row.fields[1]), p.point);
      const Vector3d s(csv.number(row, 2), csv.number(row, 3), csv.number(row, 4));
      const Vector3d n(csv.number(row, 5), csv.number(row, 6), csv.number(row, 7));
      EXPECT_NEAR(n.norm(), 1, 1e-6);
      const Vector2d sm = atC(s.head<2>(), p.c_deg, clockwise), nm = atC(n.head<2>(), p.c_deg, clockwise);
      const Vector3d want = man.part_origin_mm + Vector3d(sm.x(), sm.y(), s.z()) + rt * Vector3d(nm.x(), nm.y(), n.z());
      EXPECT_LT((p.contact_mm - want).norm(), 2e-6) << p.feature << " " << p.point;
      EXPECT_LT((p.approach + Vector3d(nm.x(), nm.y(), n.z())).norm(), 1e-6);
      // Facets and the datum circle are probed along -X only (L2099).
      const auto* f = man.feature(p.feature);
      ASSERT_TRUE(f);
      if (f->nominal.role == "facet" || f->nominal.role == "datum_circle") {
        EXPECT_NEAR(p.approach.x(), -1, 1e-12);
      }
      if (f->nominal.role == "z_path" || f->nominal.role == "datum_top") {
        EXPECT_NEAR(p.approach.z(), -1, 1e-12);
      }
      EXPECT_EQ(p.position, f->position);
      // The point lies on its nominal surface.
      const auto& nf = f->nominal;
      if (nf.kind == "plane") {
        EXPECT_NEAR((s - nf.point_mm).dot(nf.direction), 0, 1e-6) << p.feature;
      } else {
        EXPECT_NEAR((s - nf.point_mm).head<2>().norm(), nf.radius_mm, 1e-6) << p.feature;
      }
      // The measuring move ends overtravel past the contact on the approach line.
      const Vector3d end(moves[i]->x, moves[i]->y, moves[i]->z);
      EXPECT_LT((end - (p.contact_mm + t.probing.overtravel_mm * p.approach)).norm(), 1e-4);
      EXPECT_EQ(moves[i]->position, p.position);
      EXPECT_EQ(moves[i]->point, p.point);
      EXPECT_EQ(p.point, ++last_point[p.feature]);
    }
  }
}

TEST(ThermalTestPiecePlan, TheCLoadTurnsWithinTheTurningSpeedAndFillsTheWait) {
  const auto t = piece();
  for (const auto& m : {nmv(), mill()}) {
    const auto plan = planThermalTestPiece(t, m, m.dialect);
    const double turning = m.c.max_turning_speed_rpm;
    std::vector<double> turns;
    for (const auto& op : program(plan, "test").program.ops)
      if (const auto* f = std::get_if<gcode::TurnC>(&op)) {
        turns.push_back(f->delta_deg);
        EXPECT_LE(f->feed_deg_per_min / 360, turning + 1e-9);
      }
    ASSERT_EQ(turns.size(), 2u * 4);  // forward and back inside each warm-up's loop
    for (std::size_t i = 0; i < turns.size(); i += 2) {
      EXPECT_GT(turns[i], 0);
      EXPECT_EQ(turns[i + 1], -turns[i]);  // C back where it started after every pair
      EXPECT_NEAR(std::fmod(turns[i], 360.0), 0, 1e-9);
    }
    ASSERT_EQ(plan.loads.size(), 8u);
    for (const auto& l : plan.loads) {
      if (l.phase == "hold") {
        EXPECT_EQ(l.rpm, 0);
        EXPECT_EQ(l.dwell_s, t.wait_s);
        continue;
      }
      EXPECT_EQ(l.rpm, std::min(1200.0, turning));
      EXPECT_NEAR(l.pairs * 2 * l.move_s + l.dwell_s, t.wait_s, 1e-3);
      EXPECT_NEAR(l.move_s, t.c_turn_move_s, 0.5 * 60 / l.rpm);  // whole turns: within half a turn
    }
    if (m.c.max_turning_speed_rpm >= 1200) {
      EXPECT_EQ(plan.loads[0].turns_per_move, 200);  // 1200 rpm x 10 s
      EXPECT_EQ(plan.loads[0].pairs, 180);
    }
  }
  // Long moves are capped at 277 turns (a C word of at most 8 digits) and still fill the wait.
  auto t2 = t;
  t2.c_turn_move_s = 60;
  const auto plan = planThermalTestPiece(t2, nmv(), parts::Dialect::FanucMacroB);
  EXPECT_EQ(plan.loads[0].turns_per_move, 277);
  EXPECT_NEAR(plan.loads[0].pairs * 2 * plan.loads[0].move_s + plan.loads[0].dwell_s, t.wait_s, 1e-3);
  const std::string text = ttpProgramText(program(plan, "test"), parts::Dialect::FanucMacroB);
  EXPECT_NE(text.find("WHILE [#101 LE " + std::to_string(plan.loads[0].pairs) + "] DO1\nG91 G1 C99720.000 F432000.000\nG90\nG91 G1 C-99720.000 F432000.000\nG90\n"
                      "#101=#101+1\nEND1\n"),
            std::string::npos);
}

// Runs the emitted texts through our interpreter on a machine that keeps the simulator's clock
// (docs/simulator.md §2): the programs parse in both dialects, probe and log every point, and
// take the planned times.
namespace {
struct ClockMachine : gcode::MachineInterface {
  const parts::Machine& m;
  const parts::ThermalTestPiece& t;
  const parts::PlanManifest& man;
  gcode::MachinePosition pos;
  double time = 0;
  int tool = 0;
  std::size_t next_point = 0;
  std::vector<double> trigger_s, feed_end_s, feed_turn_deg;
  std::vector<Vector3d> feed_end_tip;
  std::vector<std::string> logs;
  ClockMachine(const parts::Machine& m_, const parts::ThermalTestPiece& t_, const parts::PlanManifest& man_)
      : m(m_), t(t_), man(man_) {
    pos.xyz_mm = Vector3d(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), m.z.max_mm);
  }
  gcode::MachinePosition start() const override { return pos; }
  // The clock: the planner's one copy of the simulator's (planner/program_walker.hpp).
  void rapid(const gcode::MachinePosition& to) override {
    time += rapidSeconds(m, to.xyz_mm - pos.xyz_mm, to.b_deg - pos.b_deg, to.c_deg - pos.c_deg);
    pos = to;
  }
  void feed(const gcode::MachinePosition& to, double F) override {
    const double len = (to.xyz_mm - pos.xyz_mm).norm();
    time += len > 0 ? linearFeedSeconds(len, F) : rotaryFeedSeconds(to.c_deg - pos.c_deg, F);
    feed_turn_deg.push_back(to.c_deg - pos.c_deg);
    pos = to;
    feed_end_s.push_back(time);
    feed_end_tip.push_back(to.xyz_mm - Vector3d(0, 0, toolLength(tool)));
  }
  gcode::ProbeOutcome probe(const gcode::MachinePosition& to, double F, gcode::ProbeMode) override {
    gcode::ProbeOutcome o;
    const double L = toolLength(tool);
    if (next_point < man.points.size()) {
      const auto& p = man.points[next_point];
      const Vector3d end = p.contact_mm + t.probing.overtravel_mm * p.approach + Vector3d(0, 0, L);
      if ((end - to.xyz_mm).norm() < 1e-3) {  // the measuring move: contact at the nominal point
        o.contact = true;
        o.stop = to;
        o.stop.xyz_mm = p.contact_mm + Vector3d(0, 0, L);
        time += linearFeedSeconds((o.stop.xyz_mm - pos.xyz_mm).norm(), F);
        trigger_s.push_back(time);
        ++next_point;
        pos = o.stop;
        return o;
      }
    }
    time += linearFeedSeconds((to.xyz_mm - pos.xyz_mm).norm(), F);  // a protected move: nothing touched
    o.stop = to;
    pos = to;
    return o;
  }
  void dwell(double s) override { time += s; }
  void toolChange(int tl) override {
    time += m.tool_change.time_s;
    tool = tl;
  }
  double toolLength(int tl) const override {
    if (tl == m.probe.tool) return m.probe.length_mm;
    if (tl == m.tool_change.empty_tool) return 0;
    if (const auto* c = t.tool(tl)) return c->length_mm;
    throw InputError("", 0, "no tool T" + std::to_string(tl));
  }
  void spindle(double) override {}
  void coolant(bool) override {}
  void openLog(const std::string&) override {}
  void log(const std::string& l) override {
    if (l != "%" && l.rfind("START ", 0) != 0) logs.push_back(l);  // Fanuc's START: the clock at the program's start
  }
  void closeLog() override {}
};
}  // namespace

TEST(ThermalTestPiecePlan, OurInterpreterRunsTheTextsInBothDialectsInThePlannedTimes) {
  const auto t = piece();
  for (const auto& m : {nmv(), mill()})
    for (auto d : {parts::Dialect::LinuxCnc, parts::Dialect::FanucMacroB}) {
      const auto plan = planThermalTestPiece(t, m, d);
      const auto& man = plan.manifest;
      ClockMachine cm(m, t, man);
      for (std::size_t i = 0; i < plan.programs.size(); ++i) {
        const auto& p = plan.programs[i];
        gcode::Interpreter in(d == parts::Dialect::LinuxCnc ? gcode::ProgramDialect::LinuxCnc : gcode::ProgramDialect::FanucMacroB,
                              p.file, ttpProgramText(p, d));
        const double t0 = cm.time;
        EXPECT_TRUE(in.run(cm).ended) << p.file;
        EXPECT_NEAR(t0, man.programs[i].start_s, 1e-6) << p.file;
        EXPECT_NEAR(cm.time - t0, man.programs[i].duration_s, 1e-6) << p.file;
      }
      ASSERT_EQ(cm.trigger_s.size(), man.points.size());
      ASSERT_EQ(cm.logs.size(), man.points.size());
      for (std::size_t k = 0; k < man.points.size(); ++k) {
        EXPECT_NEAR(cm.trigger_s[k] - man.cycle_start_s[0], man.points[k].time_in_cycle_s, 1e-6);
        std::istringstream f(cm.logs[k]);
        std::string pt;
        double cycle;
        int pos, point;
        f >> pt >> cycle >> pos >> point;
        EXPECT_EQ(pt, "PT");
        EXPECT_EQ(cycle, 1);
        EXPECT_EQ(pos, man.points[k].position);
        EXPECT_EQ(point, man.points[k].point);
      }
      // Every planned cut ends at a feed end of the run at its planned end time, in order (a
      // cut that starts where it ends is a turn of C).
      std::size_t j = 0;
      for (const auto& c : man.cuts) {
        const bool turn = (c.from_mm - c.to_mm).norm() < 1e-9;
        while (j < cm.feed_end_tip.size() &&
               ((cm.feed_end_tip[j] - c.to_mm).norm() > 1e-6 || turn != (std::fabs(cm.feed_turn_deg[j]) == 360)))
          ++j;
        ASSERT_LT(j, cm.feed_end_tip.size()) << c.id;
        EXPECT_NEAR(cm.feed_end_s[j], c.end_s, 1e-6) << c.id;
        ++j;
      }
    }
}

TEST(ThermalTestPiecePlan, DeterministicAndAllFacetsPreCutOnce) {
  const auto t = piece();
  const auto a = planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
  const auto b = planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
  for (std::size_t i = 0; i < a.programs.size(); ++i)
    EXPECT_EQ(ttpProgramText(a.programs[i], parts::Dialect::FanucMacroB), ttpProgramText(b.programs[i], parts::Dialect::FanucMacroB));
  EXPECT_EQ(parts::manifestToJson(a.manifest), parts::manifestToJson(b.manifest));
  EXPECT_EQ(a.cmm_points_csv, b.cmm_points_csv);
  std::map<std::string, int> pre;
  for (const auto& n : program(a, "pre_machining").notes)
    if (n.cut && n.where.rfind("facet ", 0) == 0) ++pre[n.where];
  EXPECT_EQ(pre.size(), 36u);
  for (const auto& [w, k] : pre) EXPECT_EQ(k, 1) << w;
  // The manifest reads back.
  const std::string path = testing::TempDir() + "/ttp_plan.json";
  {
    std::ofstream(path) << parts::manifestToJson(a.manifest);
  }
  const auto back = parts::readManifest(path);
  EXPECT_EQ(back.points.size(), a.manifest.points.size());
  EXPECT_EQ(back.cuts.size(), a.manifest.cuts.size());
  EXPECT_EQ(back.cut_cycles.size(), 9u);
  EXPECT_EQ(back.program("test")->duration_s, a.manifest.program("test")->duration_s);
  EXPECT_EQ(a.manifest.kind, "thermal_test_piece");
  EXPECT_EQ(a.manifest.ttp.cmm_plan, "cmm_points.csv");
  EXPECT_EQ(a.manifest.features.size(), 4u + 9 + 36);
}

// Review fixes (issue 13 follow-up): rollover, layouts that cannot be made, tool changes, the
// C travel of C feeds, the G0 and tool-change rules, the strips the facet cuts re-cut.

// A C axis with rollover (Fanuc ROA, LinuxCNC WRAPPED_ROTARY) and one without run the same
// programs to the same table angles: every C feed is an incremental move of the commanded
// amount, every absolute C word lies in [0, 360) (a rollover control may take it the short
// way), so the table stands alike at every cut and every probing move.
TEST(ThermalTestPiecePlan, TheTableTurnsAlikeWithAndWithoutCRollover) {
  const auto t = piece();
  for (const auto& m : {nmv(), mill()}) {
    const auto plan = planThermalTestPiece(t, m, m.dialect);
    auto wrap = [](double a) { return std::fmod(std::fmod(a, 360.0) + 360.0, 360.0); };
    double linear = 0, physical = 0, fed = 0;  // C without rollover; the table's angle with it
    int compared = 0, band_turns = 0;
    for (const auto& p : plan.programs)
      for (std::size_t i = 0; i < p.program.ops.size(); ++i) {
        const auto& op = p.program.ops[i];
        if (const auto* r = std::get_if<gcode::RotateC>(&op)) {
          EXPECT_GE(r->c_deg, 0);
          EXPECT_LT(r->c_deg, 360);
          linear = r->c_deg;
          double d = wrap(r->c_deg - wrap(physical));  // rollover: the shorter way to the word
          if (d > 180) d -= 360;
          physical += d;
        } else if (const auto* f = std::get_if<gcode::TurnC>(&op)) {
          linear += f->delta_deg;
          physical += f->delta_deg;
          fed += std::fabs(f->delta_deg);
          if (p.notes[i].cut) {
            ++band_turns;
            EXPECT_EQ(f->delta_deg, 360);
          }
        }
        if (p.notes[i].cut || std::holds_alternative<gcode::ProbeMove>(op)) {
          ++compared;
          const double d = std::fabs(wrap(linear) - wrap(physical));
          EXPECT_LT(std::min(d, 360 - d), 1e-9) << p.file << ": " << p.notes[i].where;
        }
      }
    EXPECT_EQ(band_turns, 4);
    EXPECT_GT(compared, 400);
    // The loads turn the table on a rollover axis too (loops written once: per pass).
    double planned = 4 * 360.0;  // the bands
    for (const auto& l : plan.loads) planned += l.rpm > 0 ? 2.0 * l.turns_per_move * 360.0 : 0.0;
    EXPECT_NEAR(fed, planned, 1e-6);
    // In the texts: every feed of C is G91 ... then G90 at once; no other line holds G91.
    for (const auto d : {parts::Dialect::LinuxCnc, parts::Dialect::FanucMacroB})
      for (const auto& p : plan.programs) {
        std::istringstream in(ttpProgramText(p, d));
        std::string line, prev;
        const std::regex c_word(R"(\bC-?\d)");
        while (std::getline(in, line)) {
          const std::string code = line.substr(0, line.find('('));
          if (code.rfind("G1 ", 0) == 0) {
            EXPECT_FALSE(std::regex_search(code, c_word)) << p.file << ": " << line;
          }
          if (code.find("G91") != std::string::npos) {
            EXPECT_EQ(code.rfind("G91 G1 C", 0), 0u) << line;
          }
          if (prev.rfind("G91", 0) == 0) {
            EXPECT_EQ(code, "G90") << p.file << " after " << prev;
          }
          prev = code;
        }
      }
  }
}

TEST(ThermalTestPiecePlan, ACFeedBeyondTheTravelOfANonContinuousCIsRefused) {
  const auto t = piece();
  auto m = nmv();
  m.c.continuous = false;
  m.c.min_deg = -360;
  m.c.max_deg = 360;  // the bands (0 -> 360) fit, the load's 200 turns do not
  try {
    planThermalTestPiece(t, m, parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("thermal_test.nc: load before test cycle 1: C turns forward: C feed move needs "
                                         "C = 72000.000 deg, outside the C travel [-360.000, 360.000]"),
              std::string::npos)
        << e.what();
  }
  m.c.max_deg = 359;  // not even one band turn
  try {
    planThermalTestPiece(t, m, parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("pre_machining.nc: band d202: one turn of C: C feed move needs C = 360.000 deg"),
              std::string::npos)
        << e.what();
  }
}

TEST(ThermalTestPiecePlan, LayoutsThatCannotBeMadeAreRefusedNamingTheKeyNeverWrittenAsNan) {
  // A 176 mm notch cuts the first facets of every segment away (and leaves no room for TOP
  // points: asin > 1); it used to write "Xnan".
  auto t = piece();
  t.x_notch_width_mm = 176;
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("thermal_test_piece.yaml: pre_machining.x_notch.width: 176 mm cuts facet X1_1 away: "
                                         "its centre (x 78.38, y 58.00 mm) lies in the notch (|y| < 88 mm)"),
              std::string::npos)
        << e.what();
  }
  t = piece();
  t.y_notch_width_mm = 20;  // X1_9's centre at x 9.35
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pre_machining.y_notch.width: 20 mm cuts facet X1_9 away"), std::string::npos) << e.what();
  }
  // A probe tip so large that no TOP point keeps a tip diameter from the notch and the facets.
  auto m = nmv();
  m.probe.tip_diameter_mm = 40;
  try {
    planThermalTestPiece(piece(), m, parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pre_machining.x_notch.width: 110 mm: no room on the top for the inspection's TOP points"),
              std::string::npos)
        << e.what();
  }
  // Nothing non-finite gets into a program: NotedProgram::add refuses it.
  NotedProgram p;
  p.file = "x.nc";
  OpNote n;
  n.where = "somewhere";
  EXPECT_THROW(p.add(gcode::Rapid{NAN, 0, std::nullopt}, n), GeometryError);
  EXPECT_THROW(p.add(gcode::TurnC{360, INFINITY}, n), GeometryError);
  EXPECT_TRUE(p.program.ops.empty());
}

// The test's facet cuts run with the tool's bottom 0.1 mm below the notch floor: where a facet's
// chord passes over the notch they re-cut the floor. Z-path points there are refused.
TEST(ThermalTestPiecePlan, ZPathPointsOnTheStripsTheFacetCutsReCutAreRefused) {
  auto t = piece();
  t.z_path_points_along_mm = {-85, -50, -20, 20, 50, 85};
  try {
    planThermalTestPiece(t, nmv(), parts::Dialect::FanucMacroB);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("inspection.z_path_points.along: the point x 85 y 51 mm of Z path Z9 lies in the strip of "
                                         "notch floor the test's cuts of facet X1_1 re-cut at the cutting height"),
              std::string::npos)
        << e.what();
  }
  // The shipped points: x +-80 at y +-51 stay 2.86 mm off the strips of X1_1, Y1_1, X2_1, Y2_1.
  const auto plan = planThermalTestPiece(piece(), nmv(), parts::Dialect::FanucMacroB);
  const double r = t.tool(t.test_tool)->diameter_mm / 2, a = t.facet_apothem_mm;
  double closest = INFINITY;
  for (const auto& p : plan.manifest.points) {
    if (plan.manifest.feature(p.feature)->nominal.role != "z_path") continue;
    const Vector2d q = (p.contact_mm - plan.manifest.part_origin_mm).head<2>();  // C 0: part frame
    for (const auto& f : plan.manifest.features) {
      if (f.nominal.role != "facet") continue;
      const Vector2d n = f.nominal.direction.head<2>(), u(-n.y(), n.x());
      const double along = std::clamp(q.dot(u), -t.facet_path_half_length_mm, t.facet_path_half_length_mm);
      closest = std::min(closest, (q - ((a + r) * n + along * u)).norm() - r);
    }
  }
  EXPECT_NEAR(closest, 2.855, 1e-3);
}

// A face tool other than the band tool (and a facet tool other than the X notch's): the spindle
// stops before each change, and the header lists every tool.
TEST(ThermalTestPiecePlan, EveryToolChangeComesWithTheSpindleStoppedAndEveryToolIsListed) {
  auto t = piece();
  t.face_tool = 3;
  t.face_stepover_mm = 10;
  t.facet_pre_tool = 2;
  for (const auto& m : {nmv(), mill()}) {
    const auto plan = planThermalTestPiece(t, m, m.dialect);
    const auto& pre = program(plan, "pre_machining");
    for (int n : {1, 2, 3, 4}) {
      bool listed = false;
      for (const auto& h : pre.program.header) listed = listed || h.rfind("T" + std::to_string(n) + ": ", 0) == 0;
      EXPECT_TRUE(listed) << "T" << n;
    }
    for (auto d : {parts::Dialect::LinuxCnc, parts::Dialect::FanucMacroB}) {
      std::istringstream in(ttpProgramText(pre, d));
      std::string line;
      bool turning = false;
      int changes = 0;
      while (std::getline(in, line)) {
        if (line.find(" M3") != std::string::npos) turning = true;
        if (line == "M5") turning = false;
        if (line.find(" M6") != std::string::npos) {
          ++changes;
          EXPECT_FALSE(turning) << line;
        }
      }
      EXPECT_EQ(changes, 7);  // T1 bands, T3 face, T4 mark, T2 Y notch, T1 X notch, T2 facets, T0
    }
    // The face passes are T3's cuts.
    for (const auto& c : plan.manifest.cuts) {
      if (c.feature == "TOP") {
        EXPECT_EQ(c.tool, 3);
      }
    }
  }
}

// The rules docs §5 lists as checked, on edited programs (checkThermalTestPiecePrograms walks
// them with every check the planner makes).
TEST(ThermalTestPiecePlan, AG0OfSeveralAxesBelowTheTopAndAToolChangeAwayFromItsHeightAreRefused) {
  const auto t = piece();
  const auto m = mill();
  const auto plan = planThermalTestPiece(t, m, parts::Dialect::LinuxCnc);
  EXPECT_NO_THROW(checkThermalTestPiecePrograms(t, m, plan.programs));
  auto edited = [&](const std::string& role, const std::string& where_starts, gcode::Op op, bool before = false) {
    auto programs = plan.programs;
    for (auto& p : programs) {
      if (p.role != role) continue;
      for (std::size_t i = 0; i < p.notes.size(); ++i)
        if (p.notes[i].where.rfind(where_starts, 0) == 0) {
          const std::size_t at = before ? i : i + 1;
          p.program.ops.insert(p.program.ops.begin() + static_cast<long>(at), op);
          OpNote n;
          n.where = "edited";
          p.notes.insert(p.notes.begin() + static_cast<long>(at), n);
          break;
        }
    }
    return programs;
  };
  // At the cutting height beside the part, a G0 in X and Y together (a Fanuc may dog-leg).
  const double x = plan.manifest.part_origin_mm.x() - 135, y = plan.manifest.part_origin_mm.y() + 5;
  try {
    checkThermalTestPiecePrograms(t, m, edited("test", "test: down to the cutting height", gcode::Rapid{x, y, std::nullopt}));
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("thermal_test.ngc: edited: G0 from X-130.000 Y0.000 Z54.900 to X-135.000 Y5.000 Z54.900 "
                                         "moves 2 axes with the tool T3 below the top of the part"),
              std::string::npos)
        << e.what();
  }
  // One axis is straight on every control.
  EXPECT_NO_THROW(checkThermalTestPiecePrograms(t, m, edited("test", "test: down to the cutting height",
                                                             gcode::Rapid{x, std::nullopt, std::nullopt})));
  // A tool change below the tool-change height.
  try {
    checkThermalTestPiecePrograms(t, m, edited("inspection", "inspection: probe in", gcode::Rapid{std::nullopt, std::nullopt, 300.0}, true));
    FAIL();
  } catch (const SafetyError& e) {
    EXPECT_NE(std::string(e.what()).find("inspection.ngc: inspection: probe in: tool change T99 with the gauge line at Z 300.000 mm, "
                                         "not at the tool-change height"),
              std::string::npos)
        << e.what();
  }
  // A number that is not finite, put into the ops behind add()'s back, is refused by the walk.
  auto programs = plan.programs;
  programs[1].program.ops.insert(programs[1].program.ops.begin() + 5, gcode::Rapid{NAN, 0.0, std::nullopt});
  programs[1].notes.insert(programs[1].notes.begin() + 5, OpNote{});
  EXPECT_THROW(checkThermalTestPiecePrograms(t, m, programs), SafetyError);
}
