// Plan manifests (plan.json, written by probeloop plan, read by evaluate and simulate).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/plan_manifest.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".json");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { parts::readManifest(path); });
}
