// QIF 3.0 plans and results (interop/qif.hpp): what we write validates against the QIF 3.0.0
// XSD (libxml2's validator, the engine behind xmllint, on ../shared/refdata/qif3) and reads
// back to the same features, points and values; other software's samples read with the counts
// and coordinates xmllint --xpath gives for them; bad files are refused with file:line.
#include "interop/qif.hpp"

#include <gtest/gtest.h>
#include <libxml/parser.h>
#include <libxml/xmlschemas.h>

#include <filesystem>

#include "core/error.hpp"
#include "interop/test_documents.hpp"

namespace probeloop::interop {
namespace {

namespace fs = std::filesystem;

fs::path qifDir() { return fs::path(PROBELOOP_SOURCE_DIR) / ".." / "shared" / "refdata" / "qif3"; }

// Validation errors, one per line; "" when the document is valid.
std::string schemaErrors(const std::string& xml) {
  static xmlSchemaPtr schema = [] {
    xmlSchemaParserCtxtPtr pc = xmlSchemaNewParserCtxt((qifDir() / "QIFApplications" / "QIFDocument.xsd").string().c_str());
    xmlSchemaPtr s = xmlSchemaParse(pc);
    xmlSchemaFreeParserCtxt(pc);
    return s;
  }();
  if (!schema) return "the QIF schema did not load";
  xmlDocPtr doc = xmlReadMemory(xml.data(), static_cast<int>(xml.size()), "doc.qif", nullptr, XML_PARSE_NONET);
  if (!doc) return "not well-formed";
  std::string errors;
  xmlSchemaValidCtxtPtr vc = xmlSchemaNewValidCtxt(schema);
  xmlSchemaSetValidStructuredErrors(
      vc, [](void* out, xmlErrorPtr e) { *static_cast<std::string*>(out) += std::to_string(e->line) + ": " + e->message; }, &errors);
  const int rc = xmlSchemaValidateDoc(vc, doc);
  xmlSchemaFreeValidCtxt(vc);
  xmlFreeDoc(doc);
  return rc == 0 ? "" : (errors.empty() ? "invalid" : errors);
}

bool haveSchemas() { return fs::exists(qifDir() / "QIFApplications" / "QIFDocument.xsd"); }

CmmDocument sample() { return testing::ballPlaneBore(); }

TEST(Qif, APlanValidatesAgainstTheSchema) {
  if (!haveSchemas()) GTEST_SKIP() << "no " << qifDir();
  const std::string xml = qifPlan(sample());
  EXPECT_EQ(schemaErrors(xml), "");
  EXPECT_NE(xml.find("<NominalPointSet id=\"10\" n=\"5\">"), std::string::npos) << xml.substr(0, 3000);
  EXPECT_EQ(xml, qifPlan(sample()));  // deterministic, QPId included
}

TEST(Qif, APlanReadsBackToItsFeaturesAndPoints) {
  const auto a = sample();
  const auto b = parseQifPlan(qifPlan(a), "plan.qif");
  testing::expectSamePlan(a, b, 1e-8);  // directions written to 1e-9
  EXPECT_THROW(parseQifPlan(qifResults(CmmDocument{}), "empty.qif"), InputError);
}

TEST(Qif, ResultsValidateAndReadBackToTheSameFeatures) {
  auto d = sample();
  for (auto& f : d.features) {
    f.measured = f.nominal;
    f.measured.given = true;
  }
  d.features[0].measured.location_mm += Eigen::Vector3d(0.0012, -0.0007, 0.0004);
  d.features[0].measured.diameter_mm = 25.0016;
  d.features[1].measured.form_mm = 0.0022;
  d.features[2].points[3].p_mm.x() += 0.0003;
  d.characteristics.push_back({"EX0C", false, 0.0031, 0.0008});
  d.characteristics.push_back({"EA0C", true, 12.5e-6, 3e-6});
  const std::string xml = qifResults(d);
  if (haveSchemas()) {
    EXPECT_EQ(schemaErrors(xml), "");
  }
  const auto r = parseQifResults(xml, "r.qif");
  ASSERT_EQ(r.features.size(), 3u);
  EXPECT_EQ(r.runs, 1);
  EXPECT_EQ(r.length_unit, "mm");
  for (std::size_t i = 0; i < 3; ++i) {
    const auto& a = d.features[i];
    const auto& b = r.features[i];
    EXPECT_EQ(b.name, a.name);
    EXPECT_EQ(b.kind, a.kind);
    EXPECT_TRUE(b.measured.given);
    EXPECT_LT((b.measured.location_mm - a.measured.location_mm).norm(), 1e-6);
    ASSERT_EQ(b.points.size(), a.points.size());
    for (std::size_t k = 0; k < a.points.size(); ++k) {
      EXPECT_LT((b.points[k].p_mm - a.points[k].p_mm).norm(), 1e-6);  // written to 1 nm
      EXPECT_LT((b.points[k].normal - a.points[k].normal).norm(), 1e-9);
    }
  }
  EXPECT_NEAR(r.features[0].measured.diameter_mm, 25.0016, 1e-12);
  EXPECT_NEAR(r.features[1].measured.form_mm, 0.0022, 1e-12);
  EXPECT_LT((r.features[2].measured.direction - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  ASSERT_EQ(r.characteristics.size(), 2u);
  EXPECT_EQ(r.characteristics[0].name, "EX0C");
  EXPECT_NEAR(r.characteristics[0].value, 0.0031, 1e-12);
  EXPECT_NEAR(r.characteristics[0].u, 0.0008, 1e-12);
  EXPECT_TRUE(r.characteristics[1].angular);
  EXPECT_NEAR(r.characteristics[1].value, 12.5e-6, 1e-12);
}

// A sphere campaign's results: characteristics only, no features (empty lists are invalid QIF).
TEST(Qif, ResultsWithoutFeaturesValidate) {
  CmmDocument d;
  d.characteristics.push_back({"EX0C cycle 2", false, -0.0012, 0.0003});
  const std::string xml = qifResults(d);
  if (haveSchemas()) {
    EXPECT_EQ(schemaErrors(xml), "");
  }
  const auto r = parseQifResults(xml, "c.qif");
  EXPECT_TRUE(r.features.empty());
  ASSERT_EQ(r.characteristics.size(), 1u);
  EXPECT_EQ(r.characteristics[0].name, "EX0C cycle 2");
  EXPECT_EQ(xml.find("<Features>"), std::string::npos);
}

// A producer working in inches, with one point set in another declared unit and a range.
TEST(Qif, LengthsAreConvertedToMillimetres) {
  const std::string xml = R"(<?xml version="1.0"?>
<q:QIFDocument xmlns:q="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0" idMax="9">
 <q:QPId>00000000-0000-4000-8000-000000000000</q:QPId>
 <q:FileUnits><q:PrimaryUnits><q:LinearUnit><q:UnitName>inch</q:UnitName></q:LinearUnit></q:PrimaryUnits>
  <q:OtherUnits><q:LinearUnit><q:UnitName>thou</q:UnitName><q:UnitConversion><q:Factor>0.0000254</q:Factor></q:UnitConversion></q:LinearUnit></q:OtherUnits></q:FileUnits>
 <q:Results><q:MeasurementResultsSet n="1"><q:MeasurementResults id="1">
  <q:MeasuredFeatures n="1"><q:SphereFeatureMeasurement id="2"><q:FeatureName>BALL</q:FeatureName>
   <q:PointList n="1"><q:RangePointSetId range="2 3">3</q:RangePointSetId></q:PointList>
   <q:Location>1 2 3</q:Location><q:Diameter linearUnit="thou">500</q:Diameter></q:SphereFeatureMeasurement></q:MeasuredFeatures>
  <q:MeasuredPointSets n="1"><q:MeasuredPointSet id="3" count="3"><q:Points>0 0 0 1 0 0
   0 1 0</q:Points><q:Compensated>true</q:Compensated></q:MeasuredPointSet></q:MeasuredPointSets>
  <q:InspectionStatus><q:InspectionStatusEnum>PASS</q:InspectionStatusEnum></q:InspectionStatus>
 </q:MeasurementResults></q:MeasurementResultsSet></q:Results></q:QIFDocument>)";
  const auto r = parseQifResults(xml, "inch.qif");
  ASSERT_EQ(r.features.size(), 1u);
  const auto& f = r.features[0];
  EXPECT_EQ(f.name, "BALL");
  EXPECT_EQ(r.length_unit, "inch");
  EXPECT_LT((f.measured.location_mm - Eigen::Vector3d(25.4, 50.8, 76.2)).norm(), 1e-12);
  EXPECT_NEAR(f.measured.diameter_mm, 12.7, 1e-12);
  ASSERT_EQ(f.points.size(), 2u);  // points 2 and 3 of the set
  EXPECT_LT((f.points[0].p_mm - Eigen::Vector3d(25.4, 0, 0)).norm(), 1e-12);
  EXPECT_LT((f.points[1].p_mm - Eigen::Vector3d(0, 25.4, 0)).norm(), 1e-12);
  EXPECT_EQ(f.line, 7);
}

void expectRefused(const std::string& xml, const std::string& want, bool strict = false) {
  try {
    parseQifResults(xml, "bad.qif", CmmReadOptions{strict});
    ADD_FAILURE() << "accepted; expected '" << want << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
  }
}

TEST(Qif, RefusesWhatIsNotQif3OrDoesNotAddUp) {
  expectRefused("<a/>", "bad.qif:1: the root element is a, not QIFDocument");
  expectRefused("<QIFDocument", "bad.qif:1: not well-formed XML");
  expectRefused("<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif2\" versionQIF=\"2.1.0\"/>", "namespace 'http://qifstandards.org/xsd/qif2'");
  expectRefused("<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif3\" versionQIF=\"2.1.0\"/>", "bad.qif:1: versionQIF: '2.1.0'");
  auto d = sample();
  d.features.resize(1);
  const std::string good = qifResults(d);
  // The good document with its first `from` replaced by `to`.
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  expectRefused(with("count=\"5\"", "count=\"6\""), "Points: 15 numbers, expected 18");
  const auto p = good.find("<WholePointSetId>") + 17;
  // A dangling id: refused when strict (read with a warning otherwise: qif_lenient_test.cpp).
  expectRefused(with(good.substr(p, good.find('<', p) - p) + "</WholePointSetId>", "99</WholePointSetId>"),
                "WholePointSetId: no MeasuredPointSet with id 99", true);
  expectRefused(with("<Points>", "<Points>NaN "), "Points: 'NaN' is not a finite number");
  expectRefused(with("<UnitName>mm<", "<UnitName>furlong<"), "UnitName: 'furlong' is not a length unit");
  // Counts: beyond the bound (3 x count would overflow), and 0 with points given.
  expectRefused(with("count=\"5\"", "count=\"6148914691236517888\""),
                "count '6148914691236517888' is not a whole number from 0 to 100000000");
  expectRefused(with("count=\"5\"", "count=\"0\""), "Points: 15 numbers, expected 0");
  // A point set in its own units.
  expectRefused(with("<Points>", "<Units><LinearUnit><UnitName>inch</UnitName></LinearUnit></Units><Points>"),
                "its own Units or coordinate system are not read");
  // A DOCTYPE (entity declarations would expand in the text): refused.
  expectRefused("<?xml version=\"1.0\"?>\n<!DOCTYPE QIFDocument [<!ENTITY a \"1 2 3\">]>\n"
                "<QIFDocument xmlns=\"http://qifstandards.org/xsd/qif3\" versionQIF=\"3.0.0\"/>",
                "bad.qif:2: a DOCTYPE");
}

// Detection looks past a long prolog (the XML declaration, comments), and only at the root.
TEST(Qif, DetectedByItsRootElement) {
  EXPECT_TRUE(looksLikeQif("\xEF\xBB\xBF<?xml version=\"1.0\"?>\n<!--" + std::string(10000, 'x') + "-->\n<q:QIFDocument xmlns:q=\"x\">"));
  EXPECT_FALSE(looksLikeQif("<Other><QIFDocument/></Other>"));
  EXPECT_FALSE(looksLikeQif("feature,point,x_mm\nQIFDocument,1,2\n"));
}

// A feature measured without points (lists in QIF need n >= 1) and angular values in degrees;
// Angularity is a zone in length, not an angle.
TEST(Qif, FeaturesWithoutPointsAndAnglesInDegrees) {
  auto d = sample();
  d.features[1].points.clear();
  if (haveSchemas()) {
    EXPECT_EQ(schemaErrors(qifResults(d)), "");
    EXPECT_EQ(schemaErrors(qifPlan(d)), "");
  }
  EXPECT_TRUE(parseQifResults(qifResults(d), "r.qif").features[1].points.empty());
  const std::string xml = R"(<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0" idMax="9">
 <FileUnits><PrimaryUnits><AngularUnit><UnitName>degree</UnitName></AngularUnit><LinearUnit><UnitName>mm</UnitName></LinearUnit></PrimaryUnits></FileUnits>
 <Results><MeasurementResultsSet n="1"><MeasurementResults id="1"><MeasuredCharacteristics><CharacteristicMeasurements n="2">
  <AngleBetweenCharacteristicMeasurement id="2"><Value>90</Value></AngleBetweenCharacteristicMeasurement>
  <AngularityCharacteristicMeasurement id="3"><Value>0.095</Value></AngularityCharacteristicMeasurement>
 </CharacteristicMeasurements></MeasuredCharacteristics></MeasurementResults></MeasurementResultsSet></Results></QIFDocument>)";
  const auto r = parseQifResults(xml, "a.qif");
  ASSERT_EQ(r.characteristics.size(), 2u);
  EXPECT_TRUE(r.characteristics[0].angular);
  EXPECT_NEAR(r.characteristics[0].value, M_PI / 2, 1e-12);
  EXPECT_FALSE(r.characteristics[1].angular);
  EXPECT_NEAR(r.characteristics[1].value, 0.095, 1e-12);
  EXPECT_TRUE(r.notes.empty()) << r.notes.front();
  // A measurement with a status only (Value is optional; a converter may lose it): named in a note.
  std::string status_only = xml;
  status_only.replace(status_only.find("<Value>0.095</Value>"), 20, "<Status><CharacteristicStatusEnum>FAIL</CharacteristicStatusEnum></Status>");
  const auto s = parseQifResults(status_only, "s.qif");
  ASSERT_EQ(s.characteristics.size(), 1u);
  ASSERT_EQ(s.notes.size(), 1u);
  EXPECT_EQ(s.notes[0], "1 characteristic measurement without a Value (AngularityCharacteristicMeasurement): a status only, not read");
}

// Other software's files (../shared/refdata/qif3/samples); the expected numbers are what
// `xmllint --xpath` gives for them (docs/interop.md lists the commands).
TEST(Qif, ReadsOtherSoftwaresSamples) {
  const auto dir = qifDir() / "samples";
  if (!fs::exists(dir)) GTEST_SKIP() << "no " << dir;
  auto count = [](const CmmDocument& d, CmmFeatureKind k) {
    int n = 0;
    for (const auto& f : d.features) n += f.kind == k;
    return n;
  };
  const auto a = readQifResults((dir / "QIF_Results_Sample.QIF").string());
  ASSERT_EQ(a.features.size(), 6u);
  EXPECT_EQ(count(a, CmmFeatureKind::Point), 3);  // 1 EdgePoint + 2 Point
  EXPECT_EQ(count(a, CmmFeatureKind::Circle), 3);
  EXPECT_EQ(a.features[0].kind_name, "EdgePoint");
  EXPECT_EQ(a.features[0].name, "TRIM1");
  EXPECT_LT((a.features[0].measured.location_mm - Eigen::Vector3d(2460.72, 770.62, 944.98)).norm(), 1e-9);
  const auto b = readQifResults((dir / "WIDGET_QIF_RESULTS_W_QPIDS.QIF").string());
  ASSERT_EQ(b.features.size(), 19u);
  EXPECT_EQ(count(b, CmmFeatureKind::Plane), 5);
  EXPECT_EQ(count(b, CmmFeatureKind::Cylinder), 6);
  EXPECT_EQ(count(b, CmmFeatureKind::Circle), 1);
  EXPECT_EQ(count(b, CmmFeatureKind::Point), 6);
  EXPECT_EQ(count(b, CmmFeatureKind::Other), 1);
  EXPECT_EQ(b.features[0].name, "DATUM_A");
  EXPECT_LT((b.features[0].measured.location_mm - Eigen::Vector3d(-29.763, -0.065, -42.578)).norm(), 1e-9);
  for (const auto& f : b.features) {
    if (f.kind != CmmFeatureKind::Cylinder) continue;
    EXPECT_LT((f.measured.location_mm - Eigen::Vector3d(-5, 31.051, -71.282)).norm(), 1e-9);
    EXPECT_NEAR(f.measured.diameter_mm, 19.007, 1e-9);
    break;
  }
  const auto c = readQifResults((dir / "mitutoyo_results_serialized_pass_fail_sample.QIF").string());
  EXPECT_EQ(c.features.size(), 0u);
  EXPECT_EQ(c.runs, 1);
  ASSERT_FALSE(c.notes.empty());
  EXPECT_EQ(c.notes[0], "no FileUnits: lengths read in mm");
  const auto d = readQifResults((dir / "nist_ctc_01_asme1_cr2040_rd.qif").string());
  EXPECT_EQ(d.features.size(), 0u);  // a product definition: 136 nominal features, no Results
  EXPECT_EQ(d.runs, 0);
}

}  // namespace
}  // namespace probeloop::interop
