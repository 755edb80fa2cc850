// `probeloop report ttp|stepped|sphere`: argument parsing, reading and writing files only; the
// pages and the scene are made in report/ (ttp_report, ttp_scene, sw_report, sphere_report).
#pragma once
#include <CLI/CLI.hpp>
#include <functional>

namespace probeloop::cli {

// Registers the `report` subcommand group; the returned function runs the parsed one.
std::function<int()> addReportCommands(CLI::App& app, CLI::App*& group);

}  // namespace probeloop::cli
