// Controller probe logs of the sphere artifact: LinuxCNC (LOG,PT ...) and Fanuc DPRNT
// ("START <date> <time>", "PT ... <date> <time>"), parsed alone and then matched against a
// plan as `probeloop evaluate` does (every record must belong to the manifest).
#include <cstddef>
#include <cstdint>

#include "evaluate/ingest.hpp"
#include "fuzz/fixtures.hpp"
#include "fuzz/fuzz_support.hpp"
#include "gcode/probe_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".log");
  const auto& manifest = fuzz::sphereManifest();
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess([&] { gcode::parseProbeLog(fuzz::text(data, size), "fuzz.log"); });
  fuzz::expectRefusalOrSuccess(
      [&] { evaluate::readProbeRecords(path, evaluate::PointsFormat::LinuxCncLog, manifest); });
  return fuzz::expectRefusalOrSuccess(
      [&] { evaluate::readProbeRecords(path, evaluate::PointsFormat::FanucDprnt, manifest); });
}
