// fitLeastSquares against NIST's least-squares reference pairs (ASME B89.4.10 default test,
// /work/shared/refdata/README.md): for every .ds/.fit pair of Plane, Sphere, Cylinder and
// Cone, fit the .ds points and compare with the .fit element the ISO 10360-6 way. One test
// per pair, named <Kind>_<file>, e.g. NistLeastSquares/NistFit.AgreesWithReference/Cylinder_cyl7.
//
// Data: ${PROBELOOP_SOURCE_DIR}/../shared/refdata/nist-ls, or the folder named by the
// environment variable PROBELOOP_NIST_LS. The data are not part of the project: when the
// folder is absent the test skips with a message.
//
// Comparisons (as in ls_reference_test.cpp; g = centroid of the data): location = distance
// between centres (sphere), between the feet of g on the two axes (cylinder, cone), of the
// reference point (foot of g) from the fitted plane (plane); orientation =
// atan2(|n x n_ref|, |n . n_ref|), signed dot for the cone; size = radius, and for the cone
// the radius at a common axis point plus the half angle; SSR = sum of squared
// signedDistance of the points from the fitted and from the .fit element, relative 1e-9.
// Targets for every set: 0.1 um location and size, 0.1 urad angles.
//
// The one exception, per set and never global: a sphere whose data cannot fix the
// parameters to 0.1 um in double precision — an SSR change of 1e-13 relative (the ~14
// digits the objective carries) is already reached only by a parameter change > 0.1 um
// along the weakest direction of the Jacobian — is accepted when its parameters miss the
// target but its SSR agrees with the reference to 1e-13 relative (the README: partial
// spheres "can differ by ~1e-7 mm while the objective agrees to ~14 digits"). The test says
// so in its output, and the summary counts such sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "geometry/least_squares.hpp"

#ifndef PROBELOOP_SOURCE_DIR
#define PROBELOOP_SOURCE_DIR "."
#endif

using namespace probeloop;
using namespace probeloop::geometry;
using Eigen::Vector3d;
namespace fs = std::filesystem;

namespace {

constexpr double kLocationMm = 1e-4;  // 0.1 um
constexpr double kAngleRad = 1e-7;    // 0.1 urad
constexpr double kSsrRelative = 1e-9;
// Exact fits (4-point sphere, 6-point cone) have SSR ~ 0: (1 nm)^2 absolute, ~1e6 x rounding.
constexpr double kSsrFloorMm2 = 1e-18;
// Ill-conditioned spheres (see the file comment).
constexpr double kSsrDigitsRelative = 1e-13;
constexpr double kPi = 3.141592653589793238462643383279502884;

struct KindFolder {
  const char* folder;
  ElementKind kind;
  int fit_numbers;
  const char* fit_layout;
};
constexpr KindFolder kFolders[] = {
    {"Plane", ElementKind::Plane, 6, "point (3), unit normal (3)"},
    {"Sphere", ElementKind::Sphere, 4, "centre (3), diameter"},
    {"Cylinder", ElementKind::Cylinder, 7, "point on the axis (3), direction (3), diameter"},
    {"Cone", ElementKind::Cone, 8,
     "point on the axis (3), direction toward increasing radius (3), orthogonal distance "
     "from the point to the surface, full apex angle in degrees"},
};

struct NistCase {
  std::string name;  // test name: <Kind>_<stem>, or a placeholder
  const KindFolder* folder = nullptr;
  fs::path ds, fit;
  std::string problem;  // non-empty: nothing to fit; skip (absent data) or fail
  bool skip = false;
};

fs::path nistDirectory() {
  if (const char* env = std::getenv("PROBELOOP_NIST_LS"); env != nullptr && *env != '\0')
    return env;
  return fs::path(PROBELOOP_SOURCE_DIR) / ".." / "shared" / "refdata" / "nist-ls";
}

// "cyl12" -> 12, so the sets run in NIST's order (cyl2 before cyl10).
long numberSuffix(const std::string& stem) {
  size_t i = stem.size();
  while (i > 0 && std::isdigit(static_cast<unsigned char>(stem[i - 1]))) --i;
  return i < stem.size() ? std::stol(stem.substr(i)) : -1;
}

std::vector<NistCase> discoverCases() {
  const fs::path root = nistDirectory();
  std::error_code ec;
  if (!fs::is_directory(root, ec)) {
    NistCase c;
    c.name = "DataAbsent";
    c.skip = true;
    c.problem = "NIST least-squares reference data not found at " + root.string() +
                " (set PROBELOOP_NIST_LS to the folder holding Plane/, Sphere/, Cylinder/, Cone/)";
    return {c};
  }
  std::vector<NistCase> cases;
  for (const KindFolder& k : kFolders) {
    const fs::path dir = root / k.folder;
    if (!fs::is_directory(dir, ec)) continue;
    std::vector<NistCase> here;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      const fs::path p = entry.path();
      const std::string ext = p.extension().string();
      if (ext != ".ds" && ext != ".fit") continue;
      const fs::path other = fs::path(p).replace_extension(ext == ".ds" ? ".fit" : ".ds");
      if (ext == ".fit" && fs::exists(other)) continue;  // listed with its .ds
      NistCase c;
      c.folder = &k;
      c.name = std::string(k.folder) + "_" + p.stem().string();
      c.ds = ext == ".ds" ? p : other;
      c.fit = ext == ".fit" ? p : other;
      if (!fs::exists(other))
        c.problem = p.string() + " has no matching " + other.filename().string();
      here.push_back(c);
    }
    std::sort(here.begin(), here.end(), [](const NistCase& a, const NistCase& b) {
      const long na = numberSuffix(a.ds.stem().string());
      const long nb = numberSuffix(b.ds.stem().string());
      return na != nb ? na < nb : a.name < b.name;
    });
    cases.insert(cases.end(), here.begin(), here.end());
  }
  for (NistCase& c : cases)
    for (char& ch : c.name)
      if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  if (cases.empty()) {
    NistCase c;
    c.name = "NoDataSets";
    c.problem = root.string() +
                " exists but holds no .ds/.fit pair in Plane/, Sphere/, "
                "Cylinder/ or Cone/";
    cases.push_back(c);
  }
  return cases;
}

