// probeloop: the command line. Each subcommand is registered by its own file (commands.hpp);
// this file parses, dispatches, maps the exit codes (cli/README.md) and commits the outputs.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/model_commands.hpp"
#include "cli/report_commands.hpp"
#include "cli/separate_command.hpp"
#include "cli/version.hpp"
#include "core/atomic_file.hpp"

using namespace probeloop;

int main(int argc, char** argv) {
  probeloop::removeTemporaryFileOnInterrupt();
  CLI::App app{"probeloop: plan, simulate and evaluate touch-probe cycles for machine-tool metrology"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string(cli::versionText()));

  std::vector<cli::Subcommand> commands{cli::addPlanCommand(app),     cli::addReadCommand(app),
                                        cli::addResolutionCommand(app), cli::addSynthCommand(app),
                                        cli::addSimulateCommand(app), cli::addCheckCommand(app),
                                        cli::addEvaluateCommand(app), cli::addFitCommand(app),
                                        cli::addGumCommand(app),      cli::addCampaignCommands(app),
                                        cli::addLatheCommand(app)};
  cli::Subcommand model, report, separate;
  model.run = cli::addModelCommands(app, model.app);
  report.run = cli::addReportCommands(app, report.app);
  separate.run = cli::addSeparateCommand(app, separate.app);
  commands.insert(commands.end(), {model, report, separate});

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11's own codes (105 for a file option, 106 for a number...) are not ours: every usage
    // error, an input path that is not a readable regular file included, exits 2 (cli/README.md).
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  try {
    // All of a command's outputs or none (docs/reliability.md#all-or-nothing): the files are
    // written as temporaries and renamed into place only after the command succeeded.
    OutputBatch outputs;
    for (const auto& c : commands) {
      if (!*c.app) continue;
      const int code = c.run();
      if (code == 0) outputs.commit();
      return code;
    }
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "probeloop: error: %s\n", e.what());
    return 1;
  }
}
