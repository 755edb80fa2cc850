#include "gcode/probe_log.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::gcode;

TEST(ProbeLog, ReadsLinuxCncLogLines) {
  const auto p = parseProbeLog("PT 2.000000 3 1 -141.000000 0.500000 75.000000\n", "a.log");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].cycle, 2);
  EXPECT_EQ(p[0].position, 3);
  EXPECT_EQ(p[0].point, 1);
  EXPECT_DOUBLE_EQ(p[0].tip_mm.x(), -141.0);
}

TEST(ProbeLog, ReadsFanucDprntWithPaddingAndSplitSign) {
  const auto p = parseProbeLog("%\nPT    1 2 5 - 160.0010   18.0000  93.0020\n%\n", "b.txt");
  ASSERT_EQ(p.size(), 1u);
  EXPECT_DOUBLE_EQ(p[0].tip_mm.x(), -160.001);
  EXPECT_EQ(p[0].line, 2);
}

TEST(ProbeLog, ForeignLineNamesFileAndLine) {
  try {
    parseProbeLog("PT 1 1 1 0 0 0\nhello world\n", "c.log");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c.log:2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseProbeLog("PT 1 1 1 0 nan 0\n", "d.log"), InputError);
  EXPECT_THROW(parseProbeLog("PT 1.5 1 1 0 0 0\n", "e.log"), InputError);
  // Found by fuzz/probe_log_fuzz: a cycle beyond int was converted unchecked.
  try {
    parseProbeLog("PT 1e300 1 1 0 0 0\n", "f.log");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("f.log:1: cycle, position and point must be positive integers"), std::string::npos)
        << e.what();
  }
}

// Fanuc's clock: each PT line's date and time minus the first START's, across midnight and a
// month's end (2026-01-31 23:59:58 -> 2026-02-01 00:00:03 is 5 s); LinuxCNC lines carry none.
TEST(ProbeLog, FanucClockGivesEachPointItsTimeSinceTheFirstStart) {
  const auto p = parseProbeLog("%\nSTART  20260131  235958\nPT     1 2 5  - 160.0010   18.0000  93.0020  20260131  235959\n"
                               "START  20260201       2\nPT     1 2 6  - 160.0010   18.0000  93.0020  20260201       3\n"
                               "PT 2.000000 3 1 -141.000000 0.500000 75.000000\n%\n", "d.txt");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_DOUBLE_EQ(*p[0].time_s, 1.0);
  EXPECT_DOUBLE_EQ(*p[1].time_s, 5.0);  // from the first START, not the second program's
  EXPECT_FALSE(p[2].time_s.has_value());
  try {
    parseProbeLog("START 20261301 000000\n", "e.txt");
    FAIL() << "month 13 was read";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("e.txt:1: clock '20261301 000000'"), std::string::npos) << e.what();
  }
}

// A live LinuxCNC program logs the inputs logger's clock (analog input 1) as an eighth field:
// that is the point's time as it stands (no START); a negative or non-finite clock is refused.
TEST(ProbeLog, LinuxCncClockFieldIsThePointsTime) {
  const auto p = parseProbeLog("PT 1.000000 1 1 -142.009000 0.000000 75.000000 7212.500000\n"
                               "PT 1.000000 1 2 -160.000000 17.991000 75.000000 7230.250000\n", "live.log");
  ASSERT_EQ(p.size(), 2u);
  EXPECT_DOUBLE_EQ(*p[0].time_s, 7212.5);
  EXPECT_DOUBLE_EQ(*p[1].time_s, 7230.25);
  for (const char* bad : {"PT 1 1 1 0 0 0 -1\n", "PT 1 1 1 0 0 0 inf\n", "PT 1 1 1 0 0 0 x\n"}) {
    try {
      parseProbeLog(bad, "g.log");
      FAIL() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("g.log:1: field 8"), std::string::npos) << e.what();
    }
  }
}