// Non-blank lines with their 1-based numbers, whitespace-split (the files use tabs).
std::vector<std::pair<int, std::vector<std::string>>> tokenLines(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string(), 0, "cannot open the file");
  std::vector<std::pair<int, std::vector<std::string>>> out;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (!tokens.empty()) out.emplace_back(number, std::move(tokens));
  }
  return out;
}

double number(const fs::path& path, int line, const std::string& text, const char* what) {
  double v = 0.0;
  if (!parseFiniteNumber(text, v))
    throw InputError(
        path.string(), line,
        std::string("expected a finite number (") + what + "), found \"" + text + "\"");
  return v;
}

// .ds: first line N, then N lines "x y z".
Points3 readDataSet(const fs::path& path) {
  const auto lines = tokenLines(path);
  if (lines.empty())
    throw InputError(path.string(), 0, "empty file; expected N then N lines x y z");
  const auto& [head_line, head] = lines.front();
  double count = 0.0;
  if (head.size() != 1 || !parseFiniteNumber(head[0], count) || count < 1 ||
      count != std::floor(count))
    throw InputError(path.string(), head_line,
                     "expected the number of points N (a positive integer) alone on the first "
                     "line, found \"" +
                         head[0] + (head.size() > 1 ? " ..." : "") + "\"");
  const size_t n = static_cast<size_t>(count);
  if (lines.size() - 1 != n)
    throw InputError(path.string(), 0,
                     "the first line announces " + std::to_string(n) + " points but " +
                         std::to_string(lines.size() - 1) + " point lines follow");
  Points3 points;
  points.reserve(n);
  for (size_t i = 1; i < lines.size(); ++i) {
    const auto& [line, t] = lines[i];
    if (t.size() != 3)
      throw InputError(path.string(), line,
                       "expected 3 numbers \"x y z\", found " + std::to_string(t.size()));
    points.emplace_back(number(path, line, t[0], "x"), number(path, line, t[1], "y"),
                        number(path, line, t[2], "z"));
  }
  return points;
}

