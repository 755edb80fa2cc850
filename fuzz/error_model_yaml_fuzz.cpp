// Error models: the error_model YAML (effects, parameters, --start-from) and the component_model YAML (regression families). Both readers see every input.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/component_model_file.hpp"
#include "parts/error_model_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess([&] { parts::loadErrorModel(path); });
  return fuzz::expectRefusalOrSuccess([&] { parts::loadComponentModel(path); });
}
