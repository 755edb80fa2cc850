#include "geometry/fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace {
// A bore of radius 25 mm at (600, -400) sampled by 120 tip centres with 1 um noise, and
// spikes of +40 um at the given indices (chips or dust under the probe).
Points3 circleWithSpikes(const std::vector<int>& spikes, std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.7e-3, 1.7e-3);  // ~1 um RMS
  Points3 p;
  for (int i = 0; i < 120; ++i) {
    const double a = 2 * M_PI * i / 120.0;
    double r = 25.0 + u(rng);
    if (std::find(spikes.begin(), spikes.end(), i) != spikes.end()) r += 0.040;
    p.emplace_back(600 + r * std::cos(a), -400 + r * std::sin(a), 12.0);
  }
  return p;
}
}  // namespace

TEST(FitElementOutliers, DropsExactlyTheSpikesAndReportsThem) {
  const std::vector<int> spikes{17, 80};
  const Points3 p = circleWithSpikes(spikes);
  FitOptions o;
  o.outliers = OutlierOptions{};
  const ElementFit f = fitElement(ElementKind::Circle2D, p, o);
  ASSERT_EQ(f.dropped.size(), 2u);
  EXPECT_EQ(f.dropped[0].index, 17);
  EXPECT_EQ(f.dropped[1].index, 80);
  EXPECT_EQ(f.dropped[0].round, 1);
  EXPECT_NEAR(f.dropped[0].residual_mm, 0.040, 0.005);
  EXPECT_EQ(f.kept.size(), 118u);
  EXPECT_EQ(f.fit.residuals_mm.size(), 118u);
  // Without the spikes the scatter is the noise: RMS below 1.5 um, form below 4 um.
  EXPECT_LT(f.fit.rms_mm, 1.5e-3);
  EXPECT_LT(f.fit.form_mm, 4e-3);
  EXPECT_NEAR(f.fit.element.radius_mm, 25.0, 1e-3);
  EXPECT_GE(f.outlier_rounds, 2);  // a second round confirmed nothing more to drop
}

TEST(FitElementOutliers, CleanDataLosesNothing) {
  FitOptions o;
  o.outliers = OutlierOptions{};
  const ElementFit f = fitElement(ElementKind::Circle2D, circleWithSpikes({}), o);
  EXPECT_TRUE(f.dropped.empty());
  EXPECT_EQ(f.outlier_rounds, 1);
}

TEST(FitElementOutliers, RefusesToEatAWrongElement) {
  // A square traced as a circle: the "outliers" are the shape, not dirt.
  Points3 p;
  for (int i = 0; i < 40; ++i) {
    const double t = -10.0 + 20.0 * i / 40.0;
    p.emplace_back(t, -10, 0);
    p.emplace_back(10, t, 0);
    p.emplace_back(-t, 10, 0);
    p.emplace_back(-10, -t, 0);
  }
  FitOptions o;
  o.outliers = OutlierOptions{1.0, 10, 0.05};
  try {
    fitElement(ElementKind::Circle2D, p, o);
    FAIL() << "accepted";
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("check the element type"), std::string::npos) << e.what();
  }
}

TEST(FitElementOptions, KnownRadiusOnlyWithLeastSquares) {
  FitOptions o;
  o.method = FitMethod::MinimumZone;
  o.fixed_radius_mm = 25.0;
  EXPECT_THROW(fitElement(ElementKind::Circle2D, circleWithSpikes({}), o), GeometryError);
}

TEST(FitElementTip, BoreDiameterFromTipCentres) {
  FitOptions o;
  o.tip = TipCompensation{1.5, MaterialSide::Outside};  // bore: material outside
  const ElementFit f = fitElement(ElementKind::Circle2D, circleWithSpikes({}), o);
  EXPECT_NEAR(f.fit.element.radius_mm - f.tip_centre_element.radius_mm, 1.5, 1e-15);
  EXPECT_NEAR(f.fit.element.radius_mm, 26.5, 1e-3);
}
