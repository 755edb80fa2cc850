// The kind dispatch every `probeloop plan` goes through (planner/piece_plan.hpp).
#include "planner/piece_plan.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "planner/sphere_cycle.hpp"

using namespace probeloop;
using namespace probeloop::planner;

namespace {
const std::string src = PROBELOOP_SOURCE_DIR;
parts::Machine machine(const std::string& name) { return parts::loadMachine(src + "/parts/machines/" + name + ".yaml"); }
}  // namespace

TEST(PlanTestPiece, TheSphereArtifactIsPlannedByTheSphereCycleByteForByte) {
  const auto piece = parts::loadTestPiece(src + "/parts/sphere_artifact.yaml");
  const auto artifact = parts::loadSphereArtifact(src + "/parts/sphere_artifact.yaml");
  for (const char* name : {"nmv5000", "linuxcnc_rotary_mill"})
    for (auto d : {parts::Dialect::LinuxCnc, parts::Dialect::FanucMacroB}) {
      const auto m = machine(name);
      const auto plan = planTestPiece(piece, m, d, "out");
      PlanFiles files;
      files.program_file = d == parts::Dialect::LinuxCnc ? "sphere_cycle.ngc" : "sphere_cycle.nc";
      auto ref = planSphereCycle(artifact, m, files);
      ref.manifest.dialect = parts::dialectName(d);
      ref.manifest.programs.front().dialect = ref.manifest.dialect;
      ASSERT_EQ(plan.programs.size(), 1u);
      EXPECT_EQ(plan.programs[0].file, files.program_file);
      EXPECT_EQ(plan.programs[0].text, programText(ref, d));
      EXPECT_EQ(parts::manifestToJson(plan.manifest), parts::manifestToJson(ref.manifest));
      ASSERT_EQ(plan.files.size(), 1u);
      EXPECT_EQ(plan.files[0].first, "probe_plan.qif");
      EXPECT_EQ(plan.summary.rfind("Planned " + std::to_string(ref.manifest.cycles) + " cycles of the sphere cycle for " + m.name, 0), 0u);
      EXPECT_NE(plan.summary.find("  wrote out/" + files.program_file + " and out/plan.json\n"), std::string::npos) << plan.summary;
      const std::string tail = "  (no acceleration; see docs/sphere-cycle.md for the comparison with 95 s)\n"
                               "  the probing plan as QIF 3.0: out/probe_plan.qif\n";
      EXPECT_EQ(plan.summary.substr(plan.summary.size() - tail.size()), tail);
      EXPECT_NEAR(plan.programs[0].duration_s,
                  ref.manifest.cycles * ref.cycle_time.total() + (ref.manifest.cycles - 1) * ref.manifest.gap_s, 1e-9);
    }
}

TEST(PlanTestPiece, APlainWorkpieceHasNoPlanner) {
  const auto piece = parts::loadTestPiece(src + "/examples/workpiece_block.yaml");
  try {
    planTestPiece(piece, machine("vmc3"), parts::Dialect::LinuxCnc);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("workpiece_block.yaml: a plain workpiece has no planner: write its program yourself and "
                                         "run it with probeloop simulate"),
              std::string::npos)
        << e.what();
  }
}

// Issue 14 in progress: the description loads, planning says what is missing, nothing written.
// A stepped workpiece is planned one experiment at a time: without one the refusal lists them;
// an experiment given for another kind is refused too; with W8 the three programs, the CMM plan
// and a summary with each step's Temp state.
TEST(PlanTestPiece, TheSteppedWorkpieceIsPlannedPerExperiment) {
  const auto piece = parts::loadTestPiece(src + "/parts/stepped_workpiece.yaml");
  auto refusal = [&](const parts::TestPiece& p, const std::string& e) {
    try {
      planTestPiece(p, machine("vmc3"), parts::Dialect::LinuxCnc, "out", e);
    } catch (const InputError& x) {
      return std::string(x.what());
    }
    return std::string("(planned)");
  };
  EXPECT_NE(refusal(piece, "").find("choose the experiment to plan with --experiment (one of W1, W2, W3, W4, W5, W6, W7, W8)"),
            std::string::npos);
  const auto ttp = parts::loadTestPiece(src + "/parts/thermal_test_piece.yaml");
  EXPECT_NE(refusal(ttp, "W8").find("--experiment W8: only a stepped workpiece has experiments"), std::string::npos);
  const auto plan = planTestPiece(piece, machine("vmc3"), parts::Dialect::FanucMacroB, "out", "W8");
  ASSERT_EQ(plan.programs.size(), 3u);
  EXPECT_EQ(plan.programs[0].file, "roughing.nc");
  EXPECT_EQ(plan.programs[2].file, "probing.nc");
  ASSERT_EQ(plan.files.size(), 3u);
  EXPECT_EQ(plan.files[0].first, "cmm_points.csv");
  EXPECT_EQ(plan.files[1].first, "cmm_plan.qif");
  EXPECT_EQ(plan.files[2].first, "cmm_plan.dmi");
  EXPECT_EQ(plan.manifest.kind, "stepped_workpiece");
  for (const char* s : {"Planned experiment W8", "O3002", "step 4: feed XY 800 / Z 800 mm/min, 3500 rpm", "T = "})
    EXPECT_NE(plan.summary.find(s), std::string::npos) << s << "\n" << plan.summary;
  // The manifest's stepped-workpiece block survives its JSON round trip.
  const auto path = std::filesystem::temp_directory_path() / "probeloop-sw-plan.json";
  std::ofstream(path) << parts::manifestToJson(plan.manifest);
  const auto back = parts::readManifest(path.string());
  EXPECT_EQ(back.sw.experiment, "W8");
  ASSERT_EQ(back.sw.steps.size(), 4u);
  EXPECT_DOUBLE_EQ(back.sw.steps[3].feed_xy_mm_per_min, 800);
  EXPECT_DOUBLE_EQ(back.sw.steps[2].temp_state_min, plan.manifest.sw.steps[2].temp_state_min);
  EXPECT_EQ(back.points.size(), plan.manifest.points.size());
  std::filesystem::remove(path);
}

