// `probeloop lathe`: the seed 002 turning centre on the virtual machine: a turning campaign's
// inputs.csv and errors.csv for `probeloop model`, and the truth behind them
// (sim/lathe_campaign.hpp; docs/lathe-seed002.md).
#include <cstdio>
#include <memory>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/paths.hpp"
#include "sim/lathe_campaign.hpp"

namespace probeloop::cli {
namespace {

struct LatheArgs {
  std::string truth, out = ".";
  std::uint64_t seed = 1;
};

int runLathe(const LatheArgs& a) {
  const auto truth = sim::loadLatheTruth(a.truth);
  const auto c = sim::simulateLatheCampaign(truth, a.seed);
  writeFileAtomic(pathIn(a.out, "inputs.csv"), c.inputs_csv);
  writeFileAtomic(pathIn(a.out, "errors.csv"), c.errors_csv);
  writeFileAtomic(pathIn(a.out, "truth.csv"), c.truth_csv);
  std::printf("Turned and measured %d parts (seed %llu) into %s: inputs.csv, errors.csv (diameter_um, face_z_um), "
              "truth.csv\n",
              c.cycles, static_cast<unsigned long long>(a.seed), a.out.c_str());
  std::printf("Resultant volumetric error |P| (seed 002 eq. 30): %.1f um warm at the cold-start load, %.1f um of it "
              "still to come after the %.1f h warm-up; largest in the campaign %.1f um\n",
              c.cold_start_resultant_um, c.after_warm_up_resultant_um, truth.cold_start_s / 3600.0,
              c.max_resultant_um);
  return 0;
}

}  // namespace

Subcommand addLatheCommand(CLI::App& app) {
  auto a = std::make_shared<LatheArgs>();
  auto* cmd = app.add_subcommand("lathe", "The seed 002 turning centre on the virtual machine: a turning campaign "
                                          "(diameter and face errors per part) for `probeloop model`");
  cmd->add_option("truth", a->truth, "lathe truth (YAML, kind: lathe_truth)")->required()->check(inputFile());
  cmd->add_option("--out", a->out, "output folder")->capture_default_str();
  cmd->add_option("--seed", a->seed, "random seed")->capture_default_str();
  return {cmd, [a] { return runLathe(*a); }};
}

}  // namespace probeloop::cli