// .fit: one number per line, the reference element in NIST's layout for the kind.
Element readFit(const fs::path& path, const KindFolder& k) {
  const auto lines = tokenLines(path);
  if (static_cast<int>(lines.size()) != k.fit_numbers)
    throw InputError(path.string(), 0,
                     "expected " + std::to_string(k.fit_numbers) + " numbers, one a line (" +
                         k.fit_layout + "), found " + std::to_string(lines.size()) + " lines");
  std::vector<double> v;
  for (const auto& [line, t] : lines) {
    if (t.size() != 1)
      throw InputError(
          path.string(), line,
          "expected one number on the line, found " + std::to_string(t.size()) + " fields");
    v.push_back(number(path, line, t[0], k.fit_layout));
  }
  Element e;
  e.kind = k.kind;
  e.position_mm = Vector3d(v[0], v[1], v[2]);
  if (k.kind == ElementKind::Sphere) {
    if (!(v[3] > 0.0)) throw InputError(path.string(), lines[3].first, "diameter must be > 0");
    e.radius_mm = 0.5 * v[3];
    return e;
  }
  const Vector3d d(v[3], v[4], v[5]);
  if (!(d.norm() > 0.0))
    throw InputError(path.string(), lines[3].first, "direction (lines 4-6) is zero");
  e.direction = d.normalized();
  if (k.kind == ElementKind::Cylinder) {
    if (!(v[6] > 0.0)) throw InputError(path.string(), lines[6].first, "diameter must be > 0");
    e.radius_mm = 0.5 * v[6];
  } else if (k.kind == ElementKind::Cone) {
    const double apex_deg = v[7];
    if (!(apex_deg > 0.0 && apex_deg < 180.0))
      throw InputError(
          path.string(), lines[7].first,
          "full apex angle must be in (0, 180) degrees, found " + std::to_string(apex_deg));
    // NIST gives the orthogonal distance d from the axis point to the surface; the radius
    // there, perpendicular to the axis, is d / cos(a).
    e.half_angle_rad = 0.5 * apex_deg * kPi / 180.0;
    e.radius_mm = v[6] / std::cos(e.half_angle_rad);
  }
  return e;
}

Vector3d centroid(const Points3& p) {
  Vector3d g = Vector3d::Zero();
  for (const auto& x : p) g += x;
  return g / static_cast<double>(p.size());
}

Vector3d footOnAxis(const Element& e, const Vector3d& q) {
  return e.position_mm + e.direction * e.direction.dot(q - e.position_mm);
}

// Sum of squared signedDistance, points and element moved to the centroid g (translation
// invariant; keeps the digits 1000 mm coordinates would cost).
double ssrCentred(Element e, const Points3& points, const Vector3d& g) {
  e.position_mm -= g;
  double s = 0.0;
  for (const auto& p : points) {
    const double d = signedDistance(e, p - g);
    s += d * d;
  }
  return s;
}

struct Deviation {
  double location_mm = 0.0;
  double orientation_rad = 0.0;
  double size_mm = 0.0;
  double half_angle_rad = 0.0;
  double ssr_fit_mm2 = 0.0;
  double ssr_ref_mm2 = 0.0;
  // |ssr_fit - ssr_ref| / (ssr_ref + kSsrFloorMm2 / kSsrRelative): relative, with the
  // absolute floor folded in, so "<= kSsrRelative" is the whole SSR criterion.
  double ssr_relative = 0.0;
};

