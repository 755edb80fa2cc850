// Feature actuals matched to a plan's nominal features (issue 34): by id, by nominal geometry,
// and the refusals, on a hand-made plan of three Z-path strips 12 mm apart, a facet and a datum
// cylinder.
#include "evaluate/feature_match.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "evaluate/feature_test_support.hpp"

using namespace probeloop;
using namespace probeloop::evaluate;

namespace {

parts::ManifestFeature plane(const std::string& id, const Eigen::Vector3d& p, const Eigen::Vector3d& n, const Eigen::Vector3d& u,
                             double hu, double hv) {
  return feature_test::nominalPlane(id, p, n, u, hu, hv);
}

parts::PlanManifest plan() {
  parts::PlanManifest m;
  m.file = "plan.json";
  m.kind = "thermal_test_piece";
  for (int j = 0; j < 3; ++j)
    m.features.push_back(plane("Z" + std::to_string(j + 1), {0, -12.0 + 12 * j, -12.1}, {0, 0, 1}, {1, 0, 0}, 80, 6));
  m.features.push_back(plane("X1_1", {-100, 0, -20}, {-1, 0, 0}, {0, 1, 0}, 30, 4));
  parts::ManifestFeature c;
  c.nominal.id = "CYL";
  c.nominal.kind = "cylinder";
  c.nominal.point_mm = {0, 0, -16.5};
  c.nominal.direction = {0, 0, 1};
  c.nominal.radius_mm = 100.5;
  m.features.push_back(c);
  return m;
}

FeatureActual row(int line, const std::string& id, const std::string& kind, const Eigen::Vector3d& p, const Eigen::Vector3d& n,
                  double size = NAN) {
  return feature_test::statedFeature(line, id, kind, p, n, size);
}

std::string refusal(const std::vector<FeatureActual>& rows) {
  try {
    matchFeatureActuals(rows, plan());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MatchFeatureActuals, ByIdAndByNominalGeometryInFileOrder) {
  const auto m = plan();
  // Z2's strip is y in [-6, 6] (+1 mm margin); the row lies 5 mm off its centre line, 20 um deep.
  // PLN_7 states its normal into the material: a plane matches in either sense.
  const auto r = matchFeatureActuals({row(2, "PLN_7", "plane", {30, 5, -12.12}, Eigen::Vector3d(1e-5, 0, -1).normalized()),
                                      row(3, "X1_1", "plane", {-100.002, 3, -20}, {-1, 0, 0}),
                                      row(4, "CIR_1", "circle", {0.001, -0.002, -16}, {0, 0, -1}, 201.0),
                                      row(5, "PT_1", "point", {0, 0, 0}, {0, 0, 0})},
                                     m);
  ASSERT_EQ(r.matched.size(), 3u);
  EXPECT_EQ(r.matched[0].feature->nominal.id, "Z2");
  EXPECT_FALSE(r.matched[0].by_id);
  EXPECT_EQ(r.matched[1].feature->nominal.id, "X1_1");
  EXPECT_TRUE(r.matched[1].by_id);
  EXPECT_EQ(r.matched[2].feature->nominal.id, "CYL");  // a circle for the cylinder, its axis reversed
  EXPECT_EQ(r.other_kinds, 1);
  EXPECT_EQ(r.assigned_by, "labels and nominal geometry");
  ASSERT_NE(r.find("CYL"), nullptr);
  EXPECT_EQ(r.find("CYL")->actual.line, 4);
  EXPECT_EQ(r.find("Z1"), nullptr);
}

TEST(MatchFeatureActuals, ARowThatFitsNothingIsListedWithItsNearestFeature) {
  // 7.5 mm off Z1's centre line: outside its strip (6 + 1 mm), and outside Z2's (19.5 mm).
  const auto r = matchFeatureActuals({row(2, "A", "plane", {0, -12, -12.1}, {0, 0, 1}),
                                      row(3, "B", "plane", {0, -19.5, -12.1}, {0, 0, 1}),
                                      row(4, "REF", "sphere", {300, 0, 0}, {0, 0, 0}, 25.0)},
                                     plan());
  ASSERT_EQ(r.matched.size(), 1u);
  ASSERT_EQ(r.unmatched.size(), 2u);
  EXPECT_EQ(r.unmatched[0].actual.id, "B");
  EXPECT_EQ(r.unmatched[0].nearest, "Z1");
  EXPECT_NEAR(r.unmatched[0].distance_mm, 1.5, 1e-12);  // on Z1's plane, 1.5 mm beyond its extent
  EXPECT_EQ(r.unmatched[0].why, "beyond its face by 1.5 mm (at most 1)");
  EXPECT_EQ(r.unmatched[1].nearest, "");               // the plan has no sphere
  EXPECT_EQ(r.assigned_by, "nominal geometry");
}

TEST(MatchFeatureActuals, Refusals) {
  EXPECT_NE(refusal({row(7, "CYL", "plane", {0, 0, 0}, {0, 0, 1})}).find("f.csv:7: 'CYL' is a cylinder in the plan plan.json, but the file gives a plane"),
            std::string::npos);
  EXPECT_NE(refusal({row(2, "Z1", "plane", {0, -12, -12.1}, {0, 0, 1}), row(3, "P", "plane", {1, -12, -12.1}, {0, 0, 1})})
                .find("f.csv:3: feature Z1 is given twice: by the row at line 2 ('Z1') and the row at line 3 ('P')"),
            std::string::npos);
  // A strip boundary: y = -6 is 6 mm from both Z1 and Z2's centre lines, within both extents.
  EXPECT_NE(refusal({row(4, "P", "plane", {0, -6, -12.1}, {0, 0, 1})}).find("fits both Z1 (0 mm) and Z2 (0 mm)"), std::string::npos);
  // Everything 5 mm too high: another frame.
  const std::string other = refusal({row(2, "P", "plane", {0, 0, -7.1}, {0, 0, 1}), row(3, "Q", "plane", {0, 12, -7.1}, {0, 0, 1})});
  EXPECT_NE(other.find("f.csv:2: no feature of the file fits a feature of the plan plan.json"), std::string::npos) << other;
  EXPECT_NE(other.find("nearest Z2, 5 mm"), std::string::npos) << other;
  auto two = row(3, "Z2", "plane", {0, 0, -12.1}, {0, 0, 1});
  two.cycle = 2;
  EXPECT_NE(refusal({row(2, "Z1", "plane", {0, -12, -12.1}, {0, 0, 1}), two}).find("f.csv:3: cycle 2: the thermal_test_piece is measured once"),
            std::string::npos);
  // A row named for a feature must lie on it too: the features routes place the plan's points
  // on it in the part frame.
  const std::string named = refusal({row(5, "Z1", "plane", {0, -12, -12.1}, Eigen::Vector3d(0.035, 0, 1).normalized())});
  EXPECT_NE(named.find("f.csv:5: plane 'Z1' is named for Z1 but lies off its nominal geometry: normal off by 2.00"), std::string::npos)
      << named;
  EXPECT_NE(refusal({row(6, "CYL", "circle", {0.8, 0, -16.5}, {0, 0, 1}, 201.0)}).find("off its axis by 0.8 mm (at most 0.5)"),
            std::string::npos);
  // A normal 2 deg off fits nothing.
  EXPECT_NE(refusal({row(2, "P", "plane", {0, 0, -12.1}, Eigen::Vector3d(0.035, 0, 1).normalized())}).find("nearest"),
            std::string::npos);
}
