// The shipped descriptions load, and every kind of bad input names file, line and key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"

using namespace probeloop;
using namespace probeloop::parts;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;

std::string writeTemp(const std::string& name, const std::string& text) {
  // One file per test: ctest runs tests of this binary in parallel processes.
  const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const auto p = std::filesystem::temp_directory_path() / ("probeloop_" + test + "_" + name);
  std::ofstream(p) << text;
  return p.string();
}

// Loads a modified copy of the shipped artifact and returns the error message.
std::string artifactError(const std::string& from, const std::string& to) {
  std::ifstream in(src + "/parts/sphere_artifact.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  text.replace(pos, from.size(), to);
  const auto path = writeTemp("artifact.yaml", text);
  try {
    loadSphereArtifact(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(SphereArtifact, ShippedDefaultsFollowTheThesis) {
  const auto a = loadSphereArtifact(src + "/parts/sphere_artifact.yaml");
  EXPECT_DOUBLE_EQ(a.radius_from_axis_mm, 160.0);
  EXPECT_EQ(a.c_positions_deg, (std::vector<double>{0, 90, 180, 270, 360}));
  EXPECT_EQ(a.pointsPerPosition(), 5);
  EXPECT_DOUBLE_EQ(a.probing_feed_mm_per_min, 200.0);
  EXPECT_DOUBLE_EQ(a.gap_s, 300.0);
}

TEST(SphereArtifact, UnknownKeyNamesLineAndAllowedKeys) {
  const auto m = artifactError("  approach: 3 mm", "  approach: 3 mm\n  aproach: 3 mm");
  EXPECT_NE(m.find("artifact.yaml:19: unknown key 'probing.aproach'"), std::string::npos) << m;
  EXPECT_NE(m.find("allowed here:"), std::string::npos) << m;
}

TEST(SphereArtifact, MissingKeyIsNamed) {
  const auto m = artifactError("  feed: 200 mm/min         # seed 004 L2145\n", "");
  EXPECT_NE(m.find("missing key 'probing.feed'"), std::string::npos) << m;
}

TEST(SphereArtifact, WrongUnitIsNamedWithLine) {
  const auto m = artifactError("radius_from_c_axis: 160 mm", "radius_from_c_axis: 160 s");
  EXPECT_NE(m.find(":10: placement.radius_from_c_axis: unit 's'"), std::string::npos) << m;
}

TEST(SphereArtifact, CountAndDurationAreExclusive) {
  const auto m = artifactError("  count: 12", "  count: 12\n  duration: 72 h");
  EXPECT_NE(m.find("exactly one of"), std::string::npos) << m;
}

TEST(SphereArtifact, NanIsRejected) {
  const auto m = artifactError("diameter: 30 mm", "diameter: .nan");
  EXPECT_NE(m.find("sphere.diameter"), std::string::npos) << m;
}

// cycles.live_interval: absent is false (the fixed gap); a value that is not a bool is refused
// with its line and field.
TEST(SphereArtifact, LiveIntervalIsAnOptionalBool) {
  EXPECT_FALSE(loadSphereArtifact(src + "/parts/sphere_artifact.yaml").live_interval);
  std::ifstream in(src + "/parts/sphere_artifact.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::string key = "  tool_change_each_cycle: true\n";
  ASSERT_NE(text.find(key), std::string::npos);
  text.replace(text.find(key), key.size(), key + "  live_interval: true\n");
  const auto a = loadSphereArtifact(writeTemp("live.yaml", text));
  EXPECT_TRUE(a.live_interval);
  EXPECT_DOUBLE_EQ(a.gap_s, 300.0);  // still read: the nominal schedule
  const auto m = artifactError("  tool_change_each_cycle: true", "  tool_change_each_cycle: true\n  live_interval: 5 min");
  EXPECT_NE(m.find("artifact.yaml:25: cycles.live_interval: expected true or false"), std::string::npos) << m;
}

TEST(Machine, ShippedMachinesLoad) {
  const auto m = loadMachine(src + "/parts/machines/nmv5000.yaml");
  EXPECT_EQ(m.dialect, Dialect::FanucMacroB);
  EXPECT_DOUBLE_EQ(m.x.max_mm - m.x.min_mm, 730.0);
  EXPECT_DOUBLE_EQ(m.y.max_mm - m.y.min_mm, 510.0);
  EXPECT_DOUBLE_EQ(m.z.max_mm - m.z.min_mm, 510.0);
  EXPECT_DOUBLE_EQ(m.x.resolution_mm, 0.001);
  EXPECT_TRUE(m.c.positive_is_clockwise);
  EXPECT_EQ(m.work_offset, 6);
  const auto l = loadMachine(src + "/parts/machines/linuxcnc_rotary_mill.yaml");
  EXPECT_EQ(l.dialect, Dialect::LinuxCnc);
  EXPECT_FALSE(l.b.present);
}

TEST(Machine, YamlSyntaxErrorHasLine) {
  const auto p = writeTemp("bad.yaml", "kind: machine\nname: [unclosed\n");
  try {
    loadMachine(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos) << e.what();
  }
}

// Issue 28: yaml-cpp keeps both entries of a key written twice and returns the first; a
// hand-edited `diameter: 3000 mm` below `diameter: 30 mm` was silently ignored.
TEST(SphereArtifact, AKeyWrittenTwiceIsRefusedWithBothLines) {
  const auto m = artifactError("  diameter: 30 mm", "  diameter: 30 mm\n  diameter: 3000 mm");
  EXPECT_NE(m.find("artifact.yaml:6: key 'diameter' is written twice (lines 5 and 6)"), std::string::npos) << m;
  // At the top level too.
  const auto top = artifactError("kind: sphere_artifact", "kind: sphere_artifact\nkind: sphere_artifact");
  EXPECT_NE(top.find("key 'kind' is written twice (lines 3 and 4)"), std::string::npos) << top;
}

TEST(Machine, AnAliasUsedAsAKeyNamesTheFile) {
  // yaml-cpp marks an alias with the line of the node it names (2), not of its use (3).
  const auto p = writeTemp("alias.yaml", "kind: machine\nbase: &b {x: 1}\n*b : 2\n");
  try {
    loadMachine(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("alias.yaml:2: a key must be a plain name; found a mapping"), std::string::npos)
        << e.what();
  }
  // An alias bomb (each level doubles the last) is refused, not walked for ever.
  std::string bomb = "kind: machine\na0: &a0 [x, x]\n";
  for (int i = 1; i < 40; ++i)
    bomb += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) + ", *a" +
            std::to_string(i - 1) + "]\n";
  const auto q = writeTemp("bomb.yaml", bomb);
  try {
    loadMachine(q);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("expands to more than 1000000 nodes"), std::string::npos) << e.what();
  }
}

TEST(Machine, AFileOfAnotherKindIsNamedWhenItIsNotYaml) {
  const auto p = writeTemp("plan.yaml", "<?xml version=\"1.0\"?>\n<QIFDocument>\n  <a>: b\n  c: [</a>\n</QIFDocument>\n");
  try {
    loadMachine(p);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("looks like a QIF (XML) document, not YAML"), std::string::npos) << e.what();
  }
}