TEST(PlanTestPiece, TheThermalTestPieceGivesThreeProgramsTheCmmPlanAndASummary) {
  const auto piece = parts::loadTestPiece(src + "/parts/thermal_test_piece.yaml");
  const auto plan = planTestPiece(piece, machine("nmv5000"), parts::Dialect::FanucMacroB, "plan");
  ASSERT_EQ(plan.programs.size(), 3u);
  const char* files[3] = {"pre_machining.nc", "thermal_test.nc", "inspection.nc"};
  const char* roles[3] = {"pre_machining", "test", "inspection"};
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(plan.programs[i].file, files[i]);
    EXPECT_EQ(plan.programs[i].role, roles[i]);
    EXPECT_EQ(plan.programs[i].text.rfind("%\nO" + std::to_string(2001 + i) + " (", 0), 0u);
    EXPECT_EQ(plan.manifest.programs[i].file, files[i]);
    EXPECT_NEAR(plan.manifest.programs[i].start_s, plan.programs[i].start_s, 1e-12);
  }
  EXPECT_EQ(plan.manifest.programs[2].log_file, "ttp_probe.log");
  EXPECT_EQ(plan.manifest.programs[0].log_file, "");
  ASSERT_EQ(plan.files.size(), 3u);
  EXPECT_EQ(plan.files[2].first, "cmm_plan.dmi");
  EXPECT_NE(plan.files[2].second.find("\nF(CYL)=FEAT/CYLNDR,OUTER,CART,"), std::string::npos);
  EXPECT_EQ(plan.files[0].first, "cmm_points.csv");
  EXPECT_NE(plan.files[0].second.find("feature,point,x_mm,y_mm,z_mm,nx,ny,nz\nTOP,1,"), std::string::npos);
  EXPECT_EQ(plan.files[1].first, "cmm_plan.qif");
  // The datum band CYL is a boss (its outward normals point away from the axis); the QIF plan
  // names every feature of the CSV (checked against the schema in tests/integration/cmm_interop_cli.py).
  EXPECT_NE(plan.files[1].second.find("<InternalExternal>EXTERNAL</InternalExternal>"), std::string::npos);
  EXPECT_EQ(plan.files[1].second.find("INTERNAL"), std::string::npos);
  EXPECT_NE(plan.files[1].second.find("<FeatureName>X2_9</FeatureName>"), std::string::npos);
  for (const char* s : {"45 measurement surfaces: 9 Z paths (12 mm pitch) + 36 facets (4 x 9, 6 deg pitch)",
                        "8 waits of 3600 s + 9 cutting cycles", "Inspection: 364 points", "plan/cmm_points.csv, plan/cmm_plan.qif, plan/cmm_plan.dmi and plan/plan.json",
                        "C at 1200 rpm (180 x 200 turns forward and back)"})
    EXPECT_NE(plan.summary.find(s), std::string::npos) << s << "\n" << plan.summary;
  // The LinuxCNC dialect of the same machine: .ngc files, the inspection log opened by name.
  const auto lc = planTestPiece(piece, machine("nmv5000"), parts::Dialect::LinuxCnc);
  EXPECT_EQ(lc.programs[2].file, "inspection.ngc");
  EXPECT_NE(lc.programs[2].text.find("(LOGOPEN,ttp_probe.log)\n#<_pl_cycle> = 1\n"), std::string::npos);
  EXPECT_EQ(lc.manifest.dialect, "linuxcnc");
}

// The planner uses the loaded model's features and evaluation rules, not a second computation.
TEST(PlanTestPiece, TheThermalTestPiecesFeaturesAndEvaluationComeFromTheLoadedModel) {
  auto piece = parts::loadTestPiece(src + "/parts/thermal_test_piece.yaml");
  piece.features.front().half_u_mm = 42.5;  // TOP, as the model has it
  piece.evaluation = {piece.evaluation.front()};
  piece.evaluation.front().formula = "as loaded";
  const auto plan = planTestPiece(piece, machine("nmv5000"), parts::Dialect::FanucMacroB);
  ASSERT_EQ(plan.manifest.features.size(), piece.features.size());
  EXPECT_EQ(plan.manifest.features.front().nominal.id, "TOP");
  EXPECT_EQ(plan.manifest.features.front().nominal.half_u_mm, 42.5);
  ASSERT_EQ(plan.manifest.evaluation.size(), 1u);
  EXPECT_EQ(plan.manifest.evaluation.front().formula, "as loaded");
  for (std::size_t i = 0; i < piece.features.size(); ++i) EXPECT_EQ(plan.manifest.features[i].nominal.id, piece.features[i].id);
}
