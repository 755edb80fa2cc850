// `probeloop gum`: the uncertainty of a measurement model written as text in YAML: the GUM
// budget, the Monte Carlo method and the one validated against the other (uncertainty/).
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <optional>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "parts/gum_model.hpp"

namespace probeloop::cli {
namespace {

struct GumArgs {
  std::string model;
  bool json = false, mcm = false;
  long trials = 0;
  int digits = 2;
  std::uint64_t seed = 1;
};

int runGum(const GumArgs& a) {
  const auto model = parts::loadGumModel(a.model);
  std::optional<uncertainty::McmOptions> mo;
  if (a.mcm || a.trials > 0) {
    uncertainty::McmOptions o;
    o.fixed_trials = a.trials;
    o.seed = a.seed;
    o.significant_digits = a.digits;
    if (isatty(STDERR_FILENO))  // a progress line on long runs, only for a person watching
      o.progress = [](long done) { std::fprintf(stderr, "\rMonte Carlo: %ld trials", done); };
    mo = o;
  }
  const auto r = uncertainty::evaluateTextModel(model, mo);
  if (mo && mo->progress) std::fprintf(stderr, "\r%40s\r", "");
  std::fputs((a.json ? uncertainty::textModelJson(model, r) : uncertainty::textModelReport(model, r)).c_str(), stdout);
  return 0;
}

}  // namespace

Subcommand addGumCommand(CLI::App& app) {
  auto a = std::make_shared<GumArgs>();
  auto* gum = app.add_subcommand("gum", "Uncertainty of a user measurement model (YAML): GUM budget, Monte Carlo, validation");
  gum->add_option("model", a->model, "measurement model (YAML, kind: gum_model)")->required()->check(inputFile());
  gum->add_flag("--mcm", a->mcm, "also run the Monte Carlo method (JCGM 101) and validate the GUF against it");
  gum->add_option("--trials", a->trials, "Monte Carlo trials (0: adaptive, JCGM 101 7.9)")->capture_default_str()->check(CLI::NonNegativeNumber);
  gum->add_option("--digits", a->digits, "adaptive stop: significant digits of u (n_dig)")->capture_default_str()->check(CLI::Range(1, 4));
  gum->add_option("--seed", a->seed, "random seed")->capture_default_str();
  gum->add_flag("--json", a->json, "print the results as JSON instead of the text report");
  return {gum, [a] { return runGum(*a); }};
}

}  // namespace probeloop::cli
