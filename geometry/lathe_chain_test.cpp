// Seed 002's turning centre: tests T002-1..3 of notes/seeds001-003.md §4.1. The reference
// is the notes' written-out first-order model (§2.5, derived with sympy in
// notes/verify/derive002.py), typed in below from the notes, not from lathe_chain.cpp; the
// ideal tool offset is eq. 24 with its -z (notes §2.4), typed in as well.
#include "geometry/identifiability.hpp"
#include "geometry/lathe_chain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace probeloop::geometry {
namespace {

using Eigen::Vector3d;

// The scalars of the notes' formulas: a[i], b[i], c[i] and the errors with i = 1..4.
struct Symbols {
  double a[5]{}, b[5]{}, c[5]{}, x = 0, z = 0, Wx = 0, Wy = 0, Wz = 0;
  double dx[5]{}, dy[5]{}, dz[5]{}, ex[5]{}, ey[5]{}, ez[5]{};
};

// notes §2.5, Px / Py / Pz as printed there
Vector3d notesFirstOrder(const Symbols& s) {
  const double *a = s.a, *b = s.b, *c = s.c, *dx = s.dx, *dy = s.dy, *dz = s.dz, *ex = s.ex, *ey = s.ey, *ez = s.ez;
  const double x = s.x, z = s.z, Wx = s.Wx, Wy = s.Wy, Wz = s.Wz;
  const double Px = dx[1] + dx[2] + dx[3] - dx[4] + ey[1] * (c[4] + Wz - z - c[1]) + ey[2] * (c[4] + Wz - z - c[1] - c[2]) +
                    ey[3] * (c[4] + Wz - z - c[1] - c[2] - c[3]) - ez[1] * (b[4] + Wy - b[1]) -
                    ez[2] * (b[4] + Wy - b[1] - b[2]) - ez[3] * (b[4] + Wy - b[1] - b[2] - b[3]) - ey[4] * Wz +
                    ez[4] * Wy;
  const double Py = dy[1] + dy[2] + dy[3] - dy[4] + ez[1] * (a[4] + Wx - a[1]) + ez[2] * (a[4] + Wx - a[1] - a[2] - x) +
                    ez[3] * (a[4] + Wx - a[1] - a[2] - a[3] - x) - ex[1] * (c[4] + Wz - z - c[1]) -
                    ex[2] * (c[4] + Wz - z - c[1] - c[2]) - ex[3] * (c[4] + Wz - z - c[1] - c[2] - c[3]) +
                    ex[4] * Wz - ez[4] * Wx;
  const double Pz = dz[1] + dz[2] + dz[3] - dz[4] + ex[1] * (b[4] + Wy - b[1]) + ex[2] * (b[4] + Wy - b[1] - b[2]) +
                    ex[3] * (b[4] + Wy - b[1] - b[2] - b[3]) - ey[1] * (a[4] + Wx - a[1]) -
                    ey[2] * (a[4] + Wx - a[1] - a[2] - x) - ey[3] * (a[4] + Wx - a[1] - a[2] - a[3] - x) +
                    ey[4] * Wx - ex[4] * Wy;
  return {Px, Py, Pz};
}

// eq. 24 with -z (notes §2.4)
Vector3d eq24(const Symbols& s, double z_sign = -1) {
  return {-s.a[1] - s.a[2] - s.a[3] + s.a[4] - s.x + s.Wx, -s.b[1] - s.b[2] - s.b[3] + s.b[4] + s.Wy,
          -s.c[1] - s.c[2] - s.c[3] + s.c[4] + z_sign * s.z + s.Wz};
}

LatheOffsets offsetsOf(const Symbols& s) {
  LatheOffsets off;
  for (int i = 0; i < 4; ++i) off.o[static_cast<std::size_t>(i)] = Vector3d(s.a[i + 1], s.b[i + 1], s.c[i + 1]);
  return off;
}

LatheErrors errorsOf(const Symbols& s) {
  LatheErrors e;
  for (int i = 1; i <= 4; ++i) {
    e.body[static_cast<std::size_t>(i - 1)].translation_mm = Vector3d(s.dx[i], s.dy[i], s.dz[i]);
    e.body[static_cast<std::size_t>(i - 1)].rotation_rad = Vector3d(s.ex[i], s.ey[i], s.ez[i]);
  }
  return e;
}

// Generic offsets and positions (mm): no lever arm vanishes.
Symbols generic() {
  Symbols s;
  const double a[4] = {310.5, -42.0, -28.5, 7.0}, b[4] = {12.0, -4.5, 3.0, 9.5}, c[4] = {705.0, 14.5, -61.0, 118.0};
  for (int i = 0; i < 4; ++i) s.a[i + 1] = a[i], s.b[i + 1] = b[i], s.c[i + 1] = c[i];
  s.x = -71.5, s.z = -352.0, s.Wx = 24.0, s.Wy = 3.5, s.Wz = 82.0;
  return s;
}

double* errorSlot(Symbols& s, int body, int component) {
  double* arrays[6] = {s.dx, s.dy, s.dz, s.ex, s.ey, s.ez};
  return &arrays[component][body];
}

Vector3d fullHtm(const Symbols& s) {
  const Vector3d T = eq24(s);
  return latheVolumetricError(latheChain(offsetsOf(s), T), s.x, s.z, errorsOf(s), Vector3d(s.Wx, s.Wy, s.Wz));
}

Vector3d firstOrder(const Symbols& s) {
  return latheVolumetricErrorFirstOrder(offsetsOf(s), eq24(s), s.x, s.z, errorsOf(s), Vector3d(s.Wx, s.Wy, s.Wz));
}

TEST(LatheT002_1, ClosedIdealChainHasNoVolumetricErrorExactly) {
  // dyadic offsets: every sum is exact in floating point, so "exactly" means == 0
  const Symbols s = generic();
  EXPECT_EQ(fullHtm(s), Vector3d::Zero());
  EXPECT_EQ(firstOrder(s), Vector3d::Zero());
  // and for arbitrary offsets and positions, to the rounding of sums of ~1000 mm
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(-800, 800);
  for (int trial = 0; trial < 50; ++trial) {
    Symbols r;
    for (int i = 1; i <= 4; ++i) r.a[i] = u(rng), r.b[i] = u(rng), r.c[i] = u(rng);
    r.x = u(rng), r.z = u(rng), r.Wx = u(rng), r.Wy = u(rng), r.Wz = u(rng);
    EXPECT_LT(fullHtm(r).norm(), 1e-11);
  }
}

TEST(LatheT002_1, PrintedPlusZOfEq24LeavesTwiceZOnTheFace) {
  // eq. 24 as printed (+z) does not close the chain: P_z = 2 z (the typo of notes §2.4)
  const Symbols s = generic();
  const Vector3d T = eq24(s, +1);
  const Vector3d P = latheVolumetricError(latheChain(offsetsOf(s), T), s.x, s.z, LatheErrors{}, Vector3d(s.Wx, s.Wy, s.Wz));
  EXPECT_EQ(P, Vector3d(0, 0, 2 * s.z));
}

TEST(LatheT002_1, IdealToolOffsetIsEq24WithMinusZ) {
  const Symbols s = generic();
  const Vector3d W(s.Wx, s.Wy, s.Wz);
  EXPECT_EQ(latheIdealToolOffset(offsetsOf(s), s.x, s.z, W), eq24(s));
  const Eigen::Vector2d xz = latheNominalXZ(offsetsOf(s), eq24(s), W);
  EXPECT_EQ(xz, Eigen::Vector2d(s.x, s.z));
}

TEST(LatheT002_2, EpsY1GivesTheNotesLeverOnPxOnly) {
  // notes §4.1 T002-2: eps_y1 = 1e-5 -> Px = 1e-5 (c4 + Wz - z - c1), Py = Pz = 0 to first order
  Symbols s = generic();
  s.ey[1] = 1e-5;
  const double Px = 1e-5 * (s.c[4] + s.Wz - s.z - s.c[1]);
  EXPECT_NEAR(firstOrder(s).x(), Px, 1e-15);
  EXPECT_EQ(firstOrder(s).y(), 0.0);
  // Pz carries eps_y1 (a4 + Wx - a1) to first order (the notes' Pz): the T002-2 sentence
  // "Pz = 0" holds for the lever a4 + Wx - a1 = 0 only
  EXPECT_NEAR(firstOrder(s).z(), -1e-5 * (s.a[4] + s.Wx - s.a[1]), 1e-15);
  const Vector3d full = fullHtm(s);
  EXPECT_NEAR(full.x(), Px, 1e-7);  // eps^2 * 1000 mm
  EXPECT_NEAR(full.y(), 0.0, 1e-7);
}

// Every one of the 24 errors alone: the code's first order is the notes' written-out model,
// and the full HTM differs from it by the second order only, which is really there for the
// rotations (it scales with eps^2) and absent for the translations.
TEST(LatheT002_2, EachOfTheTwentyFourErrorsMatchesTheNotesToFirstOrder) {
  const char* comp[6] = {"dx", "dy", "dz", "ex", "ey", "ez"};
  for (int body = 1; body <= 4; ++body)
    for (int k = 0; k < 6; ++k) {
      const bool rotation = k >= 3;
      const double v = rotation ? 1e-4 : 1e-2;  // rad, mm
      Symbols s = generic();
      *errorSlot(s, body, k) = v;
      const std::string what = std::string(comp[k]) + std::to_string(body);
      const Vector3d notes = notesFirstOrder(s);
      EXPECT_LT((firstOrder(s) - notes).norm(), 1e-13) << what;
      EXPECT_GT(notes.norm(), 0.5 * v) << what << ": every error reaches the tool-work gap";
      const Vector3d second = fullHtm(s) - notes;
      if (!rotation) {
        EXPECT_LT(second.norm(), 1e-12) << what << ": a translation enters exactly";
        continue;
      }
      // eps^2 times a lever < 1 m bounds it; halving eps quarters it
      EXPECT_LT(second.norm(), v * v * 1000) << what;
      *errorSlot(s, body, k) = v / 2;
      const Vector3d half = fullHtm(s) - notesFirstOrder(s);
      EXPECT_GT(second.norm(), 1e-3 * v * v) << what << ": the second order is there";
      EXPECT_NEAR(second.norm() / half.norm(), 4.0, 0.05) << what;
    }
}

TEST(LatheT002_2, AllTwentyFourTogetherAgreeToSecondOrder) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double scale : {1e-4, 1e-5}) {
    Symbols s = generic();
    for (int body = 1; body <= 4; ++body)
      for (int k = 0; k < 6; ++k) *errorSlot(s, body, k) = scale * u(rng) * (k < 3 ? 20 : 1);  // 20 um per 1 urad
    const Vector3d notes = notesFirstOrder(s);
    EXPECT_LT((firstOrder(s) - notes).norm(), 1e-13);
    EXPECT_LT((fullHtm(s) - notes).norm(), 50 * scale * scale * 1000) << "scale " << scale;
  }
}

