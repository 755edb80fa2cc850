// The subcommands of `probeloop`, one file each (cli/<name>_command.cpp, model_commands.cpp,
// report_commands.cpp, separate_command.cpp). Each registers its options on `app`, with
// variables of its own (none shared between subcommands), and returns the action that runs
// it when it was the one parsed. Argument parsing, printing and file writing only: what a
// command computes lives in the library that owns it.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace probeloop::cli {

struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

Subcommand addPlanCommand(CLI::App& app);
Subcommand addReadCommand(CLI::App& app);
Subcommand addResolutionCommand(CLI::App& app);
Subcommand addSynthCommand(CLI::App& app);
Subcommand addLatheCommand(CLI::App& app);  // the seed 002 turning centre's campaign
Subcommand addSimulateCommand(CLI::App& app);
Subcommand addCheckCommand(CLI::App& app);
Subcommand addEvaluateCommand(CLI::App& app);
Subcommand addFitCommand(CLI::App& app);
Subcommand addGumCommand(CLI::App& app);
Subcommand addCampaignCommands(CLI::App& app);  // campaign init | ingest | status | export

}  // namespace probeloop::cli
