// The stepped workpiece's description and geometry (seed 000, issue 14 first part). Reference
// numbers come from the notes' extraction of the thesis (notes/seed000.md §1.2: sizes, floor
// depths and the wall coordinates of Table 5.1; §2.2: Table 4.1), typed here independently
// of the shipped YAML.
#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <unistd.h>

#include "core/error.hpp"
#include "parts/piece_kinds.hpp"
#include "parts/test_support.hpp"

namespace probeloop::parts {
namespace {

using Eigen::Vector3d;

std::string shipped() { return std::string(PROBELOOP_SOURCE_DIR) + "/parts/stepped_workpiece.yaml"; }

std::string variant(const std::string& from, const std::string& to) { return test::variantOf(shipped(), from, to); }

std::string refusal(const std::string& file) {
  try {
    loadSteppedWorkpiece(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

void expectRefused(const std::string& file, const std::string& want) {
  const std::string got = refusal(file);
  EXPECT_NE(got.find(want), std::string::npos) << "expected '" << want << "' in: " << got;
}

const NominalFeature& byId(const std::vector<NominalFeature>& f, const std::string& id) {
  for (const auto& x : f)
    if (x.id == id) return x;
  throw std::logic_error("no feature " + id);
}

TEST(SteppedWorkpiece, ShippedDescriptionHasTheDerivedGeometry) {
  const auto w = loadSteppedWorkpiece(shipped());
  // notes §1.2: 30/45/80/99 square, floors at depths 9/19/29/37; W2/W5 at 29/44/79/99.
  const std::array<double, 4> size{30, 45, 80, 99}, depth{9, 19, 29, 37}, alt{29, 44, 79, 99};
  ASSERT_EQ(w.steps.size(), 4u);
  for (int k = 0; k < 4; ++k) {
    EXPECT_DOUBLE_EQ(w.steps[k].size_mm, size[k]);
    EXPECT_DOUBLE_EQ(w.steps[k].floor_depth_mm, depth[k]);
    EXPECT_DOUBLE_EQ(w.alternative_sizes_mm[k], alt[k]);
  }
  EXPECT_DOUBLE_EQ(w.finishing_margin_mm, 0.5);    // L695
  EXPECT_DOUBLE_EQ(w.alignment_tolerance_mm, 0.005);  // L968
  EXPECT_DOUBLE_EQ(w.warm_up_idle_s, 1800);        // 30 min (L992)
  EXPECT_DOUBLE_EQ(w.off_before_s, 3 * 3600);      // 3 h off (L990)
  EXPECT_DOUBLE_EQ(w.off_after_s, 3 * 3600);       // before probing (L1040)
  EXPECT_TRUE(w.warm_up_axis_manoeuvre);
}

// Table 4.1 (notes §2.2): feed XY / feed Z (mm/min) and spindle speed (rpm) per step, and the
// runout; Table 3.1 for the transitions.
TEST(SteppedWorkpiece, ExperimentsAreTable41) {
  const auto w = loadSteppedWorkpiece(shipped());
  struct Row {
    const char* id;
    std::array<std::array<double, 3>, 4> steps;
    double runout_mm;
    const char* transition;
    double transition_feed;
  };
  const std::vector<Row> table{
      {"W1", {{{100, 100, 3500}, {100, 100, 3500}, {100, 100, 3500}, {100, 100, 3500}}}, 0.004, "non_cutting", 100},
      {"W2", {{{200, 200, 3500}, {400, 400, 3500}, {800, 600, 3500}, {1600, 800, 3500}}}, 0.004, "fast", 1200},
      {"W3", {{{200, 200, 3500}, {100, 100, 5500}, {100, 100, 1000}, {800, 800, 3500}}}, 0.004, "non_cutting", 100},
      {"W4", {{{100, 100, 3500}, {100, 100, 3500}, {100, 100, 3500}, {100, 100, 3500}}}, 0.004, "non_cutting", 100},
      {"W5", {{{100, 100, 3500}, {200, 200, 3500}, {400, 400, 3500}, {800, 800, 3500}}}, 0.004, "continuous", 0},
      {"W6", {{{100, 100, 1000}, {100, 100, 1000}, {100, 100, 1000}, {100, 100, 1000}}}, 0.004, "non_cutting", 100},
      {"W7", {{{100, 100, 5500}, {100, 100, 5500}, {100, 100, 5500}, {100, 100, 5500}}}, 0.004, "non_cutting", 100},
      {"W8", {{{100, 100, 3500}, {200, 200, 3500}, {400, 400, 3500}, {800, 800, 3500}}}, 0.005, "non_cutting", 100},
  };
  ASSERT_EQ(w.experiments.size(), table.size());
  for (const auto& r : table) {
    const auto* e = w.experiment(r.id);
    ASSERT_NE(e, nullptr) << r.id;
    EXPECT_EQ(e->transition, r.transition) << r.id;
    EXPECT_DOUBLE_EQ(e->transition_feed_mm_per_min, r.transition_feed) << r.id;
    EXPECT_DOUBLE_EQ(e->tool_runout_mm, r.runout_mm) << r.id;
    ASSERT_EQ(e->steps.size(), 4u) << r.id;
    for (int k = 0; k < 4; ++k) {
      EXPECT_DOUBLE_EQ(e->steps[k].feed_xy_mm_per_min, r.steps[k][0]) << r.id << " step " << k + 1;
      EXPECT_DOUBLE_EQ(e->steps[k].feed_z_mm_per_min, r.steps[k][1]) << r.id << " step " << k + 1;
      EXPECT_DOUBLE_EQ(e->steps[k].spindle_speed_rpm, r.steps[k][2]) << r.id << " step " << k + 1;
    }
    // W2 and W5 were cut to the alternative sizes (Tables 5.6/5.7), the others to 30/45/80/99.
    const bool alt = std::string(r.id) == "W2" || std::string(r.id) == "W5";
    EXPECT_EQ(e->alternative_sizes, alt) << r.id;
    EXPECT_DOUBLE_EQ(w.sizesFor(*e).front(), alt ? 29.0 : 30.0) << r.id;
  }
}

// notes §1.2, from Table 5.1's edge coordinates: step 1 spans 0..30, step 2 -7.5..37.5, step 3
// -25..55, step 4 -34.5..64.5 in X and in Y; the walls of step k run from the floor of step
// k-1 (the top for k = 1) down to its own floor. Twenty faces (L687) plus the top.
TEST(SteppedWorkpiece, FeaturesSitWhereTable51PutsTheWalls) {
  const auto w = loadSteppedWorkpiece(shipped());
  const auto f = nominalFeatures(w);
  EXPECT_EQ(f.size(), 21u);
  const std::array<double, 4> lo{0, -7.5, -25, -34.5}, hi{30, 37.5, 55, 64.5};
  const std::array<double, 5> z{0, -9, -19, -29, -37};
  for (int k = 0; k < 4; ++k) {
    const std::string s = "S" + std::to_string(k + 1);
    EXPECT_DOUBLE_EQ(byId(f, s + "_XP").point_mm.x(), hi[k]);
    EXPECT_DOUBLE_EQ(byId(f, s + "_XN").point_mm.x(), lo[k]);
    EXPECT_DOUBLE_EQ(byId(f, s + "_YP").point_mm.y(), hi[k]);
    EXPECT_DOUBLE_EQ(byId(f, s + "_YN").point_mm.y(), lo[k]);
    for (const char* side : {"_XP", "_XN", "_YP", "_YN"}) {
      const auto& wall = byId(f, s + side);
      EXPECT_EQ(wall.role, "wall");
      EXPECT_EQ(wall.group, s);
      // Outward: a millimetre along the normal leaves the step's square; the wall spans the
      // step's height, and its v = n x u points up (the Z levels of the probe points).
      const Vector3d out = wall.point_mm + wall.direction;
      EXPECT_TRUE(out.x() < lo[k] || out.x() > hi[k] || out.y() < lo[k] || out.y() > hi[k]) << s << side;
      EXPECT_DOUBLE_EQ(wall.point_mm.z() + wall.half_v_mm, z[k]) << s << side;
      EXPECT_DOUBLE_EQ(wall.point_mm.z() - wall.half_v_mm, z[k + 1]) << s << side;
      EXPECT_LT((wall.v() - Vector3d::UnitZ()).norm(), 1e-15) << s << side;
      EXPECT_DOUBLE_EQ(wall.half_u_mm, (hi[k] - lo[k]) / 2);
    }
    const auto& floor = byId(f, s + "_F");
    EXPECT_EQ(floor.role, "floor");
    EXPECT_DOUBLE_EQ(floor.point_mm.z(), z[k + 1]);
    // The ring from this step out to the next one (the blank's edge, 75 mm from the centre,
    // for the last): its mid-line square and half its width.
    const double inner = (hi[k] - lo[k]) / 2, outer = k < 3 ? (hi[k + 1] - lo[k + 1]) / 2 : 75;
    EXPECT_DOUBLE_EQ(floor.half_u_mm, (inner + outer) / 2) << s;
    EXPECT_DOUBLE_EQ(floor.radius_mm, (outer - inner) / 2) << s;
  }
  const auto& top = byId(f, "TOP");
  EXPECT_EQ(top.role, "datum_top");
  EXPECT_EQ(top.point_mm, Vector3d(15, 15, 0));
  // The alternative set keeps the centre: step 1 of W2/W5 spans 0.5..29.5.
  const auto a = nominalFeatures(w, w.alternative_sizes_mm);
  EXPECT_DOUBLE_EQ(byId(a, "S1_XN").point_mm.x(), 0.5);
  EXPECT_DOUBLE_EQ(byId(a, "S1_XP").point_mm.x(), 29.5);
  EXPECT_DOUBLE_EQ(byId(a, "S4_YP").point_mm.y(), 64.5);
}

TEST(SteppedWorkpiece, TheStockIsTheBlankOnItsFixture) {
  const auto piece = loadTestPiece(shipped());
  EXPECT_EQ(piece.kind, "stepped_workpiece");
  ASSERT_NE(piece.steppedWorkpiece(), nullptr);
  EXPECT_EQ(piece.features.size(), 21u);
  ASSERT_TRUE(piece.stock);
  const auto& s = *piece.stock;
  // 150 x 150 x 50 mm centred on the steps' centre (15, 15), its top the finishing margin
  // (0.5 mm) above the part's top face.
  EXPECT_EQ(s.stock_min_mm, Vector3d(-60, -60, -49.5));
  EXPECT_EQ(s.stock_max_mm, Vector3d(90, 90, 0.5));
  ASSERT_EQ(s.holes.size(), 4u);
  for (const auto& h : s.holes) {
    // 10 mm in from the corners, clear of the largest step's tool path (49.5 + 10 mm).
    EXPECT_DOUBLE_EQ(std::abs(h.centre_mm.x() - 15), 65);
    EXPECT_DOUBLE_EQ(std::abs(h.centre_mm.y() - 15), 65);
    EXPECT_DOUBLE_EQ(h.radius_mm, 4.5);
  }
  ASSERT_EQ(s.obstacles.size(), 1u);
  EXPECT_EQ(s.obstacles[0].name, "fixture");
  EXPECT_DOUBLE_EQ(s.obstacles[0].z_max_mm, -49.5);
  EXPECT_THROW(expansionLevers(piece), InputError);  // no evaluation yet
}

// Sec. 3.4 / notes §3: per wall 3 positions x 2 Z levels, 9 per floor, 9 on the top (L1124);
// the positions within a face are the description's (0.6 of the half length, 0.2 and 0.8 of
// the height): 9 + 16 x 6 + 4 x 9 = 141 contacts, each on its face.
TEST(SteppedWorkpiece, ProbePointsFollowSection34) {
  const auto w = loadSteppedWorkpiece(shipped());
  for (const auto& sizes : {std::vector<double>{}, w.alternative_sizes_mm}) {
    const auto f = nominalFeatures(w, sizes);
    const auto pts = probePoints(w, f);
    EXPECT_EQ(pts.size(), 141u);
    std::map<std::string, int> per;
    for (const auto& p : pts) {
      ++per[p.feature];
      const auto& x = byId(f, p.feature);
      EXPECT_NEAR((p.contact_mm - x.point_mm).dot(x.direction), 0, 1e-12) << p.feature << " " << p.point;
      EXPECT_EQ(p.normal, x.direction);
    }
    EXPECT_EQ(per["TOP"], 9);
    for (int k = 1; k <= 4; ++k) {
      for (const char* side : {"_XP", "_XN", "_YP", "_YN"}) EXPECT_EQ(per["S" + std::to_string(k) + side], 6);
      EXPECT_EQ(per["S" + std::to_string(k) + "_F"], 9);
    }
  }
  const auto pts = probePoints(w, nominalFeatures(w));
  std::vector<Vector3d> s1xp, s4yn, s1f;
  for (const auto& p : pts) {
    if (p.feature == "S1_XP") s1xp.push_back(p.contact_mm);
    if (p.feature == "S4_YN") s4yn.push_back(p.contact_mm);
    if (p.feature == "S1_F") s1f.push_back(p.contact_mm);
  }
  // S1_XP: x = 30, y = 15 + (-0.6, 0, 0.6) x 15 along +Y, z = -0.2 x 9 and -0.8 x 9.
  const std::vector<Vector3d> want{{30, 6, -1.8}, {30, 15, -1.8}, {30, 24, -1.8}, {30, 6, -7.2}, {30, 15, -7.2}, {30, 24, -7.2}};
  ASSERT_EQ(s1xp.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_LT((s1xp[i] - want[i]).norm(), 1e-12) << i;
  // S4_YN: y = -34.5, its wall from z -29 to -37: levels at -30.6 and -35.4.
  for (const auto& p : s4yn) {
    EXPECT_DOUBLE_EQ(p.y(), -34.5);
    EXPECT_TRUE(std::abs(p.z() + 30.6) < 1e-12 || std::abs(p.z() + 35.4) < 1e-12) << p.z();
  }
  // S1_F: the ring between the 30 and 45 squares at z -9, points on its mid-line (18.75 from
  // the centre), two per side and the middle of +X: 3 points with x - 15 = 18.75.
  int on_xp = 0;
  for (const auto& p : s1f) {
    EXPECT_DOUBLE_EQ(p.z(), -9);
    EXPECT_NEAR(std::max(std::abs(p.x() - 15), std::abs(p.y() - 15)), 18.75, 1e-12);
    on_xp += std::abs(p.x() - 33.75) < 1e-12;
  }
  EXPECT_EQ(on_xp, 3);
  // A 16 mm ball does not fit the 7.5 mm ring of step 1's floor.
  expectRefused(variant("tip_diameter: 2 mm", "tip_diameter: 16 mm"), "probing: ");
  expectRefused(variant("tip_diameter: 2 mm", "tip_diameter: 16 mm"), "lies within 8.5 mm (the ball's radius + 0.5 mm) of the face's edge");
  expectRefused(variant("wall_positions: [-0.6, 0, 0.6]", "wall_positions: [-0.6, 0, 1.2]"), "wall_positions: 1.2: expected fractions of the wall's half length, strictly between -1 and 1");
  expectRefused(variant("wall_levels: [0.2, 0.8]", "wall_levels: [0.2, 1.3]"), "wall_levels: 1.3: expected fractions");
  // 0.95 of the half length of the 30 mm step: 0.75 mm from its corner, within 1.5 mm.
  expectRefused(variant("wall_positions: [-0.6, 0, 0.6]", "wall_positions: [-0.95, 0, 0.6]"), "feature S1_XP: point 1 lies within 1.5 mm");
}

TEST(SteppedWorkpiece, BadDescriptionsAreRefusedWithTheLine) {
  const std::string small = refusal(variant("{size: 45 mm, floor_depth: 19 mm}", "{size: 25 mm, floor_depth: 19 mm}"));
  EXPECT_TRUE(std::regex_search(small, std::regex(R"(\.yaml:[0-9]+: steps: step 2 \(25 mm\) must be larger than step 1)"))) << small;
  expectRefused(variant("{size: 80 mm, floor_depth: 29 mm}", "{size: 80 mm, floor_depth: 15 mm}"), "floor_depth: must be deeper than the floor of the step above (19 mm)");
  expectRefused(variant("height: 50 mm ", "height: 30 mm "), "the deepest floor (37 mm) must lie above");
  // 50 - 0.5 - 37 = 12.5 mm of base; 45 mm would leave 4.5, under the 5 mm kept above the fixture.
  expectRefused(variant("{size: 99 mm, floor_depth: 37 mm}", "{size: 99 mm, floor_depth: 45 mm}"),
                "the deepest floor (45 mm) leaves 4.5 mm of base above the fixture");
  expectRefused(variant("size: [150 mm, 150 mm]", "size: [110 mm, 150 mm]"), "leaves 5.5 mm to the blank's edge");
  expectRefused(variant("      - {feed_xy: 800, feed_z: 800, spindle_speed: 3500}\n  - id: W4",
                              "  - id: W4"), "steps: expected 4 entries, one per step of the workpiece, got 3");
  expectRefused(variant("  - id: W4\n", "  - id: W1\n"), "experiments: W1 is listed twice");
  expectRefused(variant("transition: continuous ", "transition: continuous\n    transition_feed: 100 mm/min "), "transition_feed: a continuous path has no transitions");
  expectRefused(variant("transition: fast", "transition: rapid"), "transition");
  expectRefused(variant("finishing_tool: 1", "finishing_tool: 2"), "tool T2 is not in the tools list");
  expectRefused(variant("alternative_sizes: [29 mm, 44 mm, 79 mm, 99 mm]", "alternative_sizes: [29 mm, 44 mm, 99 mm]"), "alternative_sizes: expected one size per step (4)");
  expectRefused(variant("finishing_margin: 0.5 mm", "finishing_margin: 0.5 mm\nfinish_margin: 1 mm"), "finish_margin");
  expectRefused(variant("inset: 10 mm", "inset: 2 mm"), "inset: a hole 2 mm in from the edges would break out of the blank");
  // 15 mm in: 60 mm from the centre, inside the largest step's path (49.5 + 10 + 4.5 = 64).
  expectRefused(variant("inset: 10 mm", "inset: 15 mm"), "the clamp holes at 60 mm from the centre");
  // The holes 65 mm from the centre along X and Y (91.92 mm away) with their 4.5 mm radius
  // reach 96.42 mm: they bolt into nothing on a 160 mm fixture.
  expectRefused(variant("diameter: 200 mm", "diameter: 160 mm"), "fixture.diameter: 160 mm: the clamp holes reach 96.42 mm");
  // Finishing cuts a wall in one pass: step 2's 10 mm wall + 0.5 mm margin needs 10.5 mm of flute.
  expectRefused(variant("flute_length: 22 mm", "flute_length: 10 mm"), "step 2: its wall (10.5 mm with the margin) is taller than the flutes");
  expectRefused(variant("depth_per_level: 5 mm", "depth_per_level: 30 mm"), "depth_per_level: 30 mm is deeper than the flutes of T1 (22 mm)");
  expectRefused(variant("stepover: 0.75", "stepover: 1.2"), "stepover: expected a fraction of the tool's diameter");
  expectRefused(variant("step3_wall_passes: 2", "step3_wall_passes: 0"), "step3_wall_passes: expected 1 (no repeat) to 10");
}

}  // namespace
}  // namespace probeloop::parts
