#include "evaluate/point_cloud.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::evaluate;
namespace fs = std::filesystem;

namespace {
std::string writeTemp(const std::string& name, const std::string& content) {
  const fs::path dir = fs::temp_directory_path() / ("probeloop-pc-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p, std::ios::binary) << content;
  return p.string();
}
std::string errorOf(const std::string& path, const std::string& format = "auto") {
  try {
    readPointCloud(path, format);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(PointCloud, CanonicalCsvWithApproachAndFeatureFilter) {
  const auto p = writeTemp("a.csv",
                           "# probe log\n"
                           "time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n"
                           "0,1,0,bore,1,10.5,0,3,1,0,0\n"
                           "1,1,0,top,1,0,0,8,0,0,-1\n"
                           "2,1,0,bore,2,0,10.5,3,0,1,0\n");
  const auto pc = readPointCloud(p, "auto", {"bore", ""});
  ASSERT_EQ(pc.points_mm.size(), 2u);
  EXPECT_EQ(pc.format, "csv");
  EXPECT_EQ(pc.points_mm[1], Eigen::Vector3d(0, 10.5, 3));
  EXPECT_EQ(pc.approach[1], Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(pc.source_lines[1], 5);
  // Two features in one cloud would fit one element to both: refused, naming them.
  try {
    readPointCloud(p);
    FAIL() << "a file of two features was fitted as one cloud";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 features (bore, top): choose one with --feature"), std::string::npos) << e.what();
  }
}

TEST(PointCloud, CampaignFileNeedsTheCycleAndTheFeatureNamed) {
  std::string text = "time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm\n";
  for (int cycle = 1; cycle <= 12; ++cycle)
    for (const char* f : {"S1", "S2"})
      for (int k = 0; k < 4; ++k)
        text += std::to_string(cycle * 100 + k) + "," + std::to_string(cycle) + ",0," + f + "," +
                std::to_string(k + 1) + "," + std::to_string(k) + "," + std::to_string(k * k) + ",1\n";
  const auto p = writeTemp("campaign.csv", text);
  auto message = [&](const PointSelection& s) {
    try {
      readPointCloud(p, "auto", s);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message({}).find("2 features (S1, S2): choose one with --feature NAME and one of its 12 cycles with --cycle N"),
            std::string::npos) << message({});
  EXPECT_NE(message({"S2", ""}).find("12 cycles (1, 2, 3 ... 12): choose one with --cycle N"), std::string::npos)
      << message({"S2", ""});
  EXPECT_NE(message({"S2", "13"}).find("no rows of cycle 13"), std::string::npos);
  EXPECT_NE(message({"S3", "2"}).find("no rows with feature 'S3'; the file's features: S1, S2"), std::string::npos);
  const auto pc = readPointCloud(p, "auto", {"S2", "7"});
  ASSERT_EQ(pc.points_mm.size(), 4u);
  EXPECT_EQ(pc.points_mm[3], Eigen::Vector3d(3, 9, 1));
  EXPECT_EQ(pc.source_lines[0], 2 + (7 - 1) * 8 + 4);  // header, six cycles of 8 rows, S1's 4
}

TEST(PointCloud, CsvErrorsNameFileLineAndField) {
  const auto p = writeTemp("b.csv", "x,y,z\n1,2,3\n1,nan,3\n");
  EXPECT_NE(errorOf(p).find("b.csv:3: field 'y'"), std::string::npos) << errorOf(p);
  const auto q = writeTemp("c.csv", "a,b,c\n1,2,3\n");
  EXPECT_NE(errorOf(q).find("x_mm,y_mm,z_mm"), std::string::npos) << errorOf(q);
  const auto r = writeTemp("d.csv", "x,y,z,nx,ny,nz\n1,2,3,0,0,2\n");
  EXPECT_NE(errorOf(r).find("unit vector"), std::string::npos) << errorOf(r);
}

TEST(PointCloud, NistDsCountIsChecked) {
  const auto ok = writeTemp("s.ds", "3\n1.00000 2.00000 3.00000\n4 5 6\n  7 8 9\n");
  const auto pc = readPointCloud(ok);
  ASSERT_EQ(pc.points_mm.size(), 3u);
  EXPECT_EQ(pc.points_mm[2], Eigen::Vector3d(7, 8, 9));
  const auto bad = writeTemp("t.ds", "4\n1 2 3\n4 5 6\n");
  EXPECT_NE(errorOf(bad).find("header says 4 points, the file has 2"), std::string::npos) << errorOf(bad);
}

TEST(PointCloud, XyzBlanksCommasCommentsAndExtraColumns) {
  const auto p = writeTemp("p.xyz", "# scan\n1 2 3 255 0 0\n4,5,6\n\n7\t8\t9 # tail\n");
  const auto pc = readPointCloud(p);
  ASSERT_EQ(pc.points_mm.size(), 3u);
  EXPECT_EQ(pc.points_mm[1], Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(pc.source_lines[2], 5);
  const auto bad = writeTemp("q.xyz", "1 2 3\n1 2\n");
  EXPECT_NE(errorOf(bad).find("q.xyz:2: expected 3 coordinates"), std::string::npos) << errorOf(bad);
}

TEST(PointCloud, PlyAsciiSkipsFacesAndOtherProperties) {
  const auto p = writeTemp("m.ply",
                           "ply\nformat ascii 1.0\ncomment made by hand\n"
                           "element vertex 3\nproperty float x\nproperty uchar red\n"
                           "property float y\nproperty float z\n"
                           "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                           "1 200 2 3\n4 0 5 6\n7 1 8 9\n3 0 1 2\n");
  const auto pc = readPointCloud(p);
  ASSERT_EQ(pc.points_mm.size(), 3u);
  EXPECT_EQ(pc.points_mm[2], Eigen::Vector3d(7, 8, 9));
}

TEST(PointCloud, PlyBinaryBothEndiannesses) {
  for (const bool big : {false, true}) {
    std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty float z\n"
                    "property list uchar int extra\nend_header\n";
    auto put = [&](const void* v, size_t n) {
      std::string b(static_cast<const char*>(v), n);
      if (big) std::reverse(b.begin(), b.end());
      s += b;
    };
    const double xs[2] = {1000.125, -3.5}, ys[2] = {2.25, 4.0};
    const float zs[2] = {0.5f, -7.0f};
    for (int i = 0; i < 2; ++i) {
      put(&xs[i], 8);
      put(&ys[i], 8);
      put(&zs[i], 4);
      const std::uint8_t n = 1;
      s.push_back(static_cast<char>(n));
      const std::int32_t v = 42;
      put(&v, 4);
    }
    const auto pc = readPointCloud(writeTemp(big ? "be.ply" : "le.ply", s));
    ASSERT_EQ(pc.points_mm.size(), 2u);
    EXPECT_EQ(pc.points_mm[0], Eigen::Vector3d(1000.125, 2.25, 0.5));
    EXPECT_EQ(pc.points_mm[1], Eigen::Vector3d(-3.5, 4.0, -7.0));
  }
}

TEST(PointCloud, PlyTruncatedAndMissingCoordinatesAreErrors) {
  const auto t = writeTemp("t.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
                                    "property double x\nproperty double y\nproperty double z\nend_header\n12345678");
  EXPECT_NE(errorOf(t).find("binary data ends"), std::string::npos) << errorOf(t);
  const auto m = writeTemp("m2.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n");
  EXPECT_NE(errorOf(m).find("x, y and z"), std::string::npos) << errorOf(m);
}

// Found by fuzz/ply_fuzz and fuzz/nist_ds_fuzz: counts converted to integers unchecked
// (undefined behaviour), a negative binary list count, a count of empty entries that never ends.
TEST(PointCloud, HostileCountsAreErrorsWithTheLine) {
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const auto huge = writeTemp("huge.ply", "ply\nformat ascii 1.0\nelement vertex 1e20\n" + xyz + "end_header\n0 0 0\n");
  EXPECT_NE(errorOf(huge).find("huge.ply:3: PLY: expected 'element <name> <count>' with a whole count"), std::string::npos)
      << errorOf(huge);
  const auto frac = writeTemp("frac.ply", "ply\nformat ascii 1.0\nelement vertex 1.5\n" + xyz + "end_header\n0 0 0\n");
  EXPECT_NE(errorOf(frac).find("frac.ply:3:"), std::string::npos) << errorOf(frac);
  const auto list = writeTemp("list.ply", "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz +
                                              "property list uchar int l\nend_header\n0 0 0 1e300 1\n");
  EXPECT_NE(errorOf(list).find("list.ply:9: PLY: element 'vertex' list 'l': count 1e300"), std::string::npos) << errorOf(list);
  const auto fcount = writeTemp("fcount.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + xyz +
                                                  "property list float int l\nend_header\n");
  EXPECT_NE(errorOf(fcount).find("fcount.ply:7: PLY: the count type of list 'l' must be an integer type"), std::string::npos)
      << errorOf(fcount);
  std::string neg = "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + xyz + "property list char float l\nend_header\n";
  neg += std::string(12, '\0') + "\xff" + std::string(16, '\0');
  EXPECT_NE(errorOf(writeTemp("neg.ply", neg)).find("list 'l': negative count -1"), std::string::npos);
  // 4e9 entries of nothing, and 2e9 vertices in 12 bytes: refused at once, not looped over.
  const auto empty = writeTemp("empty.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" + xyz +
                                                "element nothing 2147483647\nend_header\n" + std::string(12, '\0'));
  EXPECT_EQ(readPointCloud(empty, "ply").points_mm.size(), 1u);
  const auto many = writeTemp("many.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n" + xyz +
                                              "end_header\n" + std::string(12, '\0'));
  EXPECT_NE(errorOf(many).find("binary data ends inside element 'vertex': it declares 2000000000 entries of at least 12 bytes, 12 bytes are left"),
            std::string::npos) << errorOf(many);
  const auto ds = writeTemp("huge.ds", "1e300\n0 0 0\n");
  EXPECT_NE(errorOf(ds).find("huge.ds:1: NIST .ds: the first line must be the number of points"), std::string::npos)
      << errorOf(ds);
}

TEST(PointCloud, UnknownExtensionAsksForFormat) {
  const auto p = writeTemp("points.dat", "1 2 3\n");
  EXPECT_NE(errorOf(p).find("--format"), std::string::npos);
  EXPECT_EQ(readPointCloud(p, "xyz").points_mm.size(), 1u);
  const auto e = writeTemp("empty.xyz", "# nothing\n");
  EXPECT_NE(errorOf(e).find("no points"), std::string::npos);
}

// A QIF 3.0 Results file (issue 34): one feature's measured points by name, with the lenient
// reader's warning (a self-referencing point-set id) carried along; strict refuses it.
TEST(PointCloud, AQifFeatureByNameWithTheReadersWarnings) {
  const auto p = writeTemp("r.qif", R"(<?xml version="1.0"?>
<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0">
<Results><MeasurementResultsSet n="1"><MeasurementResults id="1">
<MeasuredFeatures n="2">
<PlaneFeatureMeasurement id="2"><FeatureName>TOP</FeatureName><PointList n="1"><WholePointSetId>3</WholePointSetId></PointList>
<Location>0 0 5</Location><Normal>0 0 1</Normal></PlaneFeatureMeasurement>
<PointFeatureMeasurement id="4"><FeatureName>P</FeatureName><PointList n="1"><WholePointSetId>4</WholePointSetId></PointList>
<Location>7 8 9</Location></PointFeatureMeasurement>
</MeasuredFeatures>
<MeasuredPointSets n="2">
<MeasuredPointSet id="3" count="3"><Points>0 0 5 1 0 5 0 1 5</Points></MeasuredPointSet>
<MeasuredPointSet id="5" count="1"><Points>7 8 9</Points></MeasuredPointSet>
</MeasuredPointSets>
</MeasurementResults></MeasurementResultsSet></Results></QIFDocument>
)");
  const auto top = readPointCloud(p, "auto", {"TOP", ""});
  EXPECT_EQ(top.format, "qif");
  ASSERT_EQ(top.points_mm.size(), 3u);
  EXPECT_EQ(top.points_mm[1], Eigen::Vector3d(1, 0, 5));
  EXPECT_EQ(top.source_lines[0], 5);
  ASSERT_EQ(top.warnings.size(), 1u);
  EXPECT_EQ(top.warnings[0].rfind(p + ":7: WholePointSetId: no MeasuredPointSet with id 4", 0), 0u) << top.warnings[0];
  EXPECT_EQ(readPointCloud(p, "auto", {"P", ""}).points_mm.at(0), Eigen::Vector3d(7, 8, 9));  // set 5, the only candidate
  EXPECT_NE(errorOf(p).find("2 measured features with points (TOP, P): give --feature NAME"), std::string::npos) << errorOf(p);
  try {
    readPointCloud(p, "auto", {"TOP", "", true});
    ADD_FAILURE() << "strict accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(p + ":7: WholePointSetId"), std::string::npos) << e.what();
  }
}