Deviation compare(const Element& fit, const Element& ref, const Points3& points) {
  Deviation dev;
  const Vector3d g = centroid(points);
  switch (ref.kind) {
    case ElementKind::Sphere:
      dev.location_mm = (fit.position_mm - ref.position_mm).norm();
      dev.size_mm = std::abs(fit.radius_mm - ref.radius_mm);
      break;
    case ElementKind::Plane: {
      const Vector3d ref_point = g - ref.direction * ref.direction.dot(g - ref.position_mm);
      dev.location_mm = std::abs(fit.direction.dot(ref_point - fit.position_mm));
      break;
    }
    default: {  // cylinder, cone
      const Vector3d ref_foot = footOnAxis(ref, g);
      dev.location_mm = (footOnAxis(fit, g) - ref_foot).norm();
      if (ref.kind == ElementKind::Cylinder) {
        dev.size_mm = std::abs(fit.radius_mm - ref.radius_mm);
      } else {
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
  if (ref.kind != ElementKind::Sphere) {
    const double dot = fit.direction.dot(ref.direction);
    dev.orientation_rad = std::atan2(fit.direction.cross(ref.direction).norm(),
                                     ref.kind == ElementKind::Cone ? dot : std::abs(dot));
  }
  dev.ssr_ref_mm2 = ssrCentred(ref, points, g);
  dev.ssr_fit_mm2 = ssrCentred(fit, points, g);
  dev.ssr_relative =
      std::abs(dev.ssr_fit_mm2 - dev.ssr_ref_mm2) / (dev.ssr_ref_mm2 + kSsrFloorMm2 / kSsrRelative);
  return dev;
}

// Parameter change along the weakest direction of the sphere Jacobian [u_i, 1] that moves
// the SSR by kSsrDigitsRelative of itself: (sigma_min delta)^2 = 1e-13 ssr. Larger than
// the 0.1 um target means double precision cannot pin this sphere's parameters to it.
double sphereIndeterminacyMm(const Element& ref, const Points3& points) {
  Eigen::MatrixXd J(static_cast<Eigen::Index>(points.size()), 4);
  double ssr = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const Vector3d v = points[i] - ref.position_mm;
    J.row(static_cast<Eigen::Index>(i)) << v.x() / v.norm(), v.y() / v.norm(), v.z() / v.norm(),
        1.0;
    const double d = v.norm() - ref.radius_mm;
    ssr += d * d;
  }
  const double sigma_min = Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues().minCoeff();
  return sigma_min > 0.0 ? std::sqrt(kSsrDigitsRelative * ssr) / sigma_min : INFINITY;
}

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

// Largest deviation relative to its target: which set is worst for the kind.
double targetRatio(const Deviation& d) {
  return std::max({d.location_mm / kLocationMm, d.size_mm / kLocationMm,
                   d.orientation_rad / kAngleRad, d.half_angle_rad / kAngleRad});
}

struct Row {
  Deviation max;  // sets accepted on SSR excluded from the parameter columns
  int sets = 0;
  int ill_conditioned = 0;  // spheres meeting the indeterminacy criterion
  int accepted_on_ssr = 0;
  std::string worst_parameters, worst_ssr;
  double worst_ratio = -1.0;
};
std::map<ElementKind, Row>& summary() {
  static std::map<ElementKind, Row> rows;
  return rows;
}

class SummaryPrinter : public ::testing::Environment {
 public:
  void TearDown() override {
    if (summary().empty()) return;
    std::printf(
        "\nLS vs NIST reference fits: largest deviations per kind (um, urad, relative SSR;"
        " targets 0.1 um, 0.1 urad, 1e-9)\n"
        "%-9s %4s %10s %10s %10s %10s %10s %-12s %-12s %s\n",
        "kind", "sets", "location", "orient", "size", "halfangle", "ssr_rel", "worst", "worst_ssr",
        "ill-cond/accepted-on-SSR");
    for (const auto& [kind, row] : summary())
      std::printf("%-9s %4d %10.2e %10.2e %10.2e %10.2e %10.2e %-12s %-12s %d/%d\n",
                  std::string(elementName(kind)).c_str(), row.sets, row.max.location_mm * 1e3,
                  row.max.orientation_rad * 1e6, row.max.size_mm * 1e3,
                  row.max.half_angle_rad * 1e6, row.max.ssr_relative, row.worst_parameters.c_str(),
                  row.worst_ssr.c_str(), row.ill_conditioned, row.accepted_on_ssr);
    std::fflush(stdout);
  }
};
[[maybe_unused]] ::testing::Environment* const kSummary =
    ::testing::AddGlobalTestEnvironment(new SummaryPrinter);

void PrintTo(const NistCase& c, std::ostream* os) { *os << c.name; }

class NistFit : public ::testing::TestWithParam<NistCase> {};

}  // namespace

TEST_P(NistFit, AgreesWithReference) {
  const NistCase& c = GetParam();
  if (c.skip) GTEST_SKIP() << c.problem;
  ASSERT_TRUE(c.problem.empty()) << c.problem;
  const Points3 points = readDataSet(c.ds);
  const Element ref = readFit(c.fit, *c.folder);
  const FitResult fit = fitLeastSquares(ref.kind, points);
  ASSERT_EQ(fit.element.kind, ref.kind);
  const Deviation dev = compare(fit.element, ref, points);

  const bool parameters_ok = targetRatio(dev) <= 1.0;
  const bool ill_conditioned =
      ref.kind == ElementKind::Sphere && sphereIndeterminacyMm(ref, points) > kLocationMm;
  // Only an ill-conditioned sphere may be accepted on its SSR (see the file comment).
  const bool accepted_on_ssr =
      !parameters_ok && ill_conditioned && dev.ssr_relative <= kSsrDigitsRelative;
  if (accepted_on_ssr) {
    std::printf(
        "[ NOTE     ] %s: ill-conditioned sphere (an SSR change of 1e-13 relative allows "
        "%.2e um along the weakest direction); parameters differ (location %.3e um, "
        "radius %.3e um) but the SSR agrees to %.2e relative: ACCEPTED ON SSR\n",
        c.name.c_str(), sphereIndeterminacyMm(ref, points) * 1e3, dev.location_mm * 1e3,
        dev.size_mm * 1e3, dev.ssr_relative);
    RecordProperty(
        "accepted_on_ssr",
        "ill-conditioned sphere: parameters miss 0.1 um, SSR agrees to " + sci(dev.ssr_relative));
  } else {
    // n = p (4-point sphere, 6-point cone): the points may lie on several elements exactly,
    // so a different exact fit is possible; say so, the target still holds.
    const bool exact_fit = static_cast<int>(points.size()) == minimumPoints(ref.kind);
    const std::string hint = exact_fit
                                 ? " [exact-fit set, " + std::to_string(points.size()) +
                                       " points: SSR of the fit " + sci(dev.ssr_fit_mm2) +
                                       " mm^2, of the reference " + sci(dev.ssr_ref_mm2) + " mm^2]"
                                 : "";
    EXPECT_LE(dev.location_mm, kLocationMm) << c.name << ": location" << hint;
    EXPECT_LE(dev.orientation_rad, kAngleRad) << c.name << ": orientation" << hint;
    EXPECT_LE(dev.size_mm, kLocationMm) << c.name << ": size" << hint;
    EXPECT_LE(dev.half_angle_rad, kAngleRad) << c.name << ": half angle" << hint;
  }
  EXPECT_LE(dev.ssr_relative, kSsrRelative)
      << c.name << ": SSR of the fit " << dev.ssr_fit_mm2 << " mm^2, of the reference "
      << dev.ssr_ref_mm2 << " mm^2 (" << points.size() << " points)";

  RecordProperty("location_um", sci(dev.location_mm * 1e3));
  RecordProperty("orientation_urad", sci(dev.orientation_rad * 1e6));
  RecordProperty("size_um", sci(dev.size_mm * 1e3));
  RecordProperty("half_angle_urad", sci(dev.half_angle_rad * 1e6));
  RecordProperty("ssr_relative", sci(dev.ssr_relative));
  Row& row = summary()[ref.kind];
  ++row.sets;
  row.ill_conditioned += ill_conditioned ? 1 : 0;
  if (accepted_on_ssr) {
    ++row.accepted_on_ssr;  // its parameter deviations are in the NOTE line above
  } else {
    row.max.location_mm = std::max(row.max.location_mm, dev.location_mm);
    row.max.orientation_rad = std::max(row.max.orientation_rad, dev.orientation_rad);
    row.max.size_mm = std::max(row.max.size_mm, dev.size_mm);
    row.max.half_angle_rad = std::max(row.max.half_angle_rad, dev.half_angle_rad);
    if (targetRatio(dev) > row.worst_ratio) {
      row.worst_ratio = targetRatio(dev);
      row.worst_parameters = c.ds.stem().string();
    }
  }
  if (dev.ssr_relative >= row.max.ssr_relative) row.worst_ssr = c.ds.stem().string();
  row.max.ssr_relative = std::max(row.max.ssr_relative, dev.ssr_relative);
}

INSTANTIATE_TEST_SUITE_P(NistLeastSquares, NistFit, ::testing::ValuesIn(discoverCases()),
                         [](const ::testing::TestParamInfo<NistCase>& info) {
                           return info.param.name;
                         });
