#include "report/evaluation_scene.hpp"

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "report/scene.hpp"
#include "report/ttp_scene.hpp"

namespace probeloop::report {

double defaultSceneExaggeration(const evaluate::EvaluationFiles& f) { return f.sphere ? 10000.0 : 1000.0; }

std::string evaluationSceneGltf(const parts::PlanManifest& manifest, const evaluate::EvaluationFiles& f,
                                const std::string& input_file, double exaggeration) {
  if (f.thermal_test_piece && f.thermal_test_piece->route == evaluate::TtpRoute::Gauge)
    throw InputError(input_file, 0, "--scene: dial-gauge readings give no measured surfaces to draw (use a CMM export or an on-machine log)");
  if (f.sphere) {
    std::vector<CycleCentres> cycles;
    for (const auto& c : f.sphere->cycles) {
      CycleCentres x;
      x.cycle = c.cycle;
      for (const auto& s : c.spheres) x.centre_mm.push_back(s.centre_mm());
      cycles.push_back(x);
    }
    return campaignSceneGltf(manifest, cycles, f.sphere->reference_cycle, exaggeration);
  }
  return thermalTestPieceSceneGltf(manifest, nlohmann::json::parse(f.evaluation_json), exaggeration);
}

}  // namespace probeloop::report
