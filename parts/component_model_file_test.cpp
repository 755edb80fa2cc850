// The component-model file: the shipped seed 000 instance loads with every equation of Ch. 5,
// and broken files are refused with their line.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <set>

#include "core/error.hpp"
#include "parts/component_model_file.hpp"
#include "parts/test_support.hpp"

using namespace probeloop;
using probeloop::parts::test::variantOf;

namespace {

const std::string kFile = std::string(PROBELOOP_SOURCE_DIR) + "/examples/stepped_workpiece/yaqoob2017_components.yaml";

// The InputError's line and message for a variant of the shipped file.
std::pair<int, std::string> refusal(const std::string& from, const std::string& to) {
  const auto path = variantOf(kFile, from, to);
  try {
    parts::loadComponentModel(path);
  } catch (const InputError& e) {
    return {e.line(), e.what()};
  }
  return {0, "loaded"};
}

int lineOf(const std::string& text) {
  std::ifstream in(kFile);
  std::string l;
  for (int n = 1; std::getline(in, l); ++n)
    if (l.find(text) != std::string::npos) return n;
  return -1;
}

}  // namespace

// Every numbered equation of Ch. 5 that is a function of one input is in the file (Eq. 5.17-5.44
// are the thermal block's interpolations, Eq. 5.54/5.55 the control block's feed scaling), and
// each evaluates to a finite number at an input of its range.
TEST(ComponentModelFile, ShippedSeed000ModelHasEveryEquationOfChapter5) {
  const auto m = parts::loadComponentModel(kFile);
  std::set<int> numbered;
  const std::regex eq(R"(Eq\. 5\.(\d+))");
  for (const auto& e : m.equations) {
    for (std::sregex_iterator it(e.equation.begin(), e.equation.end(), eq), end; it != end; ++it)
      numbered.insert(std::stoi((*it)[1]));
    const double x = e.input == "T_min" ? 60 : e.input == "e_prog" ? 4e-6 : e.input.rfind("feed", 0) == 0 ? 200 : 50;
    EXPECT_TRUE(std::isfinite(e(x))) << e.id;
    EXPECT_GT(e.line, 0);
  }
  for (int n : {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 45, 46, 47, 48, 49, 50, 51, 52, 53, 56, 57})
    EXPECT_TRUE(numbered.count(n)) << "Eq. 5." << n << " is missing";
  ASSERT_EQ(m.thermal.size(), 7u);
  EXPECT_EQ(m.stages("e_splz").stage_3500_rpm, "e_splz_s1_pred");
  EXPECT_EQ(m.control_feed_high_mm_per_min, 2400);
  // Values typed from the print: Eq. 5.4 at T = 0 is 0.012 - 0.0104453; Eq. 5.3 at dz = 9 is
  // Table 6.4's e_posz -0.001753.
  EXPECT_NEAR(m.equation("e_splz_s1")(0), 0.0015547, 1e-15);
  EXPECT_NEAR(m.equation("e_pos_z")(9), -0.001753, 1e-15);
  // The typo readings are in the data, each naming what was read.
  for (const char* id : {"e_spd_y_s1", "e_tt_x_s3", "e_splz_s3", "e_pf_x", "e_tt_y_s1", "e_splz_s1_pred", "e_pt_x_s2_pred"})
    EXPECT_FALSE(m.equation(id).reading.empty()) << id;
  EXPECT_THROW(m.equation("e_nothing"), std::out_of_range);
}

TEST(ComponentModelFile, BrokenFilesAreRefusedWithTheirLine) {
  const int l_pos_x = lineOf("{id: e_pos_x,");
  auto r = refusal("family: polynomial, input: dx_mm", "family: exponential, input: dx_mm");
  EXPECT_EQ(r.first, l_pos_x) << r.second;
  EXPECT_NE(r.second.find("'exponential' is not one of"), std::string::npos) << r.second;

  r = refusal("input: dx_mm", "input: dx_um");
  EXPECT_EQ(r.first, l_pos_x) << r.second;

  r = refusal("{a: 0.012, b: 0.0104453, c: 0.01862}", "{a: 0.012, b: 0.0104453, k: 0.01862}");
  EXPECT_NE(r.second.find("missing key 'equations.e_splz_s1.coefficients.c'"), std::string::npos) << r.second;

  r = refusal("{a: 0.012, b: 0.0104453, c: 0.01862}", "{a: 0.012, b: 0.0104453, c: 0.01862, d: 1}");
  EXPECT_NE(r.second.find("unknown key 'equations.e_splz_s1.coefficients.d'"), std::string::npos) << r.second;

  r = refusal("{a: 0.012, b: 0.0104453, c: 0.01862}", "{a: 0.012, b: .nan, c: 0.01862}");
  EXPECT_NE(r.second.find("expected a finite number"), std::string::npos) << r.second;

  r = refusal("{id: e_pos_y,", "{id: e_pos_x,");
  EXPECT_EQ(r.first, lineOf("{id: e_pos_y,")) << r.second;
  EXPECT_NE(r.second.find("listed twice"), std::string::npos);

  r = refusal("stage_5500_rpm: e_pt_y_s3}", "stage_5500_rpm: e_pt_y_s4}");
  EXPECT_EQ(r.first, lineOf("stage_5500_rpm: e_pt_y_s3}")) << r.second;
  EXPECT_NE(r.second.find("no equation with id 'e_pt_y_s4'"), std::string::npos);

  r = refusal("stage_5500_rpm: e_pt_y_s3}", "stage_5500_rpm: e_pf_y}");
  EXPECT_NE(r.second.find("a thermal stage function is of T_min"), std::string::npos) << r.second;

  r = refusal("feed_high_mm_per_min: 2400", "feed_high_mm_per_min: 50");
  EXPECT_EQ(r.first, lineOf("feed_high_mm_per_min: 2400")) << r.second;

  r = refusal("coefficients: [0, 0.000249252, -9.57162e-7]", "coefficients: {c0: 0}");
  EXPECT_NE(r.second.find("as a list"), std::string::npos) << r.second;

  r = refusal("kind: component_model", "kind: error_model");
  EXPECT_NE(r.second.find("expected 'component_model'"), std::string::npos) << r.second;
}
