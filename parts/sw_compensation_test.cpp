// The compensation file of the stepped workpiece (parts/sw_compensation.hpp): a round trip of
// what evaluate writes, and every refusal names the file and the key.
#include "parts/sw_compensation.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/error.hpp"

namespace probeloop::parts {
namespace {

std::string write(const std::string& text) {
  static int n = 0;
  const auto p = std::filesystem::temp_directory_path() /
                 ("probeloop-comp-" + std::to_string(::getpid()) + "-" + std::to_string(n++) + ".json");
  std::ofstream(p) << text;
  return p.string();
}

const char* kGood = R"({"format": "probeloop-compensation", "kind": "stepped_workpiece", "experiment": "W8",
  "steps": [{"step": 1, "wall_um": {"XP": 3.5, "XN": -1.25, "YP": 5, "YN": 0}, "floor_um": -6.5},
            {"step": 2, "wall_um": {"XP": 1, "XN": 2, "YP": 3, "YN": 4}, "floor_um": 0.5, "U_floor_um": 1.2}]})";

TEST(SwCompensation, ReadsWhatItWritesAndAHandWrittenFile) {
  const auto c = loadSwCompensation(write(kGood));
  ASSERT_EQ(c.steps.size(), 2u);
  EXPECT_EQ(c.experiment, "W8");
  EXPECT_DOUBLE_EQ(c.steps[0].wall_um[1], -1.25);  // XN
  EXPECT_DOUBLE_EQ(c.steps[0].floor_um, -6.5);
  EXPECT_DOUBLE_EQ(c.steps[1].U_floor_um, 1.2);
  EXPECT_DOUBLE_EQ(c.steps[0].U_floor_um, 0.0);  // not given
  const auto again = loadSwCompensation(write(swCompensationJson(c)));
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(again.steps[k].wall_um, c.steps[k].wall_um);
    EXPECT_EQ(again.steps[k].floor_um, c.steps[k].floor_um);
  }
}

std::string refusal(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const auto at = text.find(from);
  if (at == std::string::npos) return "(test error: no '" + from + "')";
  text.replace(at, from.size(), to);
  const std::string path = write(text);
  try {
    loadSwCompensation(path);
  } catch (const InputError& e) {
    const std::string w = e.what();
    return w.find(path) == std::string::npos ? "(no file name) " + w : w;
  }
  return "(accepted)";
}

TEST(SwCompensation, RefusalsNameTheKey) {
  EXPECT_NE(refusal("probeloop-compensation", "qif").find("format: expected"), std::string::npos);
  EXPECT_NE(refusal("stepped_workpiece", "thermal_test_piece").find("kind: expected"), std::string::npos);
  EXPECT_NE(refusal("\"step\": 2", "\"step\": 3").find("steps[1].step: expected 2"), std::string::npos);
  // Compared as numbers (fuzz review): 1e300 was converted to int unchecked, 1.5 read as 1.
  EXPECT_NE(refusal("\"step\": 2", "\"step\": 1e300").find("steps[1].step: expected 2 (in order from the top), found 1e+300"),
            std::string::npos) << refusal("\"step\": 2", "\"step\": 1e300");
  EXPECT_NE(refusal("\"step\": 2", "\"step\": 2.5").find("steps[1].step: expected 2"), std::string::npos);
  EXPECT_NE(refusal("\"XN\": -1.25, ", "").find("steps[0].wall_um.XN: missing"), std::string::npos);
  EXPECT_NE(refusal("\"floor_um\": -6.5", "\"floor_um\": \"deep\"").find("steps[0].floor_um: expected a number"), std::string::npos);
  EXPECT_NE(refusal("\"floor_um\": 0.5", "\"floor_um\": 600").find("offset 600 um beyond +-500 um"), std::string::npos);
  EXPECT_NE(refusal("{\"format\"", "[\"format\"").find("not JSON"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::parts
