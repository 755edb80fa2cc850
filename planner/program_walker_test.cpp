// The program walker (planner/program_walker.hpp): the simulator's clock in one place, the
// incremental C feed, the checks of every op.
#include "planner/program_walker.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

using namespace probeloop;
using namespace probeloop::planner;
using Eigen::Vector3d;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;
parts::Machine mill() { return parts::loadMachine(src + "/parts/machines/linuxcnc_rotary_mill.yaml"); }

WalkerTool cutter() {
  WalkerTool w;
  w.number = 1;
  w.length_mm = 100;
  w.radius_mm = 5;
  w.cutter = true;
  return w;
}

NotedProgram program(std::vector<gcode::Op> ops) {
  NotedProgram p;
  p.file = "p.ngc";
  for (auto& op : ops) {
    OpNote n;
    n.where = "op " + std::to_string(p.notes.size() + 1);
    p.add(std::move(op), n);
  }
  return p;
}

std::string failure(const parts::Machine& m, const NotedProgram& p) {
  try {
    ProgramWalker w(m, {cutter()});
    w.run(p);
  } catch (const SafetyError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ProgramWalker, TheClockIsTheSimulators) {
  const auto m = mill();  // rapid 4000 mm/min, C max_speed 10 rpm
  EXPECT_DOUBLE_EQ(rapidSeconds(m, Vector3d(40, -20, 10)), 0.6);             // slowest linear axis
  EXPECT_DOUBLE_EQ(rapidSeconds(m, Vector3d(4, 0, 0), 0, 90), 1.5);          // C: 90 deg at 3600 deg/min
  EXPECT_DOUBLE_EQ(rotaryIndexSeconds(-360, m.c), 6.0);
  EXPECT_DOUBLE_EQ(linearFeedSeconds(50, 1500), 2.0);
  EXPECT_DOUBLE_EQ(rotaryFeedSeconds(-720, 3600), 12.0);
}

TEST(ProgramWalker, AnIncrementalCFeedTurnsTheCommandedAmountAndIsTimedByIt) {
  auto m = mill();
  m.c.max_turning_speed_rpm = 10;
  const auto p = program({gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{1, true}, gcode::Spindle{1000},
                          gcode::RotateC{90}, gcode::TurnC{720, 3600}, gcode::TurnC{-360, 3600}, gcode::RotateC{0},
                          gcode::Spindle{0}});
  ProgramWalker w(m, {cutter()});
  std::vector<double> c_after;
  w.run(p, [&](std::size_t, double, double) { c_after.push_back(w.c()); });
  EXPECT_EQ(c_after[4], 810);
  EXPECT_EQ(c_after[5], 450);
  EXPECT_EQ(c_after[6], 0);  // a linear C turns back the long way, as the simulator does
  EXPECT_NEAR(w.times().rotary_feed_s, 12 + 6, 1e-12);
  EXPECT_NEAR(w.times().rotary_index_s, rotaryIndexSeconds(90, m.c) + rotaryIndexSeconds(450, m.c), 1e-12);
  // Above C's max_turning_speed; beyond the travel of a C that is not continuous.
  m.c.max_turning_speed_rpm = 1;
  EXPECT_NE(failure(m, p).find("p.ngc: op 5: C feed F3600.000 deg/min = 10.000 rpm exceeds C's max_turning_speed 1.000 rpm"),
            std::string::npos)
      << failure(m, p);
  m.c.max_turning_speed_rpm = 10;
  m.c.continuous = false;
  m.c.min_deg = -360;
  m.c.max_deg = 720;
  EXPECT_NE(failure(m, p).find("p.ngc: op 5: C feed move needs C = 810.000 deg, outside the C travel [-360.000, 720.000]"),
            std::string::npos)
      << failure(m, p);
}

TEST(ProgramWalker, AToolChangeNeedsTheSpindleStoppedAndTheToolChangeHeight) {
  const auto m = mill();
  EXPECT_EQ(failure(m, program({gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{1, true}})), "");
  EXPECT_NE(failure(m, program({gcode::Rapid{std::nullopt, std::nullopt, 400.0}, gcode::ToolChange{1, true}}))
                .find("p.ngc: op 2: tool change T1 with the gauge line at Z 400.000 mm, not at the tool-change height 500.000 mm"),
            std::string::npos);
  EXPECT_NE(failure(m, program({gcode::RapidMachineZ{m.tool_change.z_mm}, gcode::ToolChange{1, true}, gcode::Spindle{1000},
                                gcode::ToolChange{0, false}}))
                .find("op 4: tool change T0 with the spindle turning (M5 first)"),
            std::string::npos);
}

TEST(ProgramWalker, NumbersThatAreNotFiniteNeverPass) {
  // NotedProgram::add refuses them ...
  NotedProgram p;
  p.file = "p.ngc";
  OpNote n;
  n.where = "here";
  try {
    p.add(gcode::Feed{1.0, NAN, std::nullopt, 100}, n);
    FAIL();
  } catch (const GeometryError& e) {
    EXPECT_NE(std::string(e.what()).find("p.ngc: here: a coordinate, feed or time that is not a finite number"), std::string::npos);
  }
  // ... and the walker, for ops put in behind its back (a NaN target fails the travel test too).
  p.program.ops.push_back(gcode::Rapid{NAN, std::nullopt, std::nullopt});
  p.notes.push_back(n);
  EXPECT_NE(failure(mill(), p).find("p.ngc: here: a coordinate, feed or time that is not a finite number"), std::string::npos);
}

// The A axis of a table-table A/C machine (issue 33): indexed at its positioning speed, within
// its travel, refused on a machine without one.
TEST(ProgramWalker, TheAAxisIsTimedAndCheckedLikeB) {
  const auto ac = parts::loadMachine(src + "/parts/machines/table_table_ac.yaml");  // A 20 rpm, travel +-120 deg
  const auto p = program({gcode::RotateA{-30}, gcode::RotateA{60}});
  ProgramWalker w(ac, {cutter()});
  w.run(p);
  // 30 + 90 deg at 20 rpm = 7200 deg/min: 1 s in all.
  EXPECT_NEAR(w.times().rotary_index_s, 120.0 / 7200.0 * 60.0, 1e-12);
  EXPECT_DOUBLE_EQ(rapidSeconds(ac, Vector3d(0, 0, 0), 0, 0, 90), 0.75);
  EXPECT_NE(failure(ac, program({gcode::RotateA{130}})).find("p.ngc: op 1: A = 130.000 deg is outside the A travel"),
            std::string::npos);
  EXPECT_NE(failure(mill(), program({gcode::RotateA{10}})).find("p.ngc: op 1: A move on a machine without an A axis"),
            std::string::npos);
  EXPECT_TRUE(newNotedProgram(ac, "r", "f.ngc", 1, "t").program.has_a_axis);
  EXPECT_FALSE(newNotedProgram(mill(), "r", "f.ngc", 1, "t").program.has_a_axis);
}
