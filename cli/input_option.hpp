// The check every input-file option of the CLI makes: a readable regular file (after links),
// with the same rule and message as the readers' own opening (core/input_file.hpp), so that a
// folder, a FIFO, a device or a link loop is refused at once, naming the path (exit 2).
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "core/input_file.hpp"

namespace probeloop::cli {

inline CLI::Validator inputFile() {
  return CLI::Validator([](std::string& path) { return regularFileProblem(path); }, "FILE", "InputFile");
}

}  // namespace probeloop::cli
