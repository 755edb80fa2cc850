// `probeloop separate`: the stepped workpiece campaign's separation (model/thermal_stages.hpp)
// from several parts' evaluation.json: argument parsing, reading and writing files only.
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace probeloop::cli {

// Registers the `separate` subcommand; the returned function runs it once parsed.
std::function<int()> addSeparateCommand(CLI::App& app, CLI::App*& sub);

}  // namespace probeloop::cli
