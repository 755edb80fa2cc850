// The stepped workpiece's series for the model loop (model/stepped_series.hpp): two small parts
// on one clock, the gap between them, the derived columns of the step being cut, the error rows
// at the steps' cut times; hand-derived expectations.
#include "model/stepped_series.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "model/fit.hpp"

namespace probeloop::model {
namespace {

using nlohmann::json;

// A part logged every 10 s from 0 to 100 s: spindle 1000 rpm from 20 s, T_env 20 -> 21 C.
InputSeries log(const std::string& file, double T0) {
  InputSeries s;
  s.file = file;
  s.names = {"T_env_C", "spindle_rpm", "tool_changes"};
  s.columns.assign(3, {});
  s.step_s = 10;
  for (int k = 0; k <= 10; ++k) {
    s.t_s.push_back(10.0 * k);
    s.columns[0].push_back(T0 + 0.1 * k);
    s.columns[1].push_back(k >= 2 ? 1000 : 0);
    s.columns[2].push_back(k == 1 ? 1 : 0);
  }
  return s;
}

// Two steps: cut 20-50 s (mid 35) and 50-90 s (mid 70); sizes 30 and 45, tool d 10.
// Walls joined by 100 mm/min moves unless said otherwise.
json evaluation(const char* id, double feed2, const char* transition = "non_cutting", double transition_feed = 100) {
  json j{{"kind", "stepped_workpiece"}, {"experiment", id}, {"transition", transition}};
  if (std::string(transition) != "continuous") j["transition_feed_mm_per_min"] = transition_feed;
  const double start[2] = {20, 50}, end[2] = {50, 90}, T[2] = {0.25, 0.8333333333333334}, F[2] = {100, feed2};
  for (int i = 0; i < 2; ++i) {
    j["separation"].push_back({{"step", i + 1}, {"feed_mm_per_min", F[i]}, {"spindle_rpm", 1000}, {"temp_state_min", T[i]},
                               {"cut_start_s", start[i]}, {"cut_end_s", end[i]}, {"cut_mid_s", start[0] + 60 * T[i]},
                               {"travel_tool_mm", 40 + 15 * i}, {"u_cmm_width_x_um", 1.0}, {"u_cmm_width_y_um", 1.1},
                               {"u_cmm_depth_um", 0.5}});
    j["cmm"]["steps"].push_back({{"step", i + 1}, {"width_x_error_um", 3.0 + i}, {"width_y_error_um", 5.0 + i},
                                 {"depth_error_um", -1.0 - i}, {"depth_nominal_mm", 9.0 + 10 * i}});
  }
  return j;
}

TEST(SteppedSeries, TwoPartsOnOneClockWithTheGapBetween) {
  const auto s = buildSteppedSeries({{evaluation("W8", 200), "w8.json", log("w8.csv", 20)},
                                     {evaluation("W2", 400, "fast", 1200), "w2.json", log("w2.csv", 22)}},
                                    60.0);
  EXPECT_EQ(s.rows, 4);
  const auto in = parseCsv(s.inputs_csv, "inputs.csv");
  // Part 1: 11 samples 0..100 s; the gap: 6 samples 110..160 s; part 2: 11 samples from 170 s.
  ASSERT_EQ(in.rows.size(), 28u);
  const int t = in.column("time_s"), T = in.column("T_env_C"), S = in.column("spindle_rpm"), tc = in.column("tool_changes"),
            L = in.column("travel_mm"), f = in.column("chip_load_um_per_rev"), F = in.column("cut_feed_mm_per_min");
  EXPECT_DOUBLE_EQ(in.number(in.rows[17], t), 170);
  // In the gap the spindle stands and the hall goes linearly from 21 C (part 1's last) to 22 C.
  EXPECT_DOUBLE_EQ(in.number(in.rows[11], S), 0);
  EXPECT_DOUBLE_EQ(in.number(in.rows[11], tc), 0);
  EXPECT_NEAR(in.number(in.rows[11], T), 21 + 1.0 / 7, 1e-4);
  EXPECT_NEAR(in.number(in.rows[16], T), 21 + 6.0 / 7, 1e-4);
  EXPECT_DOUBLE_EQ(in.number(in.rows[20], S), 1000);
  // The step being cut: part 1 step 2 from 50 s, part 2 step 1 from 170 + 20 = 190 s.
  EXPECT_DOUBLE_EQ(in.number(in.rows[4], L), 40);
  EXPECT_DOUBLE_EQ(in.number(in.rows[5], L), 55);
  EXPECT_DOUBLE_EQ(in.number(in.rows[5], F), 200);
  EXPECT_DOUBLE_EQ(in.number(in.rows[18], L), 55);  // 180 s: part 2 has not started cutting
  EXPECT_DOUBLE_EQ(in.number(in.rows[19], L), 40);  // 190 s
  EXPECT_DOUBLE_EQ(in.number(in.rows[22], f), 400);  // 220 s: part 2 step 2, 1000 x 400 / 1000
  // The walls' joining feed: part 1's from its first step, part 2's from its first step on.
  const int tf = in.column("transition_feed_mm_per_min");
  EXPECT_DOUBLE_EQ(in.number(in.rows[0], tf), 100);
  EXPECT_DOUBLE_EQ(in.number(in.rows[18], tf), 100);
  EXPECT_DOUBLE_EQ(in.number(in.rows[19], tf), 1200);
  const auto er = parseCsv(s.errors_csv, "errors.csv");
  ASSERT_EQ(er.rows.size(), 4u);
  const int et = er.column("time_s"), wx = er.column("width_x_um"), U = er.column("U_width_y_um");
  EXPECT_NEAR(er.number(er.rows[0], et), 35, 1e-3);
  EXPECT_NEAR(er.number(er.rows[3], et), 170 + 70, 1e-3);
  EXPECT_DOUBLE_EQ(er.number(er.rows[3], wx), 4);
  EXPECT_DOUBLE_EQ(er.number(er.rows[1], U), 2.2);
  EXPECT_NE(s.model_yaml.find("width_x_um: [{effect: static, input: travel_mm}]"), std::string::npos);
  EXPECT_NE(s.model_yaml.find("training_fraction: 0.6\n"), std::string::npos);
}

// --train-parts: the first N parts' rows train, whatever 60 % would be (2 + 2 + 2 rows, N = 2:
// 4 / 6, which trainingEnd rounds back to 4); a continuous path has no transitions (0).
TEST(SteppedSeries, TheFirstPartsTrainWhenAsked) {
  const auto s = buildSteppedSeries({{evaluation("W8", 200), "w8.json", log("w8.csv", 20)},
                                     {evaluation("W6", 400), "w6.json", log("w6.csv", 22)},
                                     {evaluation("W5", 400, "continuous"), "w5.json", log("w5.csv", 24)}},
                                    60.0, 2);
  EXPECT_NE(s.model_yaml.find("training_fraction: 0.666667\n"), std::string::npos) << s.model_yaml;
  EXPECT_EQ(trainingEnd(s.rows, 0.666667), 4);
  const auto in = parseCsv(s.inputs_csv, "inputs.csv");
  EXPECT_DOUBLE_EQ(in.number(in.rows.back(), in.column("transition_feed_mm_per_min")), 0);
  EXPECT_THROW(buildSteppedSeries({{evaluation("W8", 200), "w8.json", log("w8.csv", 20)}}, 60.0, 2), InputError);
  // Every part training leaves nothing to validate on.
  EXPECT_THROW(buildSteppedSeries({{evaluation("W8", 200), "w8.json", log("w8.csv", 20)}, {evaluation("W6", 400), "w6.json", log("w6.csv", 22)}},
                                  60.0, 2),
               InputError);
  auto old = evaluation("W8", 200);
  old.erase("transition");
  EXPECT_THROW(buildSteppedSeries({{old, "w8.json", log("w8.csv", 20)}}), InputError);
}

// A compensated part was cut off nominal on purpose: its rows are the CMM's error plus the
// offsets (walls XP + XN = 1.5 + 1.5 um, YP + YN = 2 + 2, floor 0.7).
TEST(SteppedSeries, ACompensatedPartsRowsAddItsOffsetsBack) {
  auto e = evaluation("W8", 200);
  for (int i = 0; i < 2; ++i)
    e["compensation_applied"].push_back({{"step", i + 1}, {"wall_um", {{"XP", 1.5}, {"XN", 1.5}, {"YP", 2.0}, {"YN", 2.0}}}, {"floor_um", 0.7}});
  const auto s = buildSteppedSeries({{e, "w8.json", log("w8.csv", 20)}});
  const auto er = parseCsv(s.errors_csv, "errors.csv");
  EXPECT_DOUBLE_EQ(er.number(er.rows[1], er.column("width_x_um")), 4 + 3);
  EXPECT_DOUBLE_EQ(er.number(er.rows[1], er.column("width_y_um")), 6 + 4);
  EXPECT_DOUBLE_EQ(er.number(er.rows[1], er.column("depth_um")), -2 + 0.7);
}

TEST(SteppedSeries, RefusesPartsThatAreNotOneCampaign) {
  auto other = log("w6.csv", 22);
  other.names[0] = "T_hall_C";
  EXPECT_THROW(buildSteppedSeries({{evaluation("W8", 200), "w8.json", log("w8.csv", 20)}, {evaluation("W6", 400), "w6.json", other}}),
               InputError);
  auto late = evaluation("W8", 200);
  late["separation"][1]["cut_mid_s"] = 500;
  try {
    buildSteppedSeries({{late, "w8.json", log("w8.csv", 20)}});
    FAIL() << "a cut time outside its log was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("w8.json: separation[1].cut_mid_s: 500"), std::string::npos) << e.what();
  }
  auto old = evaluation("W8", 200);
  old["separation"][0].erase("cut_mid_s");
  EXPECT_THROW(buildSteppedSeries({{old, "w8.json", log("w8.csv", 20)}}), InputError);
  EXPECT_THROW(buildSteppedSeries({}), InputError);
}

}  // namespace
}  // namespace probeloop::model
