#include "cli/separate_command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli/json_file.hpp"
#include "core/atomic_file.hpp"
#include "model/thermal_stages.hpp"

namespace probeloop::cli {
namespace {

struct SeparateArgs {
  std::vector<std::string> stages;
  std::string process, out = "separation";
};

int run(const SeparateArgs& a) {
  std::vector<std::pair<nlohmann::json, std::string>> parts;
  for (const auto& f : a.stages) parts.emplace_back(readJsonFile(f), f);
  const auto st = model::thermalStagesFromEvaluations(parts);
  std::vector<model::ProcessStep> process;
  nlohmann::json pe;
  if (!a.process.empty()) {
    pe = readJsonFile(a.process);
    process = model::separateProcess(st, pe, a.process);
  }
  // Everything computed before the first file is written.
  const std::string json = model::separationJson(st, process, a.process.empty() ? nullptr : &pe, a.process);
  const std::string csv = model::separationCsv(st, process);
  std::filesystem::create_directories(a.out);
  writeFileAtomic((std::filesystem::path(a.out) / "separation.json").string(), json);
  writeFileAtomic((std::filesystem::path(a.out) / "separation.csv").string(), csv);
  std::fputs(model::separationSummary(st, process).c_str(), stdout);
  std::printf("  wrote separation.json, separation.csv in %s\n", a.out.c_str());
  return 0;
}

}  // namespace

std::function<int()> addSeparateCommand(CLI::App& app, CLI::App*& sub) {
  auto a = std::make_shared<SeparateArgs>();
  sub = app.add_subcommand("separate",
                           "Stepped workpiece campaign: thermal stages (parts cut at one feed and speed: W1, W4, W6, W7) and the "
                           "process error of a part cut at changing feeds (W8) with the thermal error taken out");
  sub->add_option("--stage", a->stages, "evaluation.json of a thermal-stage part (repeat; parts at one speed are pooled)")
      ->required()->check(CLI::ExistingFile);
  sub->add_option("--process", a->process, "evaluation.json of the part cut at changing feeds (W8)")->check(CLI::ExistingFile);
  sub->add_option("--out", a->out, "output folder")->capture_default_str();
  return [a] { return run(*a); };
}

}  // namespace probeloop::cli
