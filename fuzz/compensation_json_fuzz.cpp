// Stepped-workpiece compensation files (compensation.json, probeloop plan --compensate; a user may write one by hand).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/sw_compensation.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".json");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { parts::loadSwCompensation(path); });
}
