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
}
