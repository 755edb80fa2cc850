// The chain's exact transformations against independent first-order derivations (seed 002
// Sec. 2.3 eq. 6; the rigid-body model of seed 004 Eqs. 5.4-5.10 in
// evaluate/location_errors.hpp) and the identifiability of location errors.
#include "geometry/identifiability.hpp"
#include "geometry/kinematic_chain.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace probeloop::geometry {
namespace {

using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;

// A B/C trunnion: B about -Y through (0, 0, zb), C about -Z through (cx, cy, zc) on it;
// X Y Z on the tool side.
KinematicChain trunnion(double zb, double cx, double cy, double zc) {
  KinematicChain c;
  Body b{"B trunnion", Vector3d::Zero(), {JointKind::Rotary, "B", -Vector3d::UnitY(), Vector3d(0, 0, zb)}};
  Body t{"C table", Vector3d::Zero(), {JointKind::Rotary, "C", -Vector3d::UnitZ(), Vector3d(cx, cy, zc), LocationConvention::BodyOnAxis}};
  c.workpiece_branch = {b, t};
  const char* n[3] = {"X", "Y", "Z"};
  for (int k = 0; k < 3; ++k) c.tool_branch.push_back(Body{std::string(n[k]), Vector3d::Zero(), {JointKind::Linear, n[k], Vector3d::Unit(k), Vector3d::Zero()}});
  return c;
}

TEST(TwistTransform, IsTheIdentityPlusSkewToFirstOrder) {
  // seed 002 eq. 6: Rot(x,ex) Rot(y,ey) Rot(z,ez) = I + skew(ex, ey, ez) + O(e^2)
  const double e = 1e-5;
  Twist t;
  t.rotation_rad = Vector3d(2 * e, -3 * e, 5 * e);
  const Eigen::Matrix3d R = twistTransform(t).linear();
  Eigen::Matrix3d expected;
  expected << 1, -5 * e, -3 * e, 5 * e, 1, -2 * e, 3 * e, 2 * e, 1;
  EXPECT_LT((R - expected).cwiseAbs().maxCoeff(), 40 * e * e);
  EXPECT_GT((R - expected).cwiseAbs().maxCoeff(), 1 * e * e);  // the second order is there
}

TEST(KinematicChain, MachineCoordinatesOfATablePointFollowTheRotaryAxes) {
  const auto chain = trunnion(-50, 10, 20, 0);
  ChainState s;
  s.positions = {{"B", 30}, {"C", 90}};
  // C' (about -Z) by 90 deg takes (cx + 100, cy, 0) to (cx, cy - 100, 0); then B' (about -Y)
  // by 30 deg about (0, 0, -50): x' = x cos - (z + 50) sin ... with the sign of -Y.
  const Vector3d after_c(10, 20 - 100, 0);
  const double b = 30 * kPi / 180;
  const Vector3d r = after_c - Vector3d(0, 0, -50);
  const Vector3d expected = Vector3d(0, 0, -50) + Vector3d(r.x() * std::cos(b) - r.z() * std::sin(b), r.y(),
                                                           r.x() * std::sin(b) + r.z() * std::cos(b));
  const Vector3d got = machineCoordinatesOf(chain, s, Vector3d(110, 20, 0));
  EXPECT_LT((got - expected).norm(), 1e-9);
}

TEST(KinematicChain, LocationErrorsOfCAtBZeroGiveTheFirstOrderSphereModel) {
  // evaluate/location_errors.hpp: dx = EX - c R sin t, dy = EY + c R cos t (c: right-hand
  // about +Z), dz = EZ + R (EA sin t - EB cos t) for a sphere at the pivot height.
  const double R = 160, zc = 75;
  const auto chain = trunnion(-100, 0, 0, zc);
  const int n = chain.bodyCount();
  std::vector<ChainParameter> p;
  for (int k = 0; k < 6; ++k) p.push_back(locationParameter(chain, "C", k));
  for (double t_deg : {0.0, 90.0, 200.0}) {
    const double t = t_deg * kPi / 180;
    const Vector3d w(R * std::cos(t), R * std::sin(t), zc);  // at C = 0
    ChainState base;
    auto observe = [&](const ChainState& s) { return Eigen::VectorXd(machineCoordinatesOf(chain, s, w)); };
    const Eigen::MatrixXd J = chainSensitivity(observe, base, p, n) * 1e3;  // um per um or urad
    // columns EX EY EZ EA EB EC (um, urad); rows dx dy dz in um
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(3, 6);
    expected(0, 0) = expected(1, 1) = expected(2, 2) = 1;
    expected(2, 3) = R * 1e-3 * std::sin(t);
    expected(2, 4) = -R * 1e-3 * std::cos(t);
    expected(0, 5) = -R * 1e-3 * std::sin(t);
    expected(1, 5) = R * 1e-3 * std::cos(t);
    EXPECT_LT((J - expected).cwiseAbs().maxCoeff(), 1e-9) << "at " << t_deg << " deg\n" << J;
  }
}

std::vector<std::string> namesOf(const std::vector<ChainParameter>& p) {
  std::vector<std::string> n;
  for (const auto& q : p) n.push_back(q.name);
  return n;
}

Eigen::MatrixXd sphereCentresSensitivity(const KinematicChain& chain, const std::vector<std::pair<double, double>>& bc,
                                         const Vector3d& w, const std::vector<ChainParameter>& p) {
  auto observe = [&](const ChainState& s) {
    Eigen::VectorXd v(3 * static_cast<Eigen::Index>(bc.size()));
    for (std::size_t k = 0; k < bc.size(); ++k) {
      ChainState t = s;
      t.positions = {{"B", bc[k].first}, {"C", bc[k].second}};
      v.segment<3>(3 * static_cast<Eigen::Index>(k)) = machineCoordinatesOf(chain, t, w);
    }
    return v;
  };
  return chainSensitivity(observe, ChainState{}, p, chain.bodyCount());
}

TEST(Identifiability, CPositionsAloneCannotSeeTheBAxis) {
  const auto chain = trunnion(0, 0, 0, 75);
  std::vector<ChainParameter> p;
  for (int k : {0, 1, 2, 3, 4, 5}) p.push_back(locationParameter(chain, "C", k));
  for (int k : {0, 2, 3, 5}) p.push_back(locationParameter(chain, "B", k));
  const Vector3d w(-160, 0, 75);
  const auto only_c = identifiability(sphereCentresSensitivity(chain, {{0, 0}, {0, 90}, {0, 180}, {0, 270}}, w, p), namesOf(p));
  EXPECT_FALSE(only_c.all());
  // B's line errors do nothing at B = 0 (ISO 230-7: the line; C's errors hold at B = 0).
  for (const char* who : {"EA0B", "EC0B", "EX0B", "EZ0B"}) {
    const auto it = std::find(only_c.names.begin(), only_c.names.end(), who);
    EXPECT_FALSE(only_c.identifiable[static_cast<std::size_t>(it - only_c.names.begin())]) << who;
  }
  EXPECT_FALSE(only_c.sentences().empty());
  // Tilting B to +-30 deg with the sphere along Y and along X separates all ten.
  const auto tilted = identifiability(
      sphereCentresSensitivity(chain, {{0, 0}, {0, 90}, {0, 180}, {0, 270}, {30, 90}, {-30, 90}, {30, 270}, {-30, 270}, {30, 0}, {-30, 180}}, w, p),
      namesOf(p));
  EXPECT_TRUE(tilted.all()) << (tilted.sentences().empty() ? "" : tilted.sentences().front());
}

TEST(Identifiability, TheZeroOfBIsTheTiltOfCPlusAShiftOfC) {
  // Turning the whole trunnion about B's own line equals tilting C about its pivot and
  // shifting it: EB0B = EB0C + (zc - zb) EX0C / 1000 (um per urad) moves no sphere centre.
  const double zb = -40, zc = 75;
  const auto chain = trunnion(zb, 0, 0, zc);
  std::vector<ChainParameter> p{locationParameter(chain, "B", 4), locationParameter(chain, "C", 4),
                                locationParameter(chain, "C", 0), locationParameter(chain, "C", 2)};
  const auto id = identifiability(
      sphereCentresSensitivity(chain, {{0, 0}, {0, 90}, {0, 180}, {0, 270}, {30, 90}, {-30, 270}}, Vector3d(-160, 0, zc), p),
      namesOf(p));
  ASSERT_EQ(id.relations.size(), 1u) << id.rank;
  const Eigen::VectorXd& v = id.relations[0];
  // EB0B 1 urad about B's line (direction -Y: right-hand about +Y is -1 in B's own sense)
  // moves the pivot by 1e-6 x (zc - zb) mm in X: so 1 urad of EB0B = 1 urad of EB0C and
  // (zc - zb) * 1e-3 um of EX0C, with opposite signs in the relation.
  EXPECT_NEAR(v(0), 1.0, 1e-9);
  EXPECT_NEAR(std::fabs(v(1)), 1.0, 1e-6);
  EXPECT_NEAR(std::fabs(v(2)), (zc - zb) * 1e-3, 1e-6);
  EXPECT_NEAR(v(3), 0.0, 1e-9);
  EXPECT_TRUE(id.identifiable[3]);
}

}  // namespace
}  // namespace probeloop::geometry
