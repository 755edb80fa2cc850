// The exchange file's lenient-reader warnings (docs/interop.md#lenient-reading) in every output
// of an evaluation that used the file (issue 34): stdout (one "warning: file:line: what" line
// each), evaluation.json (an "input_warnings" array of {file, line, what}, after every other
// key) and report.md (an "Input warnings" section at its end). Without warnings nothing is
// added, so a clean file's outputs stay byte for byte what they were.
#pragma once
#include <string>
#include <vector>

#include "interop/cmm_document.hpp"

namespace probeloop::evaluate {

struct InputWarning {
  std::string file;
  int line = 0;
  std::string what;  // what was wrong; what was done
  // false: not a producer's form mistake but what the evaluation left unused (a feature stated
  // without points in a file of points, evaluate/ttp_ingest.hpp): --strict keeps it a warning,
  // and report.md says so.
  bool strict_refuses = true;
};

std::vector<InputWarning> inputWarnings(const interop::CmmDocument& d);  // d.file, each warning's line and words
std::string inputWarningText(const InputWarning& w);                     // "file:line: what"
std::string inputWarningLines(const std::vector<InputWarning>& ws);      // stdout
// evaluation_json: an object as the evaluation writers dump it (indent 1, a final newline).
std::string withInputWarnings(const std::string& evaluation_json, const std::vector<InputWarning>& ws);
std::string withInputWarningsSection(const std::string& report_md, const std::vector<InputWarning>& ws);

}  // namespace probeloop::evaluate
