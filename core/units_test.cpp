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
