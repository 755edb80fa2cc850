// The model's campaign files: inputs CSV (time_s + one column per signal, uniform grid) and error series CSV (time_s, cycle, channels, U_ columns). Both readers see every input.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "model/dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".csv");
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess([&] { model::loadInputs(path); });
  return fuzz::expectRefusalOrSuccess([&] { model::loadErrors(path); });
}
