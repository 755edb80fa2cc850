// `probeloop synth`: the test generator: logs of a sphere campaign with known rigid-body
// C-axis errors (sim/rigid_campaign.hpp).
#include <cstdio>
#include <memory>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/atomic_file.hpp"
#include "core/paths.hpp"
#include "parts/plan_manifest.hpp"
#include "sim/rigid_campaign.hpp"

namespace probeloop::cli {
namespace {

struct SynthArgs {
  std::string manifest, truth, out = ".";
  std::uint64_t seed = 1;
};

int runSynth(const SynthArgs& a) {
  const auto m = parts::readManifest(a.manifest);
  const auto truth = sim::loadRigidTruth(a.truth);
  const auto s = sim::synthesiseSphereCampaign(m, truth, a.seed);
  writeFileAtomic(pathIn(a.out, "sphere_probe.log"), s.linuxcnc_log);
  writeFileAtomic(pathIn(a.out, "sphere_probe_dprnt.txt"), s.fanuc_dprnt);
  writeFileAtomic(pathIn(a.out, "points.csv"), s.points_csv);
  writeFileAtomic(pathIn(a.out, "truth.json"), s.truth_json);
  std::printf("Synthesised %d cycles x %zu points (seed %llu) into %s: sphere_probe.log (LinuxCNC), "
              "sphere_probe_dprnt.txt (Fanuc), points.csv, truth.json\n",
              m.cycles, m.points.size(), static_cast<unsigned long long>(a.seed), a.out.c_str());
  return 0;
}

}  // namespace

Subcommand addSynthCommand(CLI::App& app) {
  auto a = std::make_shared<SynthArgs>();
  auto* syn = app.add_subcommand("synth", "Test generator: logs of a campaign with known rigid-body C-axis errors");
  syn->add_option("manifest", a->manifest, "plan manifest (plan.json)")->required()->check(inputFile());
  syn->add_option("--truth", a->truth, "truth description (YAML)")->required()->check(inputFile());
  syn->add_option("--out", a->out, "output folder")->capture_default_str();
  syn->add_option("--seed", a->seed, "random seed")->capture_default_str();
  return {syn, [a] { return runSynth(*a); }};
}

}  // namespace probeloop::cli
