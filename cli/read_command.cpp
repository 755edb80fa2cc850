// `probeloop read`: what is in a CMM exchange file (QIF 3.0 Results or Plan, DMIS output or
// program): results when the file has any, a plan (its nominals and planned points) otherwise.
#include <cstdio>
#include <memory>

#include "cli/commands.hpp"
#include "cli/input_option.hpp"
#include "core/error.hpp"
#include "core/input_file.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "interop/summary.hpp"

namespace probeloop::cli {
namespace {

struct ReadArgs {
  std::string file;
  bool json = false, strict = false;
};

int runRead(const ReadArgs& a) {
  const std::string text = readFile(a.file);
  if (!interop::looksLikeDmis(text) && text.find_first_not_of(" \t\r\n\xEF\xBB\xBF") != std::string::npos &&
      text[text.find_first_not_of(" \t\r\n\xEF\xBB\xBF")] != '<') {
    const std::string kind = describeContent(text);
    throw InputError(a.file, 0, "this is " + (kind.empty() ? std::string("not a file probeloop recognises") : kind) +
                                    "; `probeloop read` reads QIF 3.0 (XML) and DMIS files");
  }
  if (interop::looksLikeDmis(text)) {  // a program (DMISMN: its nominals and PTMEAS points) or output (FILNAM)
    const bool program = interop::isDmisProgram(text);
    const auto d = program ? interop::parseDmisProgram(text, a.file, interop::CmmReadOptions{a.strict})
                           : interop::parseDmisOutput(text, a.file, interop::CmmReadOptions{a.strict});
    std::fputs((a.json ? interop::cmmDocumentJson(d) : interop::cmmDocumentText(d)).c_str(), stdout);
    return 0;
  }
  auto d = interop::parseQifResults(text, a.file, interop::CmmReadOptions{a.strict});
  if (d.runs == 0 && d.features.empty()) {
    try {
      d = interop::parseQifPlan(text, a.file);
    } catch (const InputError&) {  // no feature nominals either: the empty results say so
    }
  }
  std::fputs((a.json ? interop::cmmDocumentJson(d) : interop::cmmDocumentText(d)).c_str(), stdout);
  return 0;
}

}  // namespace

Subcommand addReadCommand(CLI::App& app) {
  auto a = std::make_shared<ReadArgs>();
  auto* rd = app.add_subcommand("read", "What probeloop reads in a CMM exchange file (QIF 3.0 Results or Plan, DMIS output or "
                                "program): features, points, units");
  rd->add_option("file", a->file, "QIF 3.0 or DMIS file")->required()->check(inputFile());
  rd->add_flag("--json", a->json, "print JSON (every feature with its geometry and points, in mm; the warnings)");
  rd->add_flag("--strict", a->strict, "refuse what the lenient reader reads with a warning, at its line (QIF: element order, a "
               "dangling or self-referencing id, an unknown extension, a missing PointList; DMIS: a missing ENDFIL or ENDMES, "
               "statements after ENDFIL, a label defined again)");
  return {rd, [a] { return runRead(*a); }};
}

}  // namespace probeloop::cli
