// The check every input-file option of the CLI makes: a readable regular file (after links),
// with the same rule and message as the readers' own opening (core/input_file.hpp), so that a
// folder, a FIFO, a device or a link loop is refused at once, naming the path (exit 2).
#pragma once
#include <CLI/CLI.hpp>
#include <string>

#include "core/input_file.hpp"

namespace probeloop::cli {

// `expected` says what the option wants ("the plan.json that `probeloop plan` wrote"), so
// that a missing file is refused with what should have been given.
inline CLI::Validator inputFile(const std::string& expected = "") {
  return CLI::Validator(
      [expected](std::string& path) {
        std::string problem = regularFileProblem(path);
        if (!problem.empty() && !expected.empty()) problem += "; expected " + expected;
        return problem;
      },
      "FILE", "InputFile");
}

}  // namespace probeloop::cli
