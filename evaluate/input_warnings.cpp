#include "evaluate/input_warnings.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>

namespace probeloop::evaluate {

std::vector<InputWarning> inputWarnings(const interop::CmmDocument& d) {
  std::vector<InputWarning> out;
  for (const auto& w : d.warnings) out.push_back({d.file, w.line, w.what});
  return out;
}

std::string inputWarningText(const InputWarning& w) { return w.file + ":" + std::to_string(w.line) + ": " + w.what; }

std::string inputWarningLines(const std::vector<InputWarning>& ws) {
  std::string o;
  for (const auto& w : ws) o += "warning: " + inputWarningText(w) + "\n";
  return o;
}

std::string withInputWarnings(const std::string& evaluation_json, const std::vector<InputWarning>& ws) {
  if (ws.empty()) return evaluation_json;
  // Re-read and dumped as the writers dump it (ordered, indent 1): the other keys keep their
  // order and every number its text (nlohmann writes the shortest text that reads back).
  auto j = nlohmann::ordered_json::parse(evaluation_json);
  auto& a = j["input_warnings"] = nlohmann::ordered_json::array();
  for (const auto& w : ws) a.push_back({{"file", w.file}, {"line", w.line}, {"what", w.what}});
  return j.dump(1) + "\n";
}

std::string withInputWarningsSection(const std::string& report_md, const std::vector<InputWarning>& ws) {
  if (ws.empty()) return report_md;
  std::string o = report_md;
  if (!o.empty() && o.back() != '\n') o += "\n";
  o += "\n## Input warnings\n\n";
  const bool all_strict = std::all_of(ws.begin(), ws.end(), [](const InputWarning& w) { return w.strict_refuses; });
  const bool any_strict = std::any_of(ws.begin(), ws.end(), [](const InputWarning& w) { return w.strict_refuses; });
  if (any_strict)
    o += "The input file was read leniently (docs/interop.md#lenient-reading): each line names what its producer got wrong "
         "without changing the meaning, and what was done. `--strict` refuses the file instead.";
  if (!all_strict)
    o += std::string(any_strict ? " Lines marked (kept under `--strict`) are" : "Each line names") +
         " what the file holds and the evaluation does not use (docs/interop.md#lenient-reading): the file's meaning is whole, so "
         "`--strict` does not refuse it.";
  o += "\n\n";
  for (const auto& w : ws)
    o += "- `" + w.file + "` line " + std::to_string(w.line) + ": " + w.what + (w.strict_refuses || !any_strict ? "" : " (kept under `--strict`)") + "\n";
  return o;
}

}  // namespace probeloop::evaluate
