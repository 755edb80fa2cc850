// The thermal test piece's CMM export (CSV surface points: labels or nominal-geometry
// assignment) and dial-gauge readings (CSV facet,g_um) against its plan.
#include <cstddef>
#include <cstdint>

#include "evaluate/ttp_ingest.hpp"
#include "fuzz/fixtures.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const auto& manifest = fuzz::ttpManifest();
  const std::string text = fuzz::text(data, size);
  fuzz::expectRefusalOrSuccess([&] { evaluate::readTtpCmmExport("cmm_export.csv", text, manifest); });
  return fuzz::expectRefusalOrSuccess([&] { evaluate::readTtpGauge("gauge.csv", text, manifest); });
}
