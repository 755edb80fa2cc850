// fitLeastSquares against the project's generated reference data (reference_data.hpp): the
// least-squares solution of every set is known by construction, so the fit is compared with
// it the ISO 10360-6 way. One test per set, named after it (LsReference/.../<set name>).
//
// Comparisons, per kind (g = centroid of the data):
//   location  circle2d, circle3d, sphere: distance between the centres.
//             line2d, line3d, cylinder, cone: distance between the feet of g on the fitted
//             and on the reference axis (ISO 10360-6: axes compared after projecting the
//             data centroid onto each).
//             plane: distance of the reference point (foot of g on the reference plane)
//             from the fitted plane.
//   orientation  atan2(|n x n_ref|, |n . n_ref|) for lines, planes, circle3d and cylinders
//             (their direction's sign is a convention); atan2(|n x n_ref|, n . n_ref) for
//             the cone, whose direction points toward increasing radius. None for circle2d
//             and sphere.
//   size      radius (circles, sphere, cylinder); cone: radius at a common axis point (the
//             foot of g on the reference axis; on the fitted axis the point nearest to it)
//             and the half angle (an angle, held to the angle targets).
//   SSR       sum of squared signedDistance of the points from the fitted element, computed
//             here (centred on g so 1000 mm coordinates keep their digits), and the fit's own
//             ssr_mm2, against the constructed reference_ssr_mm2: relative 1e-9.
// Targets: well-conditioned sets 0.01 um and 0.01 urad; every set 0.1 um and 0.1 urad.
// A per-kind summary of the largest deviations is printed after the run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "geometry/least_squares.hpp"
#include "geometry/reference_data.hpp"

using namespace probeloop::geometry;
using Eigen::Vector3d;

namespace probeloop::geometry {
// gtest prints a failing test's parameter; the name is enough. Internal linkage: other test
// files may print sets their own way.
[[maybe_unused]] static void PrintTo(const ReferenceDataSet& set, std::ostream* os) {
  *os << set.name;
}
}  // namespace probeloop::geometry

