// GUM measurement models (kind: gum_model YAML, probeloop gum): the loader, then the law of propagation on what it accepted (expressions evaluated with automatic differentiation; no Monte Carlo, which would only measure time).
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/gum_model.hpp"
#include "uncertainty/text_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] {
    const auto model = parts::loadGumModel(path);
    uncertainty::evaluateTextModel(model, std::nullopt);
  });
}
