// The thermal test piece from the features a CMM states (issue 34): the hand-derived errors
// from features written down from the chosen surfaces, the same values as the point route when
// the features are the least-squares fits of its points, foreign ids, a stated u, and what is
// refused or left out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "evaluate/feature_test_support.hpp"
#include "evaluate/feature_points.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "evaluate/ttp_ingest.hpp"
#include "evaluate/ttp_test_support.hpp"
#include "geometry/fit.hpp"

namespace probeloop::evaluate {
namespace {

using namespace ttptest;
using Eigen::Vector3d;

FeatureActual stated(int line, const std::string& id, const std::string& kind, const Vector3d& p, const Vector3d& n, double size,
                     double form_um, int n_points) {
  return feature_test::statedFeature(line, id, kind, p, n, size, form_um, n_points, "features.csv");
}

// The features as the chosen truth makes them, written down from its definition (not fitted):
// facets moved along their normal, Z paths cut deeper and tilted about +Y, datums nominal.
std::vector<FeatureActual> featuresOfTruth(const Fixture& f, const Truth& t) {
  std::vector<FeatureActual> out;
  int line = 1;
  for (const auto& mf : f.m.features) {
    const auto& n = mf.nominal;
    const double off = t.offset_mm.count(n.id) ? t.offset_mm.at(n.id) : 0.0;
    if (n.kind == "cylinder") {
      out.push_back(stated(++line, n.id, "circle", n.point_mm, n.direction, f.t.datum_band_diameter_mm, NAN, 0));
    } else if (n.role == "z_path") {
      const double b = t.beta_rad.count(n.id) ? t.beta_rad.at(n.id) : 0.0;
      out.push_back(stated(++line, n.id, "plane", n.point_mm - off * Vector3d::UnitZ(), Vector3d(std::tan(b), 0, 1), NAN, NAN, 0));
    } else if (n.role == "facet") {
      // On the facet's centre line at mid-height of its points (any point of the plane would do).
      const Vector3d p = (f.t.facet_apothem_mm + off) * n.direction + Vector3d(0, 0, n.point_mm.z());
      out.push_back(stated(++line, n.id, "plane", p, n.direction, NAN, NAN, 0));
    } else {
      out.push_back(stated(++line, n.id, "plane", n.point_mm, n.direction, NAN, NAN, 0));
    }
  }
  return out;
}

// The least-squares features of measured points, as CMM software states them: location at the
// centroid (plane) or on the axis, form = the range of the residuals, n = the point count.
std::vector<FeatureActual> fittedFeatures(const Fixture& f, const std::vector<Measured>& pts) {
  std::map<std::string, std::vector<Vector3d>> by;
  for (const auto& p : pts) by[p.feature].push_back(p.surface_mm);
  std::vector<FeatureActual> out;
  int line = 1;
  for (const auto& mf : f.m.features) {
    const auto it = by.find(mf.nominal.id);
    if (it == by.end()) continue;
    // The datum band is probed at one level: a circle, as CMM software reports it.
    const bool cyl = mf.nominal.kind == "cylinder";
    const auto fit = geometry::fitElement(cyl ? geometry::ElementKind::Circle3D : geometry::ElementKind::Plane, it->second, {}).fit;
    out.push_back(stated(++line, mf.nominal.id, cyl ? "circle" : "plane", fit.element.position_mm, fit.element.direction,
                         cyl ? 2 * fit.element.radius_mm : NAN, fit.form_mm * 1e3, static_cast<int>(it->second.size())));
  }
  return out;
}

// A few um of deterministic roughness on every point, along its normal.
std::vector<Measured> rough(std::vector<Measured> pts) {
  int k = 0;
  for (auto& p : pts) p.surface_mm += 0.0012 * std::sin(1.7 * ++k) * p.outward;
  return pts;
}

std::string refusal(const Fixture& f, const std::vector<FeatureActual>& rows) {
  try {
    evaluateThermalTestPieceFromFeatures(f.m, rows, "features.csv", "features");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

}  // namespace

TEST(TtpFromFeatures, HandDerivedErrorsFromTheFeaturesOfTheChosenSurfaces) {
  const auto f = makeFixture();
  const auto e = evaluateThermalTestPieceFromFeatures(f.m, featuresOfTruth(f, chosen(f)), "features.csv", "features");
  expectChosenErrors(e);
  ASSERT_TRUE(e.stated);
  EXPECT_EQ(e.assigned_by, "labels");
  EXPECT_EQ(e.stated->features.front().id, "TOP");
  EXPECT_EQ(e.stated->features.front().line, 2);
  // No form stated: the specification, MPE(L)/2, as on the point route.
  for (const auto& s : e.stated->features) EXPECT_EQ(s.sigma_from, "specification") << s.id;
  const auto& b = budget(e, 3, "EX_um");
  EXPECT_GT(contribution(b, "CMM point scatter from the stated features"), 0.0);
  EXPECT_EQ(contribution(b, "point scatter (type A)"), 0.0);
}

TEST(TtpFromFeatures, TheLeastSquaresFeaturesOfThePointsGiveThePointRoutesValues) {
  const auto f = makeFixture();
  const auto pts = rough(measure(f, chosen(f)));
  const auto by_points = evaluateThermalTestPiece(f.m, readTtpCmmExport("cmm.csv", cmmCsv(pts, true), f.m));
  const auto rows = fittedFeatures(f, pts);
  const auto by_features = evaluateThermalTestPieceFromFeatures(f.m, rows, "features.csv", "features");
  ASSERT_EQ(by_points.cycles.size(), by_features.cycles.size());
  for (std::size_t c = 0; c < by_points.cycles.size(); ++c)
    for (const auto& bp : by_points.cycles[c].values) {
      const auto* bf = by_features.cycles[c].value(bp.quantity);
      ASSERT_NE(bf, nullptr) << bp.quantity;
      EXPECT_NEAR(bf->value, bp.value, 1e-9) << "cycle " << c << " " << bp.quantity;
    }
  // The forms pooled (nu = sum(n - 3) over the Z paths and facets) against the point route's
  // pooled residual: the same scatter, estimated from ranges; within 25 % here.
  // Each form's sigma carries the dof of one range, 1/2 (d2/d3)^2, at most the residuals' n - 3.
  double dof = 0;
  for (const auto& x : by_points.features) dof += std::min(rangeDof(x.points), x.points - 3.0);
  EXPECT_NEAR(by_features.scatter.type_a_dof, dof, 1e-9);
  EXPECT_LT(by_features.scatter.type_a_dof, 1.4 * by_points.scatter.type_a_dof);
  EXPECT_NEAR(by_features.scatter.type_a_sigma_mm / by_points.scatter.type_a_sigma_mm, 1.0, 0.25);
  // Foreign ids in reverse order: the same values by the nominal geometry.
  auto foreign = rows;
  std::reverse(foreign.begin(), foreign.end());
  for (std::size_t i = 0; i < foreign.size(); ++i) foreign[i].id = "FEAT_" + std::to_string(i + 1);
  const auto by_geometry = evaluateThermalTestPieceFromFeatures(f.m, foreign, "features.csv", "features");
  EXPECT_EQ(by_geometry.assigned_by, "nominal geometry");
  for (std::size_t c = 1; c < by_points.cycles.size(); ++c)
    for (const auto& bp : by_points.cycles[c].values) EXPECT_NEAR(by_geometry.cycles[c].value(bp.quantity)->value, bp.value, 1e-9);
}

TEST(TtpFromFeatures, AStatedUOfALocationCarriesItsFeature) {
  const auto f = makeFixture();
  auto rows = featuresOfTruth(f, chosen(f));
  const std::string x1 = facetId(f, "X1", 3);
  for (auto& r : rows)
    if (r.id == x1) r.u_um = Vector3d(5, 5, 5);
  const auto plain = evaluateThermalTestPieceFromFeatures(f.m, featuresOfTruth(f, chosen(f)), "features.csv", "features");
  const auto e = evaluateThermalTestPieceFromFeatures(f.m, rows, "features.csv", "features");
  const auto s = std::find_if(e.stated->features.begin(), e.stated->features.end(), [&](const auto& x) { return x.id == x1; });
  ASSERT_NE(s, e.stated->features.end());
  EXPECT_EQ(s->sigma_from, "stated u");
  // u along the facet's normal: |n . (5, 5, 5) elementwise| um, times sqrt(n placed) per point.
  const Vector3d n = f.m.feature(x1)->nominal.direction.normalized();
  EXPECT_NEAR(s->sigma_um, n.cwiseProduct(Vector3d(5, 5, 5)).norm() * std::sqrt(static_cast<double>(s->n_planned)), 1e-9);
  // The plane's offset at its centroid then has the stated u, so u(d) >= u_n (d = n . c also
  // sees the normal's tilt, uncorrelated with it, through the centroid's height).
  auto ud = [&](const TtpEvaluation& x) -> double {
    for (const auto& r : x.features)
      if (r.id == x1) return r.u_d_um;
    return NAN;
  };
  const double u_n_um = n.cwiseProduct(Vector3d(5, 5, 5)).norm();
  EXPECT_GE(ud(e), u_n_um * (1 - 1e-12));
  EXPECT_GT(ud(e), ud(plain));
  // E_X of cycle 3 = [(d_X2,3 - d_X2,0) - (d_X1,3 - d_X1,0)] / 2: only X1_3's term changes, by 1/2.
  const double u_plain = budget(plain, 3, "EX_um").u_c, u = budget(e, 3, "EX_um").u_c;
  EXPECT_NEAR(u * u - u_plain * u_plain, 0.25 * (ud(e) * ud(e) - ud(plain) * ud(plain)), 1e-9);
  EXPECT_DOUBLE_EQ(value(e, 3, "EX_um"), value(plain, 3, "EX_um"));
}

TEST(TtpFromFeatures, RefusalsAndAMissingFacet) {
  const auto f = makeFixture();
  auto rows = featuresOfTruth(f, chosen(f));
  auto without = [&](const std::string& id) {
    auto r = rows;
    r.erase(std::remove_if(r.begin(), r.end(), [&](const FeatureActual& x) { return x.id == id; }), r.end());
    return r;
  };
  EXPECT_NE(refusal(f, without("FLANK_P")).find("features.csv: the datum FLANK_P is not among the file's features"), std::string::npos);
  EXPECT_NE(refusal(f, without(facetId(f, "X1", 0))).find("the reference feature " + facetId(f, "X1", 0)), std::string::npos);
  const auto e = evaluateThermalTestPieceFromFeatures(f.m, without(facetId(f, "Y2", 4)), "features.csv", "features");
  EXPECT_EQ(e.cycles[4].value("EY_um"), nullptr);
  EXPECT_NE(e.cycles[4].value("EX_um"), nullptr);
  ASSERT_EQ(e.cycles[4].missing.size(), 1u);
  EXPECT_NE(e.cycles[4].missing[0].find(facetId(f, "Y2", 4)), std::string::npos);
  // A feature displaced by 2 mm in the file: it fits nothing and is listed, not used.
  auto off = rows;
  for (auto& r : off)
    if (r.id == facetId(f, "Y1", 5)) r.id = "MYSTERY", r.location_mm += 2 * r.direction;
  const auto e2 = evaluateThermalTestPieceFromFeatures(f.m, off, "features.csv", "features");
  ASSERT_EQ(e2.stated->unmatched.size(), 1u);
  EXPECT_NE(e2.stated->unmatched[0].find("plane 'MYSTERY' (nearest " + facetId(f, "Y1", 5) + ", 2 mm: off its plane by 2 mm (at most 0.5))"),
            std::string::npos)
      << e2.stated->unmatched[0];
  EXPECT_EQ(e2.cycles[5].value("EY_um"), nullptr);
}

}  // namespace probeloop::evaluate
