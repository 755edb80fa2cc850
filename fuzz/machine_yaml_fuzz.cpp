// Machine descriptions (kind: machine YAML).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/machine.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { parts::loadMachine(path); });
}
