// The point route's reading of an exchange file in which some features carry points and others
// only their measured geometry (issue 34): the latter are not used, said as warnings with their
// lines; a datum or reference feature without points is refused naming it, its line and why.
// The DMIS output is written here line by line, so every line number is known independently of
// the reader.
#include "evaluate/ttp_ingest.hpp"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>

#include "core/error.hpp"
#include "evaluate/ttp_test_support.hpp"

namespace probeloop::evaluate {
namespace {

using ttptest::Fixture;

struct Dmo {
  std::string text;
  std::map<std::string, int> line;  // feature -> the line of its FA(label)=FEAT/... statement
};

// Every planned feature's points (FEAT/POINT) and its measured geometry at the nominal one
// (FEAT/PLANE, FEAT/CYLNDR); `without` lose their points and keep their geometry.
Dmo dmisOutput(const Fixture& f, const std::set<std::string>& without) {
  Dmo d;
  int n = 0;
  auto put = [&](const std::string& s) {
    d.text += s + "\n";
    ++n;
  };
  put("FILNAM/'T',05.2");
  put("UNITS/MM,ANGDEC");
  std::map<std::string, int> k;
  for (const auto& p : ttptest::measure(f, {})) {
    if (without.count(p.feature)) continue;
    char b[200];
    std::snprintf(b, sizeof b, "FA(%s_P%02d)=FEAT/POINT,CART,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f", p.feature.c_str(), ++k[p.feature],
                  p.surface_mm.x(), p.surface_mm.y(), p.surface_mm.z(), p.outward.x(), p.outward.y(), p.outward.z());
    put(b);
  }
  for (const auto& mf : f.m.features) {
    const auto& x = mf.nominal;
    char b[240];
    if (x.kind == "cylinder")
      std::snprintf(b, sizeof b, "FA(%s)=FEAT/CYLNDR,OUTER,CART,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.6f", x.id.c_str(), x.point_mm.x(),
                    x.point_mm.y(), x.point_mm.z(), x.direction.x(), x.direction.y(), x.direction.z(), 2 * x.radius_mm);
    else
      std::snprintf(b, sizeof b, "FA(%s)=FEAT/PLANE,CART,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f", x.id.c_str(), x.point_mm.x(), x.point_mm.y(),
                    x.point_mm.z(), x.direction.x(), x.direction.y(), x.direction.z());
    put(b);
    d.line[x.id] = n;
  }
  put("ENDFIL");
  return d;
}

std::string refusal(const Fixture& f, const Dmo& d) {
  try {
    readTtpCmmExport("r.dmo", d.text, f.m);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(TtpCmmExport, EveryFeatureWithItsPointsReadsWithoutWarnings) {
  const auto f = ttptest::makeFixture();
  const auto pts = readTtpCmmExport("r.dmo", dmisOutput(f, {}).text, f.m);
  EXPECT_EQ(pts.points.size(), f.planned.size());
  EXPECT_TRUE(pts.warnings.empty());
}

TEST(TtpCmmExport, AFeatureStatedWithoutPointsIsAWarningWithItsLine) {
  const auto f = ttptest::makeFixture();
  const std::string z = ttptest::zId(f, 3);  // a cutting cycle's Z path: not needed by every value
  const auto d = dmisOutput(f, {z});
  const auto pts = readTtpCmmExport("r.dmo", d.text, f.m);
  ASSERT_EQ(pts.warnings.size(), 1u);
  const auto& w = pts.warnings[0];
  EXPECT_EQ(w.file, "r.dmo");
  EXPECT_EQ(w.line, d.line.at(z));
  EXPECT_FALSE(w.strict_refuses);
  EXPECT_EQ(w.what.rfind("feature " + z + " states its measured geometry but no points, while " +
                             std::to_string(f.m.features.size() - 1) + " features of the file carry points: not used; the point "
                             "route fits its own features from the points (a file of features only is evaluated from them, "
                             "docs/formats.md#evaluating-from-features)",
                         0),
            0u)
      << w.what;
  for (const auto& p : pts.points) EXPECT_NE(p.feature, z);
  // --strict keeps it a warning: the file's meaning is whole.
  EXPECT_EQ(readTtpCmmExport("r.dmo", d.text, f.m, true).warnings.size(), 1u);
}

TEST(TtpCmmExport, ADatumOrReferenceFeatureWithoutPointsIsRefusedWithItsLineAndWhy) {
  const auto f = ttptest::makeFixture();
  auto d = dmisOutput(f, {"CYL"});
  EXPECT_NE(refusal(f, d).find("r.dmo:" + std::to_string(d.line.at("CYL")) +
                               ": feature CYL states its measured geometry but no points, while " +
                               std::to_string(f.m.features.size() - 1) +
                               " features of the file carry points: the datum CYL needs its points (seed 004 L2055: the part frame)"),
            std::string::npos)
      << refusal(f, d);
  const std::string ref = ttptest::zId(f, 0);
  d = dmisOutput(f, {ref});
  EXPECT_NE(refusal(f, d).find("r.dmo:" + std::to_string(d.line.at(ref)) + ": feature " + ref +
                               " states its measured geometry but no points, while " + std::to_string(f.m.features.size() - 1) +
                               " features of the file carry points: the reference feature " + ref + " (cycle 0) needs its points"),
            std::string::npos)
      << refusal(f, d);
}

}  // namespace
}  // namespace probeloop::evaluate