TEST(LatheT002_2, TurnedDiameterAndFaceAreTwicePxAndPz) {
  // A turned point at centre height (Wy = 0): the diameter moves by 2 Px, the face by Pz,
  // to first order (the notes' Px, Pz).
  for (int body = 1; body <= 4; ++body)
    for (int k = 0; k < 6; ++k) {
      Symbols s = generic();
      s.Wy = 0;
      s.b[4] = s.b[1] + s.b[2] + s.b[3];  // the tool at centre height: Ty = 0 closes Y
      const double v = k >= 3 ? 1e-5 : 1e-3;
      *errorSlot(s, body, k) = v;
      const Vector3d W(s.Wx, s.Wy, s.Wz);
      const LatheCutErrors cut = latheCutErrors(latheChain(offsetsOf(s), eq24(s)), s.x, s.z, errorsOf(s), W);
      const Vector3d notes = notesFirstOrder(s);
      // second order: eps^2 * 1000 mm = 1e-7 mm, a tangential delta^2 / Wx = 4e-8 mm
      EXPECT_NEAR(cut.diameter_mm, 2 * notes.x(), 5e-7) << body << "," << k;
      EXPECT_NEAR(cut.face_z_mm, notes.z(), 5e-7) << body << "," << k;
    }
}

TEST(LatheT002_3, SmallRotationsComposeToIdentityPlusSkew) {
  // seed 002 eq. 6: Rot(x,Ex) Rot(y,Ey) Rot(z,Ez) = [[1,-Ez,Ey],[Ez,1,-Ex],[-Ey,Ex,1]] + O(e^2)
  for (double e : {1e-3, 1e-5}) {
    const double Ex = 3 * e, Ey = -2 * e, Ez = 5 * e;
    Twist t;
    t.rotation_rad = Vector3d(Ex, Ey, Ez);
    Eigen::Matrix3d eq6;
    eq6 << 1, -Ez, Ey, Ez, 1, -Ex, -Ey, Ex, 1;
    const double rest = (twistTransform(t).linear() - eq6).cwiseAbs().maxCoeff();
    EXPECT_LT(rest, 25 * e * e) << e;  // the largest product 5 x 5 / 2 ... 3 x 5
    EXPECT_GT(rest, 1 * e * e) << e;   // and not first order exact
  }
}

