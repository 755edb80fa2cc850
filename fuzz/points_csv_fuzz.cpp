// The canonical points CSV (docs/formats.md#points-csv) against the sphere artifact's plan:
// labels, C angles, repeats, nearest planned points, separators and decimal commas; the same
// bytes also as a cycle-starts file (`evaluate --cycle-starts`, CSV cycle,start_s).
#include <cstddef>
#include <cstdint>

#include "evaluate/ingest.hpp"
#include "fuzz/fixtures.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".csv");
  const auto& manifest = fuzz::sphereManifest();
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess(
      [&] { evaluate::readProbeRecords(path, evaluate::PointsFormat::PointsCsv, manifest); });
  fuzz::expectRefusalOrSuccess([&] { evaluate::readProbeRecords(path, evaluate::PointsFormat::Auto, manifest); });
  return fuzz::expectRefusalOrSuccess([&] {
    parts::PlanManifest m = manifest;
    evaluate::applyCycleStarts(m, path);
  });
}
