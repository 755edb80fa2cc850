// Test pieces as data (docs/architecture.md#how-to-add-a-test-piece): every kind of test piece - the sphere artifact, the
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

#include "model/effects.hpp"
#include "parts/feature.hpp"
#include "parts/sphere_artifact.hpp"
#include "parts/stepped_workpiece.hpp"
#include "parts/thermal_test_piece.hpp"
#include "parts/workpiece.hpp"

namespace probeloop::parts {

struct TestPiece {
  std::string kind, file, name;
  std::variant<SphereArtifact, ThermalTestPiece, SteppedWorkpiece, Workpiece> description;
  std::vector<NominalFeature> features;
  std::optional<Workpiece> stock;
  std::vector<EvaluationRule> evaluation;

  const SphereArtifact* sphereArtifact() const { return std::get_if<SphereArtifact>(&description); }
  const ThermalTestPiece* thermalTestPiece() const { return std::get_if<ThermalTestPiece>(&description); }
  const SteppedWorkpiece* steppedWorkpiece() const { return std::get_if<SteppedWorkpiece>(&description); }
};

TestPiece loadTestPiece(const std::string& path);

// The kinds loadTestPiece knows (a plain workpiece has no planner and no evaluation: it
// stands on the simulated table for a program of one's own).
const std::vector<std::string>& testPieceKinds();

// How each evaluated channel of the kind reads the part's own thermal expansion: alpha and,
// per channel (the name without its unit suffix), the signed lever L of alpha L dT (mm).
// Sphere artifact: EZ0T the centre height + the ball radius, ER0T d/2 (docs/simulator.md §3).
// Thermal test piece: EZ the Z paths' height above the table (the piece and its adapter of
// the same alloy grow: a path cut warm lies deeper at 20 °C), ETTP -2 x the facets' apothem
// (Eq. 7.3: a piece cut warm is smaller when measured cold). InputError when the description
// lacks alpha or the kind has no evaluation.
model::ExpansionLevers expansionLevers(const TestPiece& piece);

// The evaluation rules of each kind (also written into the plan manifest).
std::vector<EvaluationRule> sphereArtifactEvaluation();
std::vector<EvaluationRule> thermalTestPieceEvaluation();

}  // namespace probeloop::parts
