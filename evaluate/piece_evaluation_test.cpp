// The kind dispatch of `probeloop evaluate` / `probeloop plan`: unknown kinds and options of the
// other kind are refused. The sphere artifact's outputs are not compared with earlier ones here or
// in any automated check (they go through the same writers, evaluate/outputs.cpp; a byte-for-byte
// comparison with the previous CLI was made by hand when the dispatch was introduced).
#include "evaluate/piece_evaluation.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"

namespace probeloop::evaluate {
namespace {

std::string refusal(const parts::PlanManifest& m, const EvaluateRequest& r) {
  try {
    evaluateTestPiece(m, r);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(TestPieceDispatch, UnknownKindsAndMisplacedOptionsAreRefused) {
  parts::PlanManifest m;
  m.file = "plan.json";
  m.kind = "gear";
  EvaluateRequest r;
  r.input_file = "points.csv";
  EXPECT_NE(refusal(m, r).find("plan.json: manifest kind 'gear': plans are made for sphere_artifact, thermal_test_piece and stepped_workpiece"),
            std::string::npos);
  m.kind = "stepped_workpiece";
  EXPECT_NE(refusal(m, r).find("points.csv: the stepped workpiece is evaluated from its CMM export and its on-machine probe log together"),
            std::string::npos);
  EXPECT_EQ(planPrediction(m, 0.001), "");
  m.kind = "sphere_artifact";
  r.compare_with = "other/evaluation.json";
  EXPECT_NE(refusal(m, r).find("--compare applies to the thermal test piece"), std::string::npos);
}

}  // namespace
}  // namespace probeloop::evaluate
