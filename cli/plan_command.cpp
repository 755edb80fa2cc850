// `probeloop plan`: a test piece and a machine -> programs, plan.json and the files beside it,
// written only after the safety verifier passed every program (docs/reliability.md).
#include <cstdio>
#include <memory>
#include <optional>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/paths.hpp"
#include "evaluate/piece_evaluation.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "planner/piece_plan.hpp"
#include "planner/predicted_compensation.hpp"
#include "verify/safety.hpp"

namespace probeloop::cli {
namespace {

struct PlanArgs {
  std::string piece, machine, out = ".", dialect = "machine", experiment, compensate, predict_from;
};

int runPlan(const PlanArgs& a) {
  const auto piece = parts::loadTestPiece(a.piece);
  if (!a.compensate.empty() && !a.predict_from.empty())
    throw InputError(a.predict_from, 0, "--predict-from and --compensate: give one (a prediction, or offsets already predicted)");
  std::optional<parts::SwCompensation> comp;
  if (!a.compensate.empty()) comp = parts::loadSwCompensation(a.compensate);
  const auto machine = parts::loadMachine(a.machine);
  const bool linux = a.dialect == "linuxcnc" || (a.dialect == "machine" && machine.dialect == parts::Dialect::LinuxCnc);
  const auto dialect = linux ? parts::Dialect::LinuxCnc : parts::Dialect::FanucMacroB;
  planner::TestPiecePlan plan;
  if (!a.predict_from.empty()) {
    auto predicted = planner::planWithPredictedCompensation(piece, machine, dialect, a.out, a.experiment, a.predict_from);
    std::fputs(predicted.compensation.basis.c_str(), stdout);
    plan = std::move(predicted.plan);
  } else {
    plan = planner::planTestPiece(piece, machine, dialect, a.out, a.experiment, comp ? &*comp : nullptr);
  }
  // The safety verifier reads every program as a controller would (independent of the planner):
  // any finding refuses the plan before anything is written.
  std::vector<verify::ProgramText> texts;
  for (const auto& p : plan.programs) texts.push_back({p.file, p.text});
  const auto safety = verify::checkPrograms(texts, machine, piece);
  if (!safety.safe()) {
    std::fprintf(stderr, "probeloop: error: plan refused: the safety verifier found %zu problem(s) in the programs; nothing written\n%s",
                 safety.findings.size(), verify::reportText(safety).c_str());
    return 3;
  }
  for (const auto& p : plan.programs) writeFileAtomic(pathIn(a.out, p.file), p.text);
  for (const auto& [name, content] : plan.files) writeFileAtomic(pathIn(a.out, name), content);
  writeFileAtomic(pathIn(a.out, "plan.json"), parts::manifestToJson(plan.manifest));
  std::fputs(plan.summary.c_str(), stdout);
  std::fputs(evaluate::planPrediction(plan.manifest, machine.x.resolution_mm).c_str(), stdout);
  return 0;
}

}  // namespace

Subcommand addPlanCommand(CLI::App& app) {
  auto a = std::make_shared<PlanArgs>();
  auto* plan = app.add_subcommand("plan", "Programs (G-code) and the plan manifest for a test piece: sphere artifact, thermal test piece, stepped workpiece");
  plan->add_option("piece", a->piece, "test-piece description (YAML, kind: sphere_artifact | thermal_test_piece | stepped_workpiece)")->required()->check(inputFile());
  plan->add_option("--machine", a->machine, "machine description (YAML)")->required()->check(inputFile());
  plan->add_option("--out", a->out, "output folder")->capture_default_str();
  plan->add_option("--dialect", a->dialect, "machine (from the machine file), linuxcnc or fanuc")
      ->check(CLI::IsMember({"machine", "linuxcnc", "fanuc"}))->capture_default_str();
  plan->add_option("--experiment", a->experiment, "stepped workpiece: the experiment to plan (W1 ... W8, Table 4.1)");
  plan->add_option("--predict-from", a->predict_from, "stepped workpiece: another part's evaluation.json; its separated components, "
                   "fitted against feed and Temp state, predict this experiment's wall and floor errors, which the finishing "
                   "path takes out (seed 000 Ch. 6)")->check(inputFile());
  plan->add_option("--compensate", a->compensate, "stepped workpiece: compensation.json (from evaluate): the predicted wall and "
                   "floor errors taken out of the finishing path (seed 000 Ch. 6)")->check(inputFile());
  return {plan, [a] { return runPlan(*a); }};
}

}  // namespace probeloop::cli
