// The stepped workpiece's programs (seed 000 Table 4.1, Sec. 4.1; docs/stepped-workpiece.md §4):
// the cuts per step at their depth and feed, the transitions per experiment, the warm-up and
// the procedure's waits on the planned clock, the probing program and the refusals.
#include "planner/stepped_workpiece.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "core/error.hpp"
#include "parts/test_support.hpp"

using namespace probeloop;
using namespace probeloop::planner;
using Eigen::Vector3d;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;
const std::string shipped = src + "/parts/stepped_workpiece.yaml";
parts::SteppedWorkpiece piece(const std::string& file = shipped) { return parts::loadSteppedWorkpiece(file); }
parts::Machine vmc() { return parts::loadMachine(src + "/parts/machines/vmc3.yaml"); }

const NotedProgram& program(const SteppedWorkpiecePlan& p, const std::string& role) {
  for (const auto& x : p.programs)
    if (x.role == role) return x;
  throw std::runtime_error("no program " + role);
}

std::string refusal(const parts::SteppedWorkpiece& w, const std::string& experiment, const parts::Machine& m) {
  try {
    planSteppedWorkpiece(w, experiment, m, parts::Dialect::LinuxCnc);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(planned)";
}

// W8 (Table 4.1): step k's walls at its floor depth, at its feed; the cuts in step order.
TEST(PlanSteppedWorkpiece, W8CutsEveryWallAtItsDepthAndFeed) {
  const auto w = piece();
  const auto m = vmc();
  const auto plan = planSteppedWorkpiece(w, "W8", m, parts::Dialect::LinuxCnc);
  ASSERT_EQ(plan.programs.size(), 3u);
  EXPECT_EQ(plan.programs[0].role, "roughing");
  EXPECT_EQ(plan.programs[1].role, "finishing");
  EXPECT_EQ(plan.programs[2].role, "probing");
  const Vector3d O = parts::steppedWorkpieceOrigin(w, m);
  // The steps' centre over the middle of the X/Y travel, the blank on its 25 mm fixture.
  EXPECT_NEAR(O.x() + 15, 0, 1e-12);
  EXPECT_NEAR(O.y() + 15, 0, 1e-12);
  EXPECT_NEAR(O.z(), 25 + 50 - 0.5, 1e-12);
  std::map<std::string, int> walls;
  double last_end = -1;
  for (const auto& c : plan.manifest.cuts) {
    EXPECT_EQ(c.program, "finishing");
    EXPECT_GE(c.start_s, last_end - 1e-9) << c.id;  // in time order
    last_end = c.end_s;
    if (c.feature == "TOP") {
      EXPECT_NEAR(c.to_mm.z(), O.z(), 1e-9);
      continue;
    }
    const int k = c.cycle;
    ASSERT_GE(k, 1);
    ASSERT_LE(k, 4);
    EXPECT_NEAR(c.to_mm.z(), O.z() - w.steps[k - 1].floor_depth_mm, 1e-9) << c.id;
    if (c.feature.back() == 'F') {
      // A floor contour: the closed square of half size s round the centre, 8 s long, timed
      // from the tool leaving its corner to its return (not from its last side).
      const double half = std::fabs(c.from_mm.x() - (O.x() + 15));
      EXPECT_LT((c.to_mm - c.from_mm).norm(), 1e-9) << c.id;
      EXPECT_NEAR(c.end_s - c.start_s, 8 * half / w.experiment("W8")->steps[k - 1].feed_xy_mm_per_min * 60, 1e-6) << c.id;
    } else {
      ++walls[c.feature];
      // A wall is cut straight along it at the tool's radius from its face.
      const auto* f = plan.manifest.feature(c.feature);
      ASSERT_NE(f, nullptr);
      const Vector3d n = f->nominal.direction;
      const double face = (f->nominal.point_mm + O).dot(n);
      EXPECT_NEAR(c.from_mm.dot(n) - face, 5, 1e-4) << c.id;
      EXPECT_NEAR(c.to_mm.dot(n) - face, 5, 1e-4) << c.id;
      // Non-cutting transitions: past both roughed ends by the lead, 2 (h + 0.5 + r + 2) long.
      const double h = plan.sizes_mm[k - 1] / 2;
      EXPECT_NEAR((c.to_mm - c.from_mm).norm(), 2 * (h + 0.5 + 5 + 2), 1e-4) << c.id;
      // At the step's feed: 100/200/400/800 mm/min (Table 4.1).
      const double F = w.experiment("W8")->steps[k - 1].feed_xy_mm_per_min;
      EXPECT_NEAR(c.end_s - c.start_s, (c.to_mm - c.from_mm).norm() / F * 60, 1e-6) << c.id;
    }
  }
  EXPECT_EQ(walls.size(), 16u);
  for (const auto& [id, n] : walls) EXPECT_EQ(n, 1) << id;
  // Every feature is finished by a cut and carries its mid time.
  for (const auto& f : plan.manifest.features) EXPECT_TRUE(std::isfinite(f.cut_time_s)) << f.nominal.id;
}

// Sec. 4.1: the machine is off 3 h before finishing and before probing; a 30 min idle warm-up
// (at the next step's speed) and the axis manoeuvre stand between the steps; T grows by more
// than the warm-up from step to step and step 1 is cut at the start (T of a few minutes).
TEST(PlanSteppedWorkpiece, TheProcedureIsOnThePlannedClock) {
  const auto w = piece();
  const auto plan = planSteppedWorkpiece(w, "W8", vmc(), parts::Dialect::LinuxCnc);
  ASSERT_EQ(plan.start_s.size(), 3u);
  EXPECT_NEAR(plan.start_s[1] - (plan.start_s[0] + plan.duration_s[0]), 3 * 3600, 1e-6);
  EXPECT_NEAR(plan.start_s[2] - (plan.start_s[1] + plan.duration_s[1]), 3 * 3600, 1e-6);
  int dwells = 0;
  std::vector<double> speeds;
  for (const auto& op : program(plan, "finishing").program.ops) {
    if (const auto* d = std::get_if<gcode::Dwell>(&op)) {
      ++dwells;
      EXPECT_DOUBLE_EQ(d->seconds, 1800);
    }
    if (const auto* s = std::get_if<gcode::Spindle>(&op)) speeds.push_back(s->rpm);
  }
  EXPECT_EQ(dwells, 3);
  EXPECT_EQ(plan.times[1].dwell_s, 3 * 1800);
  ASSERT_EQ(plan.steps.size(), 4u);
  EXPECT_GT(plan.steps[0].temp_state_min, 0);
  EXPECT_LT(plan.steps[0].temp_state_min, 15);
  for (std::size_t k = 1; k < 4; ++k) {
    EXPECT_GT(plan.steps[k].temp_state_min - plan.steps[k - 1].temp_state_min, 30) << k;
    EXPECT_GT(plan.steps[k].start_s, plan.steps[k - 1].end_s + 1800) << k;
  }
  // The manifest carries the same steps.
  ASSERT_EQ(plan.manifest.sw.steps.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_EQ(plan.manifest.sw.steps[k].temp_state_min, plan.steps[k].temp_state_min);
  EXPECT_EQ(plan.manifest.sw.experiment, "W8");
}

// W3 changes the speed step by step (Table 4.1): the warm-up before a step runs at its speed.
TEST(PlanSteppedWorkpiece, TheWarmUpRunsAtTheNextStepsSpeed) {
  const auto plan = planSteppedWorkpiece(piece(), "W3", vmc(), parts::Dialect::LinuxCnc);
  std::vector<double> speeds;
  for (const auto& op : program(plan, "finishing").program.ops)
    if (const auto* s = std::get_if<gcode::Spindle>(&op)) speeds.push_back(s->rpm);
  // Step 1 at 3500, the warm-ups (and steps) at 5500, 1000, 3500, then off.
  EXPECT_EQ(speeds, (std::vector<double>{3500, 5500, 1000, 3500, 0}));
}

// W2 (fast transitions at its transition feed, alternative sizes 29/44/79/99) against W5 (one
// continuous contour per step at the cutting feed): the wall cuts differ as Table 3.1 says.
TEST(PlanSteppedWorkpiece, TransitionsFollowTheExperiment) {
  const auto w = piece();
  const auto w2 = planSteppedWorkpiece(w, "W2", vmc(), parts::Dialect::LinuxCnc);
  const auto w5 = planSteppedWorkpiece(w, "W5", vmc(), parts::Dialect::LinuxCnc);
  EXPECT_EQ(w2.sizes_mm, (std::vector<double>{29, 44, 79, 99}));
  auto feeds = [](const SteppedWorkpiecePlan& p) {
    std::set<double> f;
    for (const auto& op : program(p, "finishing").program.ops)
      if (const auto* x = std::get_if<gcode::Feed>(&op)) f.insert(x->feed);
    return f;
  };
  EXPECT_TRUE(feeds(w2).count(w.experiment("W2")->transition_feed_mm_per_min));
  // W5: no feed but the steps' own (100/200/400/800) and their Z feeds.
  for (double f : feeds(w5)) EXPECT_TRUE(f == 100 || f == 200 || f == 400 || f == 800) << f;
  // W5's walls: the closed contour at the tool's radius, corner to corner (2 (h + r) long).
  for (const auto& c : w5.manifest.cuts) {
    if (c.feature.size() != 5 || c.feature.back() == 'F') continue;
    const double h = w5.sizes_mm[c.cycle - 1] / 2;
    EXPECT_NEAR((c.to_mm - c.from_mm).norm(), 2 * (h + 5), 1e-4) << c.id;
  }
}

// Sec. 3.4 and L769: the 141 contacts of the layout, then step 3's 24 wall points again; the
// CMM plan holds each contact once; every measuring move ends overtravel past its contact.
TEST(PlanSteppedWorkpiece, TheProbingProgramProbesTheLayoutAndRepeatsStep3) {
  const auto w = piece();
  const auto plan = planSteppedWorkpiece(w, "W8", vmc(), parts::Dialect::LinuxCnc);
  EXPECT_EQ(plan.manifest.points.size(), 141u + 24u);
  int rows = 0;
  for (char c : plan.cmm_points_csv) rows += c == '\n';
  EXPECT_EQ(rows, 3 + 141);  // two comment lines and the header
  std::map<std::pair<std::string, int>, Vector3d> first;
  int repeats = 0;
  for (const auto& p : plan.manifest.points) {
    EXPECT_NEAR(p.approach.norm(), 1, 1e-12);
    if (p.point > 6 && p.feature.rfind("S3_", 0) == 0 && p.feature != "S3_F") {
      ++repeats;
      EXPECT_LT((p.contact_mm - first.at({p.feature, p.point - 6})).norm(), 1e-12) << p.feature << p.point;
    } else {
      first[{p.feature, p.point}] = p.contact_mm;
    }
  }
  EXPECT_EQ(repeats, 24);
  EXPECT_DOUBLE_EQ(plan.manifest.tip_radius_mm, 1.0);  // the piece's d2 stylus
  EXPECT_DOUBLE_EQ(plan.manifest.probe_repeatability_2sigma_um, 2.0);
  std::size_t measuring = 0;
  for (std::size_t i = 0; i < program(plan, "probing").program.ops.size(); ++i) {
    const auto& op = program(plan, "probing").program.ops[i];
    if (const auto* p = std::get_if<gcode::ProbeMove>(&op)) {
      const auto& mp = plan.manifest.points[measuring++];
      const Vector3d end(p->x, p->y, p->z);
      EXPECT_LT((end - (mp.contact_mm + 2.0 * mp.approach)).norm(), 1e-4);
    }
  }
  EXPECT_EQ(measuring, plan.manifest.points.size());
}

TEST(PlanSteppedWorkpiece, IsDeterministic) {
  const auto a = planSteppedWorkpiece(piece(), "W5", vmc(), parts::Dialect::FanucMacroB);
  const auto b = planSteppedWorkpiece(piece(), "W5", vmc(), parts::Dialect::FanucMacroB);
  for (std::size_t i = 0; i < a.programs.size(); ++i)
    EXPECT_EQ(swProgramText(a.programs[i], parts::Dialect::FanucMacroB), swProgramText(b.programs[i], parts::Dialect::FanucMacroB));
  EXPECT_EQ(parts::manifestToJson(a.manifest), parts::manifestToJson(b.manifest));
}

// The bad inputs: refused before any program exists, naming the key and the value.
TEST(PlanSteppedWorkpiece, RefusesWhatTheMachineCannotDo) {
  using parts::test::variantOf;
  const auto m = vmc();
  EXPECT_NE(refusal(piece(), "W9", m).find("experiments: no experiment 'W9' (the description has W1, W2"), std::string::npos);
  // vmc3: X/Y max_feed 10000 mm/min.
  const auto fast = piece(variantOf(shipped, "{feed_xy: 800, feed_z: 800, spindle_speed: 3500}\n\nprobing",
                                    "{feed_xy: 20000, feed_z: 800, spindle_speed: 3500}\n\nprobing"));
  EXPECT_NE(refusal(fast, "W8", m).find("experiments[W8].steps[4].feed_xy: 20000 mm/min exceeds the machine's X/Y max_feed of 10000"),
            std::string::npos)
      << refusal(fast, "W8", m);
  // Z travel 150..550 (gauge line); the top of the blank at 75 + 10 clearance: a 480 mm tool
  // puts the gauge line at 565.
  const auto tall = piece(variantOf(shipped, "length: 140 mm", "length: 480 mm"));
  EXPECT_NE(refusal(tall, "W8", m).find("tools[T1].length: 480 mm: the finishing tool at the clearance plane (tip Z 85) puts the gauge "
                                        "line at Z 565, above the Z travel (max 550 mm"),
            std::string::npos)
      << refusal(tall, "W8", m);
  // ... and a 100 mm tool cannot reach the deepest floor (tip Z 37.5) from Z 150.
  const auto shortTool = piece(variantOf(shipped, "length: 140 mm", "length: 100 mm"));
  EXPECT_NE(refusal(shortTool, "W8", m).find("cannot reach down to tip Z 37.5"), std::string::npos) << refusal(shortTool, "W8", m);
  // A tool change at Z 200 would hang the 140 mm tool's tip at Z 60, inside the blank (its top
  // at 75, the clearance plane at 85): refused, naming the machine's key.
  const auto low = parts::loadMachine(variantOf(src + "/parts/machines/vmc3.yaml", "  z: 550 mm", "  z: 200 mm"));
  EXPECT_NE(refusal(piece(), "W8", low).find("tool_change.z: 200 mm puts the tip of tool T1 (140 mm) at Z 60, below the clearance plane"),
            std::string::npos)
      << refusal(piece(), "W8", low);
}

}  // namespace
