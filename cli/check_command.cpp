// `probeloop check`: the safety verifier on programs as they would run back to back.
// Exit 0 safe, 3 findings (listed), 2 input the verifier cannot read or evaluate (file:line).
#include <cstdio>
#include <memory>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "parts/machine.hpp"
#include "parts/piece_kinds.hpp"
#include "verify/safety.hpp"

namespace probeloop::cli {
namespace {

struct CheckArgs {
  std::vector<std::string> programs;
  std::string machine, part;
  bool json = false;
};

int runCheck(const CheckArgs& a) {
  try {
    const auto machine = parts::loadMachine(a.machine);
    const auto piece = parts::loadTestPiece(a.part);
    std::vector<verify::ProgramText> texts;
    for (const auto& f : a.programs) texts.push_back({f, readProgramFile(f)});
    const auto r = verify::checkPrograms(texts, machine, piece);
    if (a.json) {
      std::fputs(verify::reportJson(r).c_str(), stdout);
    } else {
      std::fputs(verify::reportText(r).c_str(), stdout);
      std::printf("%s: %zu finding(s) in %zu program(s)\nmodel: %s\n", r.safe() ? "safe" : "UNSAFE", r.findings.size(),
                  r.programs.size(), r.model.c_str());
    }
    return r.safe() ? 0 : 3;
  } catch (const InputError& e) {
    std::fprintf(stderr, "probeloop: error: %s\n", e.what());
    return 2;
  }
}

}  // namespace

Subcommand addCheckCommand(CLI::App& app) {
  auto a = std::make_shared<CheckArgs>();
  auto* chk = app.add_subcommand("check", "Safety verifier: travel, collisions, probe protection, rotary moves and spindle "
                                          "checked from the program text (exit 0 safe, 3 findings, 2 bad input)");
  chk->add_option("programs", a->programs, "G-code programs (.ngc LinuxCNC, .nc Fanuc macro B), run back to back "
                  "(material cut by one is gone for the next)")->required()->check(inputFile());
  chk->add_option("--machine", a->machine, "machine description (YAML)")->required()->check(inputFile());
  chk->add_option("--part", a->part, "what stands on the table: a sphere artifact, a thermal test piece, a stepped workpiece "
                  "or a workpiece (YAML)")->required()->check(inputFile());
  chk->add_flag("--json", a->json, "the report as JSON");
  return {chk, [a] { return runCheck(*a); }};
}

}  // namespace probeloop::cli
