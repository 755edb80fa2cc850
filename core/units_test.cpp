#include "core/units.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

#include "core/csv.hpp"

using namespace probeloop;

TEST(ParseQuantity, BareNumberIsCanonicalUnit) {
  EXPECT_DOUBLE_EQ(parseQuantity("160", Dimension::Length), 160.0);
  EXPECT_DOUBLE_EQ(parseQuantity("200", Dimension::Feed), 200.0);
}

TEST(ParseQuantity, ConvertsUnitsOfTheRightDimension) {
  EXPECT_DOUBLE_EQ(parseQuantity("0.16 m", Dimension::Length), 160.0);
  EXPECT_DOUBLE_EQ(parseQuantity("5 min", Dimension::Duration), 300.0);
  EXPECT_DOUBLE_EQ(parseQuantity("72 h", Dimension::Duration), 259200.0);
  EXPECT_DOUBLE_EQ(parseQuantity("6 m/min", Dimension::Feed), 6000.0);
  EXPECT_DOUBLE_EQ(parseQuantity("1 µm", Dimension::Length), 1e-3);
}

TEST(ParseQuantity, WrongUnitNamesWhatIsAccepted) {
  try {
    parseQuantity("160 kg", Dimension::Length);
    FAIL() << "accepted kg as a length";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a length"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseQuantity("5 mm", Dimension::Duration), std::invalid_argument);
  EXPECT_THROW(parseQuantity("abc", Dimension::Length), std::invalid_argument);
  EXPECT_THROW(parseQuantity("nan", Dimension::Length), std::invalid_argument);
}

// A European export: BOM, CRLF, ';' separators, decimal commas (and points), read as the same
// numbers; a field with both marks, and a ',' file whose rows split at decimal commas, refused.
TEST(Csv, SemicolonFilesTakeDecimalCommasAndNothingIsMisread) {
  const auto t = parseCsv("\xEF\xBB\xBFx_mm;y_mm;feature\r\n1,25;-0,5;S1,a\r\n2.5;3;S2\r\n", "eu.csv");
  EXPECT_EQ(t.separator, ';');
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.header[0], "x_mm");  // the BOM is gone
  EXPECT_DOUBLE_EQ(t.number(t.rows[0], 0), 1.25);
  EXPECT_DOUBLE_EQ(t.number(t.rows[0], 1), -0.5);
  EXPECT_EQ(t.rows[0].fields[2], "S1,a");  // a label keeps its comma
  EXPECT_DOUBLE_EQ(t.number(t.rows[1], 0), 2.5);
  EXPECT_EQ(t.rows[1].line, 3);
  const auto both = parseCsv("x_mm;y_mm\n1.234,5;2\n", "th.csv");
  try {
    both.number(both.rows[0], 0);
    FAIL() << "1.234,5 was read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("th.csv:2: field 'x_mm': '1.234,5' is not a number"), std::string::npos) << e.what();
  }
  try {
    parseCsv("x_mm,y_mm\n1,25,2,5\n", "comma.csv");
    FAIL() << "decimal commas in a comma-separated file were read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("comma.csv:2: expected 2 fields"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("separate the columns with ';'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseCsv("x_mm,y_mm;z_mm\n1,2;3\n", "mixed.csv"), std::exception);
  // Only decimal numbers: strtod alone would take hexadecimal, inf and nan.
  double v = 0;
  EXPECT_FALSE(parseFiniteNumber("0x1.8", v));
  EXPECT_FALSE(parseFiniteNumber("inf", v));
  EXPECT_FALSE(parseFiniteNumber("nan", v));
  EXPECT_TRUE(parseFiniteNumber("-1.5e-3", v));
  EXPECT_DOUBLE_EQ(v, -1.5e-3);
  // The header sniffed the same way by the readers that tell a file's kind by it.
  EXPECT_EQ(csvHeaderFields("\xEF\xBB\xBF# exported\r\nfacet;g_um\r\n1;2,5\r\n"), (std::vector<std::string>{"facet", "g_um"}));
  // A comma file is read as before: a decimal comma can never get into a number there.
  const auto c = parseCsv("a,b\n1.5,2\n", "c.csv");
  EXPECT_EQ(c.separator, ',');
  EXPECT_DOUBLE_EQ(c.number(c.rows[0], 0), 1.5);
}

TEST(Csv, ReportsLineOfBadField) {
  const auto t = parseCsv("# c\na,b\n1,2\n3,x\n", "f.csv");
  EXPECT_DOUBLE_EQ(t.number(t.rows[0], 1), 2.0);
  try {
    t.number(t.rows[1], 1);
    FAIL();
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("f.csv:4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseCsv("a,b\n1\n", "g.csv"), std::exception);
}

TEST(FormatNumber, NoNegativeZero) {
  EXPECT_EQ(formatNumber(-0.00001, 3), "0.000");
  EXPECT_EQ(formatNumber(-1.5, 1), "-1.5");
}