namespace {

constexpr double kLocationWellMm = 1e-5;  // 0.01 um
constexpr double kAngleWellRad = 1e-8;    // 0.01 urad
constexpr double kLocationAllMm = 1e-4;   // 0.1 um
constexpr double kAngleAllRad = 1e-7;     // 0.1 urad
constexpr double kSsrRelative = 1e-9;
constexpr double kSsrFloorMm2 = 1e-18;  // exact fits: (1 nm)^2, ~1e6 x rounding

struct Deviation {
  double location_mm = 0.0;
  double orientation_rad = 0.0;
  double size_mm = 0.0;
  double half_angle_rad = 0.0;  // cone only
  double ssr_relative = 0.0;    // |ssr - ssr_ref| / (ssr_ref + floor / relative target)
};

Vector3d centroid(const Points3& p) {
  Vector3d g = Vector3d::Zero();
  for (const auto& x : p) g += x;
  return g / static_cast<double>(p.size());
}

Vector3d footOnAxis(const Element& e, const Vector3d& q) {
  return e.position_mm + e.direction * e.direction.dot(q - e.position_mm);
}

double orientation(const Vector3d& n, const Vector3d& ref, bool signed_direction) {
  const double dot = n.dot(ref);
  return std::atan2(n.cross(ref).norm(), signed_direction ? dot : std::abs(dot));
}

// Sum of squared signedDistance, with the points and the element moved to the centroid
// (distances are translation invariant; the subtraction then loses no digits).
double ssrCentred(Element e, const Points3& points, const Vector3d& g) {
  e.position_mm -= g;
  double s = 0.0;
  for (const auto& p : points) {
    const double d = signedDistance(e, p - g);
    s += d * d;
  }
  return s;
}

Deviation compare(const Element& fit, const Element& ref, const Points3& points) {
  Deviation dev;
  Vector3d g = centroid(points);
  const ElementKind kind = ref.kind;
  if (kind == ElementKind::Line2D || kind == ElementKind::Circle2D) g.z() = 0.0;
  switch (kind) {
    case ElementKind::Circle2D:
    case ElementKind::Circle3D:
    case ElementKind::Sphere:
      dev.location_mm = (fit.position_mm - ref.position_mm).norm();
      dev.size_mm = std::abs(fit.radius_mm - ref.radius_mm);
      break;
    case ElementKind::Plane: {
      const Vector3d ref_point = g - ref.direction * ref.direction.dot(g - ref.position_mm);
      dev.location_mm = std::abs(fit.direction.dot(ref_point - fit.position_mm));
      break;
    }
    case ElementKind::Line2D:
    case ElementKind::Line3D:
    case ElementKind::Cylinder:
    case ElementKind::Cone: {
      const Vector3d ref_foot = footOnAxis(ref, g);
      dev.location_mm = (footOnAxis(fit, g) - ref_foot).norm();
      if (kind == ElementKind::Cylinder) dev.size_mm = std::abs(fit.radius_mm - ref.radius_mm);
      if (kind == ElementKind::Cone) {
        const double r_ref = ref.radius_mm + ref.direction.dot(ref_foot - ref.position_mm) *
                                                 std::tan(ref.half_angle_rad);
        const double r_fit = fit.radius_mm + fit.direction.dot(ref_foot - fit.position_mm) *
                                                 std::tan(fit.half_angle_rad);
        dev.size_mm = std::abs(r_fit - r_ref);
        dev.half_angle_rad = std::abs(fit.half_angle_rad - ref.half_angle_rad);
      }
      break;
    }
  }
  if (kind != ElementKind::Circle2D && kind != ElementKind::Sphere)
    dev.orientation_rad = orientation(fit.direction, ref.direction, kind == ElementKind::Cone);
  return dev;
}

// Largest deviations per kind, well-conditioned sets and all sets, printed at the end.
struct Row {
  Deviation well, all;
  int n_well = 0, n_all = 0;
};
std::map<ElementKind, Row>& summary() {
  static std::map<ElementKind, Row> rows;
  return rows;
}
void fold(Deviation& into, const Deviation& d) {
  into.location_mm = std::max(into.location_mm, d.location_mm);
  into.orientation_rad = std::max(into.orientation_rad, d.orientation_rad);
  into.size_mm = std::max(into.size_mm, d.size_mm);
  into.half_angle_rad = std::max(into.half_angle_rad, d.half_angle_rad);
  into.ssr_relative = std::max(into.ssr_relative, d.ssr_relative);
}

class SummaryPrinter : public ::testing::Environment {
 public:
  void TearDown() override {
    if (summary().empty()) return;
    std::printf(
        "\nLS vs generated reference data: largest deviations per kind (um, urad, relative SSR)\n"
        "%-9s %-5s %4s %10s %10s %10s %10s %10s\n",
        "kind", "sets", "n", "location", "orient", "size", "halfangle", "ssr_rel");
    for (const auto& [kind, row] : summary()) {
      for (int well = 1; well >= 0; --well) {
        const Deviation& d = well ? row.well : row.all;
        const int n = well ? row.n_well : row.n_all;
        if (n == 0) continue;
        std::printf("%-9s %-5s %4d %10.2e %10.2e %10.2e %10.2e %10.2e\n",
                    std::string(elementName(kind)).c_str(), well ? "well" : "all", n,
                    d.location_mm * 1e3, d.orientation_rad * 1e6, d.size_mm * 1e3,
                    d.half_angle_rad * 1e6, d.ssr_relative);
      }
    }
    std::fflush(stdout);
  }
};
[[maybe_unused]] ::testing::Environment* const kSummary =
    ::testing::AddGlobalTestEnvironment(new SummaryPrinter);

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

std::string testName(const ::testing::TestParamInfo<ReferenceDataSet>& info) {
  std::string s = info.param.name;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

class LsReferenceSet : public ::testing::TestWithParam<ReferenceDataSet> {};

}  // namespace

TEST_P(LsReferenceSet, MatchesConstruction) {
  const ReferenceDataSet& set = GetParam();
  const Element& ref = set.reference;
  const FitResult fit = fitLeastSquares(ref.kind, set.points);
  ASSERT_EQ(fit.element.kind, ref.kind);
  ASSERT_EQ(fit.residuals_mm.size(), set.points.size());

  Deviation dev = compare(fit.element, ref, set.points);
  const double ssr = ssrCentred(fit.element, set.points, centroid(set.points));
  // Relative, with the exact-fit floor folded in: "<= kSsrRelative" is the whole criterion.
  const double ssr_scale = set.reference_ssr_mm2 + kSsrFloorMm2 / kSsrRelative;
  dev.ssr_relative = std::max(std::abs(ssr - set.reference_ssr_mm2),
                              std::abs(fit.ssr_mm2 - set.reference_ssr_mm2)) /
                     ssr_scale;

  const double location_target = set.well_conditioned ? kLocationWellMm : kLocationAllMm;
  const double angle_target = set.well_conditioned ? kAngleWellRad : kAngleAllRad;
  EXPECT_LE(dev.location_mm, location_target) << set.name << ": location";
  EXPECT_LE(dev.orientation_rad, angle_target) << set.name << ": orientation";
  EXPECT_LE(dev.size_mm, location_target) << set.name << ": size";
  EXPECT_LE(dev.half_angle_rad, angle_target) << set.name << ": half angle";
  EXPECT_LE(std::abs(ssr - set.reference_ssr_mm2),
            kSsrRelative * set.reference_ssr_mm2 + kSsrFloorMm2)
      << set.name << ": SSR of the fitted element " << ssr << " vs reference "
      << set.reference_ssr_mm2;
  EXPECT_LE(std::abs(fit.ssr_mm2 - set.reference_ssr_mm2),
            kSsrRelative * set.reference_ssr_mm2 + kSsrFloorMm2)
      << set.name << ": FitResult::ssr_mm2 " << fit.ssr_mm2 << " vs reference "
      << set.reference_ssr_mm2;

  RecordProperty("location_um", sci(dev.location_mm * 1e3));
  RecordProperty("orientation_urad", sci(dev.orientation_rad * 1e6));
  RecordProperty("size_um", sci(dev.size_mm * 1e3));
  RecordProperty("half_angle_urad", sci(dev.half_angle_rad * 1e6));
  RecordProperty("ssr_relative", sci(dev.ssr_relative));
  Row& row = summary()[ref.kind];
  fold(row.all, dev);
  ++row.n_all;
  if (set.well_conditioned) {
    fold(row.well, dev);
    ++row.n_well;
  }
}

INSTANTIATE_TEST_SUITE_P(LsReference, LsReferenceSet, ::testing::ValuesIn(referenceSuite()),
                         testName);
