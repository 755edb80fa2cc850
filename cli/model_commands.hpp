// `probeloop model fit|compare|diagnose|add|talc`: argument parsing and file writing only; the
// decisions are in model/ (fit, diagnose, outputs) and parts/ (the model file).
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace probeloop::cli {

// Registers the `model` subcommand group; the returned function runs the parsed one.
std::function<int()> addModelCommands(CLI::App& app, CLI::App*& group);

}  // namespace probeloop::cli
