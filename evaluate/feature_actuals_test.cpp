// The feature-actuals reader (issue 34), the sphere centres matched from it, and the budget of
// location errors evaluated from stated centres, against hand derivations.
#include "evaluate/feature_actuals.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "evaluate/sphere_campaign.hpp"

using namespace probeloop;
using namespace probeloop::evaluate;

namespace {

// The thesis layout by hand: positions 1-4 at -X, +Y, +X, -Y (d/2 = 160 mm), 5 repeats 1.
parts::PlanManifest plan() {
  parts::PlanManifest m;
  const double ang[5] = {180, 90, 0, 270, 180};
  for (int k = 0; k < 5; ++k) {
    parts::ManifestSphere s;
    s.id = "S" + std::to_string(k + 1);
    s.position = k + 1;
    s.angle_deg = ang[k];
    s.nominal_centre_mm = {160 * std::cos(degToRad(ang[k])), 160 * std::sin(degToRad(ang[k])), 75};
    s.repeat_of = k == 4 ? 1 : 0;
    m.spheres.push_back(s);
  }
  m.cycles = 2;
  m.cycle_start_s = {0, 600};
  m.radius_from_axis_mm = 160;
  m.sphere_radius_mm = 15;
  m.tip_radius_mm = 3;
  m.probe_repeatability_2sigma_um = 1;
  m.sphere_form_error_um = 0;
  return m;
}

const std::string kHeader = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points,u_x_um,u_y_um,u_z_um,time_s\n";

std::string row(int cycle, const std::string& id, const Eigen::Vector3d& c, double t, const std::string& u = "0.8,0.8,0.8") {
  char b[256];
  std::snprintf(b, sizeof b, "%d,%s,sphere,%.6f,%.6f,%.6f,,,,30,0,5,%s,%.1f\n", cycle, id.c_str(), c.x(), c.y(), c.z(), u.c_str(), t);
  return b;
}

std::string refusal(const std::string& text, const parts::PlanManifest* m = nullptr) {
  try {
    const auto rows = parseFeatureActuals(text, "f.csv");
    if (m) sphereCentresFromFeatures(rows, *m);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(FeatureActuals, ReadsSemicolonsDecimalCommasAndCrlf) {
  const auto rows = parseFeatureActuals(
      "cycle;id;kind;x_mm;y_mm;z_mm;i;j;k;size_mm;form_um;n_points\r\n"
      "2;TOP;Plane;0;0;10,5;0;0;2;;1,25;40\r\n"
      "1;B1;cylinder;1;2;3;1;0;0;8,0;;12\r\n",
      "f.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].kind, "plane");
  EXPECT_EQ(rows[0].line, 2);
  EXPECT_DOUBLE_EQ(rows[0].location_mm.z(), 10.5);
  EXPECT_DOUBLE_EQ(rows[0].direction.z(), 1.0);  // normalised
  EXPECT_DOUBLE_EQ(rows[0].form_um, 1.25);
  EXPECT_TRUE(std::isnan(rows[0].size_mm));
  EXPECT_TRUE(std::isnan(rows[1].form_um));  // not stated
  EXPECT_EQ(rows[1].n_points, 12);
  EXPECT_FALSE(rows[1].u_um);
}

TEST(FeatureActuals, RefusesWithLineAndField) {
  const std::string h = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points\n";
  EXPECT_NE(refusal(h + "1,A,cone,0,0,0,,,,1,,5\n").find("f.csv:2: kind: 'cone' is not a feature kind"), std::string::npos);
  EXPECT_NE(refusal(h + "1,A,sphere,0,0,0,,,,30,,2.5\n").find("f.csv:2: n_points: 2.5 is not a positive integer"), std::string::npos);
  EXPECT_NE(refusal(h + "1,A,plane,0,0,0,0,0,0,,,5\n").find("f.csv:2: i,j,k: a plane needs its axis or normal"), std::string::npos);
  EXPECT_NE(refusal(h + "1,A,sphere,0,0,0,,,,30,-1,5\n").find("f.csv:2: form_um: -1 is negative"), std::string::npos);
  EXPECT_NE(refusal("cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points,u_x_um\n").find("u_x_um,u_y_um,u_z_um or none"),
            std::string::npos);
  EXPECT_NE(refusal(kHeader + row(1, "S1", {-160, 0, 75}, 1, "0.8,,0.8")).find("f.csv:2: u_x_um,u_y_um,u_z_um: all three or none"),
            std::string::npos);
}

// A fit needs at least as many points as its element has parameters: plane 3 (distance, two
// angles of the normal), circle 3 (centre in its plane, radius), sphere 4 (centre, radius),
// cylinder 5 (axis: a point in a plane across it and two angles; radius). One fewer is refused
// with the line and the field; exactly that many is read; a point is one point.
TEST(FeatureActuals, RefusesFewerPointsThanTheElementsParameters) {
  const std::string h = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points\n";
  const std::pair<const char*, int> kinds[] = {{"1,A,plane,0,0,0,0,0,1,,,", 3},
                                               {"1,A,circle,0,0,0,0,0,1,20,,", 3},
                                               {"1,A,sphere,0,0,0,,,,30,,", 4},
                                               {"1,A,cylinder,0,0,0,0,0,1,20,,", 5},
                                               {"1,A,point,0,0,0,,,,,,", 1}};
  for (const auto& [r, minimum] : kinds) {
    for (int n = 1; n < minimum; ++n)
      EXPECT_NE(refusal(h + r + std::to_string(n) + "\n").find("f.csv:2: n_points: " + std::to_string(n) + " points fit no "),
                std::string::npos)
          << r << n;
    EXPECT_EQ(refusal(h + r + std::to_string(minimum) + "\n"), "") << r << minimum;
  }
  EXPECT_NE(refusal(h + "1,A,plane,0,0,0,0,0,1,,,2\n").find("a plane has 3 parameters, so its fit needs at least 3 points"),
            std::string::npos);
}

TEST(FeatureActuals, MatchesForeignIdsByNominalCentreAndRepeatsByTime) {
  const auto m = plan();
  std::string t = kHeader;
  // Foreign ids, written in reverse order; the repeat of position 1 (position 5) is the later one.
  for (int p = 5; p >= 1; --p)
    t += row(1, "SPH" + std::to_string(p), m.spheres[p - 1].nominal_centre_mm + Eigen::Vector3d(0.002 * p, 0, 0), 10.0 * p);
  const auto c = sphereCentresFromFeatures(parseFeatureActuals(t, "f.csv"), m);
  ASSERT_EQ(c.by_cycle.at(1).size(), 5u);
  for (int p = 1; p <= 5; ++p) {
    EXPECT_EQ(c.by_cycle.at(1).at(p).feature.id, "SPH" + std::to_string(p));
    EXPECT_FALSE(c.by_cycle.at(1).at(p).by_id);
  }
  // Without the times, the two rows at position 1's place are refused, both named.
  const std::string both = kHeader + "1,P,sphere,-160,0,75,,,,30,0,5,,,,\n1,Q,sphere,-160,0,75,,,,30,0,5,,,,\n";
  EXPECT_NE(refusal(both, &m).find("f.csv:2: cycle 1: the rows at lines 2 ('P') and 3 ('Q') both match S1 and S5"), std::string::npos);
  // 6 mm from every planned centre: fits none.
  EXPECT_NE(refusal(kHeader + row(1, "X", {-154, 0, 75}, 1), &m).find("f.csv:2: sphere 'X' is 6.000 mm from the nearest planned centre (S1)"), std::string::npos);
  // A position twice (by its id, or by its id and a foreign row's centre); a diameter of another feature.
  EXPECT_NE(refusal(kHeader + row(1, "S2", {0, 160, 75}, 1) + row(1, "S2", {0, 160, 75}, 2), &m)
                .find("f.csv:3: cycle 1: position 2 is given twice, by the rows at lines 2 ('S2') and 3 ('S2')"),
            std::string::npos);
  EXPECT_NE(refusal(kHeader + row(1, "S2", {0, 160, 75}, 1) + row(1, "B", {0, 160, 75}, 2), &m)
                .find("f.csv:3: cycle 1: sphere 'B' matches S2, which the row at line 2 ('S2') names by its id"),
            std::string::npos);
  EXPECT_NE(refusal(kHeader + "1,S1,sphere,-160,0,75,,,,25,0,5,,,,\n", &m).find("size_mm: a diameter of 25 mm"), std::string::npos);
}

// EX0C is the mean x-displacement of the four level positions (the layout is symmetric, the
// least squares' columns orthogonal), so a stated u_x per centre gives u(EX0C) = u_x / 2 per
// cycle; the form term rectangular within +-form/2: form / (2 sqrt 3) per coordinate, / 2 again.
TEST(FeatureActuals, StatedCentreUncertaintyThroughTheLeastSquares) {
  const auto m = plan();
  std::string t = kHeader;
  for (int cyc = 1; cyc <= 2; ++cyc)
    for (int p = 1; p <= 5; ++p) {
      const Eigen::Vector3d shift = cyc == 2 ? Eigen::Vector3d(0.003, 0, 0) : Eigen::Vector3d::Zero();  // EX0C = 3 um
      t += row(cyc, "S" + std::to_string(p), m.spheres[p - 1].nominal_centre_mm + shift, 600.0 * (cyc - 1) + 10 * p, "0.8,0.6,0.4");
    }
  t.replace(t.find(",30,0,5,"), 8, ",30,2,5,");  // cycle 1, S1: form 2 um
  const auto e = evaluateSphereCampaignFromFeatures(m, sphereCentresFromFeatures(parseFeatureActuals(t, "f.csv"), m), "f.csv");
  ASSERT_EQ(e.cycles.size(), 2u);
  const auto& b = e.cycles[1].budgets[0];
  EXPECT_NEAR(b.value, 3.0, 1e-9);
  double stated_this = -1, stated_ref = -1, form_ref = -1;
  for (const auto& c : b.contributions) {
    if (c.input == "sphere centres as the feature file states them, this cycle") stated_this = c.u;
    if (c.input == "sphere centres as the feature file states them, reference cycle") stated_ref = c.u;
    if (c.input == "sphere form error, reference cycle") form_ref = c.u;
  }
  EXPECT_NEAR(stated_this, 0.4, 1e-12);
  EXPECT_NEAR(stated_ref, 0.4, 1e-12);
  // Only S1 of the reference cycle has form 2 um: its x enters EX0C with weight 1/4.
  EXPECT_NEAR(form_ref, 2.0 / 2 / std::sqrt(3.0) / 4, 1e-12);
  EXPECT_EQ(e.cycles[0].spheres[0].stated_u.u_mm.y(), 0.6e-3);
}

TEST(FeatureActualsFromCmm, ASphereOfPointsOnlyGetsItsLeastSquaresCentreHere) {
  interop::CmmDocument d;
  d.file = "points.qif";
  interop::CmmFeature s;
  s.name = "S1";
  s.kind = interop::CmmFeatureKind::Sphere;
  s.line = 12;
  const Eigen::Vector3d c(1, -2, 75);
  // The six poles and two more points of a 12.5 mm sphere about c: its LS centre is c exactly.
  for (const Eigen::Vector3d& u : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                   Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.6, 0, 0.8),
                                   Eigen::Vector3d(0, 0.8, 0.6)}) {
    interop::CmmPoint p;
    p.p_mm = c + 12.5 * u;
    s.points.push_back(p);
  }
  d.features.push_back(s);
  const auto rows = featureActualsFromCmm(d);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_TRUE(rows[0].fitted_here);
  EXPECT_LT((rows[0].location_mm - c).norm(), 1e-9);
  EXPECT_NEAR(rows[0].size_mm, 25.0, 1e-9);
  EXPECT_LT(rows[0].form_um, 1e-6);
  EXPECT_EQ(rows[0].n_points, 7);
  d.features[0].points.resize(3);
  try {
    featureActualsFromCmm(d);
    ADD_FAILURE() << "3 points accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("points.qif:12: sphere 'S1' has no measured Location and 3 points"), std::string::npos)
        << e.what();
  }
}

// Points only on a sphere whose radius the probe's pre-travel shrank (2 um below the known 15 mm),
// the upper hemisphere as a probe reaches it: the free-radius fit returns the true centre and
// 14.998 mm; the known-radius fit (the point route's default) keeps 15 mm and moves the centre by
// the offset that best stretches the points onto 15 mm. That offset, derived by hand: with the
// centre at c + t, point k (direction u_k) lies at ~ 14.998 - t.u_k (first order), so least
// squares gives (sum u u^T) t = -0.002 mm sum u. For the six directions below, sum u = (0.6, 0,
// 1.8) and sum u u^T has xx 2.36, yy 2, zz 1.64, xz 0.48: t_x = -0.002 (1.64 * 0.6 - 0.48 * 1.8)
// / 3.64, t_z = -0.002 (2.36 * 1.8 - 0.48 * 0.6) / 3.64 mm (3.64 the 2x2 determinant), t_y = 0.
TEST(FeatureActualsFromCmm, ASphereOfPointsOnlyIsFittedWithTheKnownRadiusUnlessFree) {
  interop::CmmDocument d;
  d.file = "points.qif";
  interop::CmmFeature s;
  s.name = "S1";
  s.kind = interop::CmmFeatureKind::Sphere;
  s.line = 7;
  const Eigen::Vector3d c(-160, 0, 75);
  for (const Eigen::Vector3d& u : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0),
                                   Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0.6, 0, 0.8)}) {
    interop::CmmPoint p;
    p.p_mm = c + 14.998 * u;
    s.points.push_back(p);
  }
  d.features.push_back(s);
  const auto free = featureActualsFromCmm(d);
  ASSERT_EQ(free.size(), 1u);
  EXPECT_LT((free[0].location_mm - c).norm(), 1e-9);
  EXPECT_NEAR(free[0].size_mm, 2 * 14.998, 1e-9);
  EXPECT_TRUE(std::isnan(free[0].fitted_known_radius_mm));
  const auto known = featureActualsFromCmm(d, 0, 15.0);
  ASSERT_EQ(known.size(), 1u);
  EXPECT_EQ(known[0].fitted_known_radius_mm, 15.0);
  EXPECT_NEAR(known[0].size_mm, 30.0, 1e-12);
  const double tx = -0.002 * (1.64 * 0.6 - 0.48 * 1.8) / 3.64, tz = -0.002 * (2.36 * 1.8 - 0.48 * 0.6) / 3.64;
  EXPECT_NEAR(known[0].location_mm.x(), c.x() + tx, 1e-6);  // first order: (2 um)^2 / 15 mm is below 1e-6 mm
  EXPECT_NEAR(known[0].location_mm.z(), c.z() + tz, 1e-6);
  EXPECT_NEAR(known[0].location_mm.y(), c.y(), 1e-9);
  EXPECT_GT(known[0].form_um, 0.1);  // the misfit of 15 mm on 14.998 mm shows as form
}

TEST(ParseFeatureActuals, AnEmptyPointCountIsNotStatedAZeroIsRefused) {
  const std::string h = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points\n";
  const auto rows = parseFeatureActuals(h + "1,P,plane,0,0,0,0,0,1,,2.5,\n", "f.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].n_points, 0);  // not stated: the plan's count stands in
  EXPECT_NE(refusal(h + "1,P,plane,0,0,0,0,0,1,,2.5,0\n").find("f.csv:2: n_points: 0 is not a positive integer (leave it empty"),
            std::string::npos);
}
