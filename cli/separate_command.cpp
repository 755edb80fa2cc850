#include "cli/separate_command.hpp"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli/input_option.hpp"
#include "parts/json_file.hpp"
#include "core/atomic_file.hpp"
#include "model/control_errors.hpp"
#include "model/thermal_stages.hpp"

namespace probeloop::cli {
using parts::readJsonFile;
namespace {

struct SeparateArgs {
  std::vector<std::string> stages;
  std::string process, control, force, out = "separation";
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
  std::optional<model::ControlSeparation> control;
  if (!a.control.empty() || !a.force.empty()) {
    const nlohmann::json ce = a.control.empty() ? nlohmann::json() : readJsonFile(a.control);
    const nlohmann::json fe = a.force.empty() ? nlohmann::json() : readJsonFile(a.force);
    control = model::separateControl(st, pe, a.process, a.control.empty() ? nullptr : &ce, a.control,
                                     a.force.empty() ? nullptr : &fe, a.force);
  }
  // Everything computed before the first file is written.
  const nlohmann::json cj = control ? model::controlJson(*control) : nlohmann::json();
  const std::string json = model::separationJson(st, process, a.process.empty() ? nullptr : &pe, a.process, control ? &cj : nullptr);
  const std::string csv = model::separationCsv(st, process);
  const std::string ccsv = control ? model::controlCsv(*control) : std::string();
  std::filesystem::create_directories(a.out);
  writeFileAtomic((std::filesystem::path(a.out) / "separation.json").string(), json);
  writeFileAtomic((std::filesystem::path(a.out) / "separation.csv").string(), csv);
  if (control) writeFileAtomic((std::filesystem::path(a.out) / "control.csv").string(), ccsv);
  else std::filesystem::remove(std::filesystem::path(a.out) / "control.csv");  // not a stale one from an earlier run
  std::fputs(model::separationSummary(st, process).c_str(), stdout);
  if (control) std::fputs(model::controlSummary(*control).c_str(), stdout);
  std::printf("  wrote separation.json, separation.csv%s in %s\n", control ? ", control.csv" : "", a.out.c_str());
  return 0;
}

}  // namespace

std::function<int()> addSeparateCommand(CLI::App& app, CLI::App*& sub) {
  auto a = std::make_shared<SeparateArgs>();
  sub = app.add_subcommand("separate",
                           "Stepped workpiece campaign: thermal stages (parts cut at one feed and speed: W1, W4, W6, W7) and the "
                           "process error of a part cut at changing feeds (W8) with the thermal error taken out");
  sub->add_option("--stage", a->stages, "evaluation.json of a thermal-stage part (repeat; parts at one speed are pooled)")
      ->required()->check(cli::inputFile());
  sub->add_option("--process", a->process, "evaluation.json of the part cut at changing feeds (W8)")->check(cli::inputFile());
  sub->add_option("--control", a->control,
                  "evaluation.json of a part whose walls are joined by fast transitions (W2): its control error e_ctrl "
                  "against the process part (Eq. 3.11-3.14)")
      ->check(cli::inputFile());
  sub->add_option("--force", a->force,
                  "evaluation.json of a part cut as one continuous path (W5): its control error under the process force "
                  "e_cpr against the process part (Eq. 3.15)")
      ->check(cli::inputFile());
  sub->get_option("--control")->needs(sub->get_option("--process"));
  sub->get_option("--force")->needs(sub->get_option("--process"));
  sub->add_option("--out", a->out, "output folder")->capture_default_str();
  return [a] { return run(*a); };
}

}  // namespace probeloop::cli
