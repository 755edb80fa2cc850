#include "sim/run_inputs.hpp"

#include <filesystem>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "parts/plan_manifest.hpp"
#include "sim/cmm_stage.hpp"

namespace probeloop::sim {

void loadCmmRequest(SimulationPart& part, const std::string& file) {
  const std::string text = readFile(file);
  if (interop::looksLikeQif(text) || interop::looksLikeDmis(text)) {  // a QIF plan or a DMIS program: answered in both
    // A program that drives the (virtual) CMM is read strictly, as a controller would run it:
    // the lenient reading (docs/interop.md#lenient-reading) is for results.
    part.cmm_plan = interop::looksLikeQif(text) ? interop::parseQifPlan(text, file)
                                                : interop::parseDmisProgram(text, file, interop::CmmReadOptions{true});
    part.cmm_points = cmmPointsOfQifPlan(*part.cmm_plan);
  } else {
    part.cmm_points = readCmmPoints(file);
  }
  part.cmm_points_file = file;
}

void scheduleFromManifest(std::vector<ProgramSource>& programs, const std::string& manifest_file) {
  const auto m = parts::readManifest(manifest_file);
  for (auto& p : programs) {
    const std::string name = std::filesystem::path(p.file).filename().string();
    std::string planned;
    for (const auto& mp : m.programs) {
      if (mp.file == name) p.start_s = mp.start_s;
      planned += (planned.empty() ? "" : ", ") + mp.file;
    }
    if (!p.start_s)
      throw InputError(manifest_file, 0, "programs[].file: '" + name + "' is not planned here (the manifest plans " + planned + ")");
  }
}

}  // namespace probeloop::sim
