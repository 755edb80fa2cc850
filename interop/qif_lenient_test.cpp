// Lenient QIF reading (issue 34, docs/interop.md#lenient-reading): each producer's mistake that
// keeps the meaning is read with a warning naming its line and what was done, and refused at the
// same line with the same words under strict. The documents are small hand-written ones, each
// with one mistake; the real file (CheckMate's) is read in tests/integration/foreign_files_cli.py.
#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"
#include "interop/qif.hpp"

namespace probeloop::interop {
namespace {

// A plane PLN (points 1..3 on z = 0, set 5) and a point PT (set 7, one point at 10 20 0), in
// mm; MIDDLE is put between the measurements and the point sets, BODY into the results.
std::string document(const std::string& pt_list, const std::string& middle = "", const std::string& body = "") {
  return R"(<?xml version="1.0"?>
<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" xmlns:acme="http://example.com/acme" versionQIF="3.0.0">
<FileUnits><PrimaryUnits><LinearUnit><SIUnitName>meter</SIUnitName><UnitName>mm</UnitName></LinearUnit></PrimaryUnits></FileUnits>
<Results><MeasurementResultsSet n="1"><MeasurementResults id="1">
<MeasuredFeatures n="2">
<PlaneFeatureMeasurement id="2"><FeatureName>PLN</FeatureName>
<PointList n="1"><WholePointSetId>5</WholePointSetId></PointList>
<Location>0 0 0</Location><Normal>0 0 1</Normal></PlaneFeatureMeasurement>
<PointFeatureMeasurement id="6"><FeatureName>PT</FeatureName>
)" + pt_list + R"(
<Location>10 20 0</Location></PointFeatureMeasurement>
</MeasuredFeatures>
)" + middle + R"(
<MeasuredPointSets n="2">
<MeasuredPointSet id="5" count="3"><Points>0 0 0 1 0 0 0 1 0</Points></MeasuredPointSet>
<MeasuredPointSet id="7" count="1"><Points>10 20 0</Points></MeasuredPointSet>
</MeasuredPointSets>
)" + body + R"(
</MeasurementResults></MeasurementResultsSet></Results></QIFDocument>
)";
}

const std::string kGoodList = R"(<PointList n="1"><WholePointSetId>7</WholePointSetId></PointList>)";

const CmmFeature& feature(const CmmDocument& d, const std::string& name) {
  for (const auto& f : d.features)
    if (f.name == name) return f;
  throw std::logic_error("no feature " + name);
}

// The lenient read gives one warning at `line` containing `what`; the strict read refuses with
// "lenient.qif:line: <the warning's problem>".
CmmDocument expectWarnedAndRefused(const std::string& xml, int line, const std::string& what) {
  const auto d = parseQifResults(xml, "lenient.qif");
  EXPECT_EQ(d.warnings.size(), 1u);
  if (d.warnings.empty()) return d;
  EXPECT_EQ(d.warnings[0].line, line);
  EXPECT_NE(d.warnings[0].what.find(what), std::string::npos) << d.warnings[0].what;
  try {
    parseQifResults(xml, "lenient.qif", CmmReadOptions{true});
    ADD_FAILURE() << "strict read accepted: " << d.warnings[0].what;
  } catch (const InputError& e) {
    const std::string problem = d.warnings[0].what.substr(0, d.warnings[0].what.find("; "));
    EXPECT_EQ(std::string(e.what()), "lenient.qif:" + std::to_string(line) + ": " + problem);
  }
  return d;
}

TEST(QifLenient, AWellFormedDocumentHasNoWarnings) {
  const auto d = parseQifResults(document(kGoodList), "good.qif", CmmReadOptions{true});
  EXPECT_TRUE(d.warnings.empty());
  EXPECT_EQ(feature(d, "PT").points.size(), 1u);
  EXPECT_EQ(d.point_sets, 2);
  EXPECT_EQ(d.point_set_points, 4u);
}

// CheckMate's mistake: the point feature names its own id (6); set 7 is the only unreferenced
// set on its location, so it is assigned.
TEST(QifLenient, ASelfReferenceIsAssignedTheUniqueCandidate) {
  const auto d = expectWarnedAndRefused(document(R"(<PointList n="1"><WholePointSetId>6</WholePointSetId></PointList>)"), 10,
                                        "WholePointSetId: no MeasuredPointSet with id 6 in this MeasurementResults (it is the "
                                        "feature measurement's own id); assigned MeasuredPointSet 7");
  ASSERT_EQ(feature(d, "PT").points.size(), 1u);
  EXPECT_EQ(feature(d, "PT").points[0].p_mm, Eigen::Vector3d(10, 20, 0));
  EXPECT_EQ(feature(d, "PLN").points.size(), 3u);
}

// A dangling id whose feature no unreferenced set fits (set 7's point is 5 mm away from the
// location): the points stay unassigned, the rest is read.
TEST(QifLenient, ADanglingIdWithoutACandidateLeavesThePointsUnassigned) {
  std::string xml = document(R"(<PointList n="1"><WholePointSetId>99</WholePointSetId></PointList>)");
  xml.replace(xml.find("<Location>10 20 0</Location>"), 28, "<Location>15 20 0</Location>");
  const auto d = expectWarnedAndRefused(xml, 10, "WholePointSetId: no MeasuredPointSet with id 99 in this MeasurementResults; the "
                                                 "feature's points left unassigned (0 unreferenced sets lie on its measured geometry)");
  EXPECT_TRUE(feature(d, "PT").points.empty());
  EXPECT_EQ(feature(d, "PLN").points.size(), 3u);
  EXPECT_EQ(d.point_set_points, 4u);  // counted, though not assigned
}

// MeasuredPointSets before MeasuredFeatures, and Location before PointList: found by name.
TEST(QifLenient, ElementsOutOfOrderAreReadAsIfInOrder) {
  std::string xml = document(kGoodList);
  const auto sets_at = xml.find("<MeasuredPointSets"), sets_end = xml.find("</MeasuredPointSets>") + 20;
  const std::string sets = xml.substr(sets_at, sets_end - sets_at);
  xml.erase(sets_at, sets_end - sets_at);
  xml.insert(xml.find("<MeasuredFeatures"), sets + "\n");
  const auto d = expectWarnedAndRefused(xml, 9, "MeasurementResults: MeasuredFeatures stands after MeasuredPointSets (QIF 3.0 "
                                                 "has it before); read as if in order");
  EXPECT_EQ(feature(d, "PT").points.size(), 1u);
  EXPECT_EQ(feature(d, "PLN").points.size(), 3u);

  std::string swapped = document(kGoodList);
  swapped.replace(swapped.find(kGoodList), kGoodList.size(), "");
  swapped.insert(swapped.find("</PointFeatureMeasurement>"), kGoodList);
  const auto e = expectWarnedAndRefused(swapped, 11, "PointFeatureMeasurement: PointList stands after Location");
  EXPECT_EQ(feature(e, "PT").points.size(), 1u);
}

// A vendor's element in its own namespace: passed over, QIF's elements read as before.
TEST(QifLenient, AnUnknownExtensionIsPassedOver) {
  const auto d = expectWarnedAndRefused(document(kGoodList, "", "<acme:ProbeTemperature>20.1</acme:ProbeTemperature>"), 18,
                                        "MeasurementResults: unknown extension ProbeTemperature (namespace http://example.com/acme); "
                                        "passed over");
  EXPECT_EQ(feature(d, "PT").points.size(), 1u);
}

// The optional PointList missing (CheckMate's POINT3): its unreferenced set is assigned.
TEST(QifLenient, AMissingPointListIsFilledByTheUniqueCandidate) {
  const auto d = expectWarnedAndRefused(document(""), 9,
                                        "PointFeatureMeasurement 6 has no PointList, but MeasuredPointSet 7 (referenced by no feature) "
                                        "lies on its measured geometry; assigned it");
  ASSERT_EQ(feature(d, "PT").points.size(), 1u);
}

// What breaks the meaning stays refused however lenient: a count that does not add up.
TEST(QifLenient, ACountThatDoesNotAddUpIsStillRefused) {
  std::string xml = document(kGoodList);
  xml.replace(xml.find("count=\"3\""), 9, "count=\"4\"");
  try {
    parseQifResults(xml, "lenient.qif");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Points: 9 numbers, expected 12"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace probeloop::interop
