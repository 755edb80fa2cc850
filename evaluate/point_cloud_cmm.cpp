// `probeloop fit` on a CMM exchange file: the measured points of one feature of a QIF 3.0
// Results document or a DMIS output file (evaluate/point_cloud.hpp has the contract).
#include <algorithm>
#include <cctype>
#include <set>

#include "core/error.hpp"
#include "evaluate/point_cloud.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"

namespace probeloop::evaluate {

void readCmmExchange(PointCloud& pc, const std::string& text, const PointSelection& select) {
  const interop::CmmReadOptions options{select.strict};
  const auto d = pc.format == "qif" ? interop::parseQifResults(text, pc.file, options) : interop::parseDmisOutput(text, pc.file, options);
  for (const auto& w : d.warnings) pc.warnings.push_back(pc.file + ":" + std::to_string(w.line) + ": " + w.what);
  // Features with points, by name (a name measured in several runs counts once per run).
  std::vector<const interop::CmmFeature*> with_points;
  std::string names;
  for (const auto& f : d.features)
    if (!f.points.empty()) {
      with_points.push_back(&f);
      names += (names.empty() ? "" : ", ") + (f.name.empty() ? "(no name, line " + std::to_string(f.line) + ")" : f.name);
    }
  const std::string what = pc.format == "qif" ? "measured features with points" : "features with points";
  if (with_points.empty())
    throw InputError(pc.file, 0, "no " + what + " in the file (" + std::to_string(d.features.size()) + " features)");
  std::vector<const interop::CmmFeature*> chosen;
  if (select.feature.empty()) {
    if (with_points.size() > 1)
      throw InputError(pc.file, 0, std::to_string(with_points.size()) + " " + what + " (" + names + "): give --feature NAME");
    chosen = with_points;
  } else {
    // DMIS labels are case-insensitive (the reader keeps them upper case); QIF names are not.
    std::string want = select.feature;
    if (pc.format != "qif")
      std::transform(want.begin(), want.end(), want.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    for (const auto& f : d.features)
      if (f.name == want) chosen.push_back(&f);
    if (chosen.empty()) throw InputError(pc.file, 0, "no feature named '" + select.feature + "'; " + what + ": " + names);
    if (chosen.size() > 1)
      throw InputError(pc.file, chosen[1]->line, "feature '" + select.feature + "' is measured " + std::to_string(chosen.size()) +
                                                     " times (lines " + std::to_string(chosen[0]->line) + " and " +
                                                     std::to_string(chosen[1]->line) + "): one run per file");
    if (chosen[0]->points.empty())
      throw InputError(pc.file, chosen[0]->line, "feature '" + select.feature + "' has no measured points in the file");
  }
  for (const auto& p : chosen[0]->points) {
    pc.points_mm.push_back(p.p_mm);
    pc.source_lines.push_back(chosen[0]->line);
  }
}

}  // namespace probeloop::evaluate
