// Test pieces as data (DESIGN.md §9): every kind of test piece - the sphere artifact, the
// thermal test piece, a plain workpiece for a program of one's own, and whatever comes next -
// is loaded into this one model, which the layers below read: the planner turns it into
// programs and a manifest, the simulator machines and measures it, the evaluation fits its
// features and applies its formulas.
//
// Contract: loadTestPiece reads `kind:` and hands the file to that kind's loader (strict,
// InputError with file:line); an unknown kind is refused naming the kinds there are. The
// model then holds, for every kind:
// - `description`: the kind's own description, as its YAML schema gives it;
// - `features`: the nominal features in the part frame (parts/feature.hpp);
// - `stock`: what the simulator machines (blank, holes, collision bodies, material, tools,
//   CMM), or nothing for an artifact that is only probed;
// - `evaluation`: which features give which error by which formula, with its source.
// Adding a kind: docs/test-pieces.md.
#pragma once
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "parts/feature.hpp"
#include "parts/sphere_artifact.hpp"
#include "parts/thermal_test_piece.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::parts {

struct TestPiece {
  std::string kind, file, name;
  std::variant<SphereArtifact, ThermalTestPiece, Workpiece> description;
  std::vector<NominalFeature> features;
  std::optional<Workpiece> stock;
  std::vector<EvaluationRule> evaluation;

  const SphereArtifact* sphereArtifact() const { return std::get_if<SphereArtifact>(&description); }
  const ThermalTestPiece* thermalTestPiece() const { return std::get_if<ThermalTestPiece>(&description); }
};

TestPiece loadTestPiece(const std::string& path);

// The kinds loadTestPiece knows, and for each whether it has a planner and an evaluation
// (a plain workpiece has neither: it stands on the simulated table for a program of one's own).
struct TestPieceKind {
  std::string kind;
  bool plannable = false;
};
const std::vector<TestPieceKind>& testPieceKinds();

// The evaluation rules of each kind (also written into the plan manifest).
std::vector<EvaluationRule> sphereArtifactEvaluation();
std::vector<EvaluationRule> thermalTestPieceEvaluation();

}  // namespace probeloop::parts
