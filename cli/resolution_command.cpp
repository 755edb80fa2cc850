// `probeloop resolution`: the location errors' resolution for a coordinate step (seed 004
// Table 5.4) and the U a sphere campaign's plan predicts.
#include <cstdio>
#include <memory>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "evaluate/piece_evaluation.hpp"
#include "evaluate/sphere_campaign.hpp"
#include "parts/machine.hpp"
#include "parts/sphere_artifact.hpp"
#include "planner/sphere_cycle.hpp"

namespace probeloop::cli {
namespace {

struct ResolutionArgs {
  std::string artifact, machine;
  double step_um = 1.0;
};

int runResolution(const ResolutionArgs& a) {
  const auto plan = planner::planSphereCycle(parts::loadSphereArtifact(a.artifact), parts::loadMachine(a.machine));
  std::fputs((evaluate::sphereResolutionText(evaluate::locationErrorResolution(plan.manifest, a.step_um * 1e-3), a.step_um) +
              evaluate::spherePredictionText(plan.manifest))
                 .c_str(),
             stdout);
  return 0;
}

}  // namespace

Subcommand addResolutionCommand(CLI::App& app) {
  auto a = std::make_shared<ResolutionArgs>();
  auto* res = app.add_subcommand("resolution", "Resolution of the location errors (seed 004 Table 5.4)");
  res->add_option("artifact", a->artifact, "sphere artifact description (YAML)")->required()->check(inputFile());
  res->add_option("--machine", a->machine, "machine description (YAML)")->required()->check(inputFile());
  res->add_option("--step-um", a->step_um, "coordinate step, um")->capture_default_str()->check(CLI::PositiveNumber);
  return {res, [a] { return runResolution(*a); }};
}

}  // namespace probeloop::cli
