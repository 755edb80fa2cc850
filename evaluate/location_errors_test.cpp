// The two location-error estimators against injected rigid-body perturbations of the C
// axis (exact transform, geometry::displacedOnTable) and against each other.
#include "evaluate/location_errors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.hpp"
#include "core/units.hpp"

using namespace probeloop;
using namespace probeloop::evaluate;
using Eigen::Vector3d;

namespace {
constexpr double kR = 160.0;  // d/2, mm (seed 004)
const Eigen::Vector2d kAxis(12.5, -30.0);

std::vector<Vector3d> nominal(const std::vector<double>& angles_deg) {
  std::vector<Vector3d> c;
  for (double a : angles_deg)
    c.emplace_back(kAxis.x() + kR * std::cos(degToRad(a)), kAxis.y() + kR * std::sin(degToRad(a)), 75.0);
  return c;
}

std::vector<Vector3d> displaced(const std::vector<Vector3d>& c, const LocationErrors& e) {
  std::vector<Vector3d> out;
  for (const auto& p : c) out.push_back(geometry::displacedOnTable(p, kAxis, e));
  return out;
}

// Thesis layout: formula index 1..4 at -X, +Y, +X, -Y (notes/seed004.md §2.3).
const std::vector<double> kThesis{180, 90, 0, 270};

std::array<Vector3d, 4> four(const std::vector<Vector3d>& v) { return {v[0], v[1], v[2], v[3]}; }

void expectNear(const LocationErrors& got, const LocationErrors& want, double tol) {
  const auto g = got.values(), w = want.values();
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(g[j], w[j], tol) << LocationErrors::names()[j];
}
}  // namespace

struct Perturbation {
  const char* name;
  LocationErrors e;
};

class SingleErrorRecovered : public ::testing::TestWithParam<Perturbation> {};

TEST_P(SingleErrorRecovered, ByFormulasAndLeastSquares) {
  const auto& e = GetParam().e;
  const auto ref = nominal(kThesis);
  const auto cyc = displaced(ref, e);
  // Second-order terms of the exact rigid-body motion are below 1e-3 um / urad here.
  expectNear(gebhardtFormulas(four(cyc), four(ref), 2 * kR * 1e-3), e, 1e-3);
  expectNear(LocationLeastSquares(kThesis, kR).solve(cyc, ref), e, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(
    RigidBody, SingleErrorRecovered,
    ::testing::Values(Perturbation{"shiftX", {5, 0, 0, 0, 0, 0, 0}},
                      Perturbation{"shiftY", {0, -7, 0, 0, 0, 0, 0}},
                      Perturbation{"liftZ", {0, 0, 11, 0, 0, 0, 0}},
                      Perturbation{"radialGrowth", {0, 0, 0, 4, 0, 0, 0}},
                      Perturbation{"tiltAboutX", {0, 0, 0, 0, 25, 0, 0}},
                      Perturbation{"tiltAboutY", {0, 0, 0, 0, 0, -30, 0}},
                      Perturbation{"zeroPosition", {0, 0, 0, 0, 0, 0, 40}},
                      Perturbation{"allAtOnce", {3, -4, 6, 2.5, 15, -20, 35}}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(LocationErrorSigns, MatchTheConventionsDrawing) {
  // A right-hand tilt about +X lifts the sphere on the +Y side: EA0C > 0 (docs/conventions.md).
  const auto ref = nominal(kThesis);
  LocationErrors tilt;
  tilt.EA0C_urad = 10;
  const auto cyc = displaced(ref, tilt);
  EXPECT_GT(cyc[1].z(), ref[1].z());  // index 2 is +Y
  // EC0C > 0: the table found turned clockwise seen from +Z: the +Y sphere moves to +X.
  LocationErrors zero;
  zero.EC0C_urad = 10;
  const auto turned = displaced(ref, zero);
  EXPECT_GT(turned[1].x(), ref[1].x());
}

TEST(LocationErrors, FormulasEqualLeastSquaresOnArbitraryData) {
  // Any data, not only rigid motions: both are the same linear map (docs/location-errors.md).
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  const auto ref0 = nominal(kThesis);
  const LocationLeastSquares ls(kThesis, kR);
  for (int trial = 0; trial < 100; ++trial) {
    auto ref = ref0, cyc = ref0;
    for (auto& p : ref) p += Vector3d(u(rng), u(rng), u(rng));
    for (auto& p : cyc) p += Vector3d(u(rng), u(rng), u(rng));
    const auto a = gebhardtFormulas(four(cyc), four(ref), 2 * kR * 1e-3).values();
    const auto b = ls.solve(cyc, ref).values();
    for (int j = 0; j < 7; ++j) EXPECT_NEAR(a[j], b[j], 1e-9) << LocationErrors::names()[j];
  }
}

TEST(LocationLeastSquares, AnyLayoutRecoversAllErrors) {
  const LocationErrors e{3, -4, 6, 2.5, 15, -20, 35};
  for (const auto& angles : std::vector<std::vector<double>>{
           {0, 120, 240}, {10, 55, 100, 145, 190, 235, 280, 325}, {30, 90, 200}}) {
    const auto ref = nominal(angles);
    expectNear(LocationLeastSquares(angles, kR).solve(displaced(ref, e), ref), e, 2e-3);
  }
}

TEST(LocationLeastSquares, DegenerateLayoutsAreExplained) {
  EXPECT_THROW(LocationLeastSquares({0, 180}, kR), GeometryError);
  try {
    LocationLeastSquares({0, 180, 0}, kR);
    FAIL();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("spread the positions"), std::string::npos) << e.what();
  }
}

TEST(LocationLeastSquares, ResidualSeesNonRigidMotion) {
  const auto ref = nominal(kThesis);
  auto cyc = ref;
  cyc[0].x() += 0.004;  // one sphere alone moves 4 um: not a rigid motion of the axis
  const auto r = LocationLeastSquares(kThesis, kR).residual(cyc, ref);
  EXPECT_EQ(r.dof_xy, 4);
  EXPECT_EQ(r.dof_z, 1);
  EXPECT_GT(r.xy_um, 1.0);
  EXPECT_NEAR(LocationLeastSquares(kThesis, kR).residual(displaced(ref, {3, 1, 2, 1, 5, 5, 5}), ref).xy_um,
              0.0, 1e-3);
}