TEST(LatheChain, TwentyFourParametersAreTheBodiesTwists) {
  const auto p = latheParameters();
  ASSERT_EQ(p.size(), 24u);
  EXPECT_EQ(p[4].name, "ey1");
  EXPECT_EQ(p[23].name, "ez4");
  EXPECT_EQ(p[23].body, latheChainIndex(4));
  ChainState s;
  p[4].addTo(s, 4, 10.0);  // 10 urad
  EXPECT_DOUBLE_EQ(s.motion[static_cast<std::size_t>(latheChainIndex(1))].rotation_rad.y(), 1e-5);
}


// What turned parts tell of the 24 errors. With one tool, the notes' Px and Pz at centre
// height (Wy = 0, x and z following W) reduce to: Px = [a constant combination] - ey4 Wz,
// Pz = [a constant combination] + (ey4 - ey1) Wx, since every other lever (c4 + Wz - z -
// c1 = c2 + c3 + Tz, a4 + Wx - a1 - a2 - x = a3 + Tx, ...) is fixed by the tool. Diameters
// and faces anywhere on the part therefore identify 4 combinations: the two constants, ey4
// (Px's slope along Wz) and ey1 (Pz's slope along Wx, given ey4); the translations along X
// of the four bodies only as their sum dx1 + dx2 + dx3 - dx4.
TEST(LatheChain, TurnedDiametersAndFacesIdentifyFourCombinationsOfTheTwentyFour) {
  const LatheOffsets off = latheDefaultOffsets();
  const Vector3d T(-150, 0, -100);
  const KinematicChain chain = latheChain(off, T);
  auto observe = [&](const ChainState& s) {
    Eigen::VectorXd v(18);
    int k = 0;
    for (double wx : {15.0, 25.0, 40.0})
      for (double wz : {20.0, 80.0, 140.0}) {
        const Vector3d W(wx, 0, wz);
        const Eigen::Vector2d xz = latheNominalXZ(off, T, W);
        ChainState at = s;
        at.positions = {{"X", xz.x()}, {"Z", xz.y()}};
        const Vector3d cut = workpieceFrame(chain, at).inverse() * toolTip(chain, at);
        v(k++) = 2 * (std::hypot(cut.x(), cut.y()) - wx);
        v(k++) = cut.z() - wz;
      }
    return v;
  };
  const auto params = latheParameters();
  std::vector<std::string> names;
  for (const auto& p : params) names.push_back(p.name);
  const Eigen::MatrixXd J = chainSensitivity(observe, ChainState{}, params, chain.bodyCount());
  const Identifiability id = identifiability(J, names, 1e-9);
  EXPECT_EQ(id.rank, 4);
  // the slopes give ey4 (Px along Wz) and then ey1 (Pz along Wx); nothing else alone
  for (int i = 0; i < 24; ++i)
    EXPECT_EQ(id.identifiable[static_cast<std::size_t>(i)], names[static_cast<std::size_t>(i)] == "ey1" || names[static_cast<std::size_t>(i)] == "ey4")
        << names[static_cast<std::size_t>(i)];
  // dx1 + dx2 + dx3 - dx4: moving dx1 up and dx2 down by as much changes nothing
  ChainState s;
  params[0].addTo(s, 4, 5.0);
  params[6].addTo(s, 4, -5.0);
  EXPECT_LT(observe(s).cwiseAbs().maxCoeff(), 1e-12);
}

}  // namespace
}  // namespace probeloop::geometry
