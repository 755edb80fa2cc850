// The campaign loader refuses bad data with the file, the line and what was expected.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>

#include "core/error.hpp"
#include "model/dataset.hpp"

using namespace probeloop;
using namespace probeloop::model;

namespace {
std::string write(const std::string& name, const std::string& text) {
  const auto p = (std::filesystem::temp_directory_path() / ("probeloop_dataset_" + name)).string();
  std::ofstream(p) << text;
  return p;
}
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}
const std::string kErrors = "time_s,cycle,EY0C_um,U_EY0C_um\n60,1,0,0\n120,2,1.5,2.2\n";
}  // namespace

TEST(Dataset, LoadsAlignsAndInterpolatesAtTheErrorTimes) {
  const auto in = write("ok_in.csv", "# c\ntime_s,T_env_C,c_rpm\n0,20,0\n60,21,300\n120,22,300\n");
  const auto c = loadCampaign(in, write("ok_err.csv", kErrors));
  EXPECT_EQ(c.inputs.step_s, 60);
  EXPECT_EQ(c.errors.channel("EY0C"), 0);
  EXPECT_EQ(c.errors.U[0][1], 2.2);
  const auto T = c.atErrorTimes(c.inputs.columns[0]);
  EXPECT_DOUBLE_EQ(T[0], 21);
  EXPECT_DOUBLE_EQ(T[1], 22);
}

TEST(Dataset, RefusesGapsNaNMisalignmentAndDisorder) {
  const auto err = write("e.csv", kErrors);
  auto msg = errorOf([&] { loadInputs(write("gap.csv", "time_s,T\n0,20\n60,20\n120,20\n300,20\n")); });
  EXPECT_NE(msg.find("gap.csv:5: gap in the inputs: 180 s since line 4"), std::string::npos) << msg;
  msg = errorOf([&] { loadInputs(write("nan.csv", "time_s,T\n0,20\n60,nan\n")); });
  EXPECT_NE(msg.find("nan.csv:3: field 'T': 'nan' is not a finite number"), std::string::npos) << msg;
  msg = errorOf([&] { loadInputs(write("order.csv", "time_s,T\n0,20\n60,20\n30,20\n")); });
  EXPECT_NE(msg.find("order.csv:4: time_s 30 does not follow 60"), std::string::npos) << msg;
  msg = errorOf([&] { loadCampaign(write("late.csv", "time_s,T\n1000,20\n1060,21\n"), err); });
  EXPECT_NE(msg.find("misaligned time bases"), std::string::npos) << msg;
  msg = errorOf([&] { loadErrors(write("negU.csv", "time_s,EY0C_um,U_EY0C_um\n0,1,-1\n")); });
  EXPECT_NE(msg.find("negU.csv:2: U_EY0C_um: an expanded uncertainty cannot be negative"), std::string::npos) << msg;
  msg = errorOf([&] { loadInputs(write("notime.csv", "t,T\n0,1\n")); });
  EXPECT_NE(msg.find("the first column must be time_s"), std::string::npos) << msg;
}
