// DMIS: the part program reader (.dmi) and the output reader (.dmo) see every input.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "interop/dmis.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const std::string text = fuzz::text(data, size);
  fuzz::expectRefusalOrSuccess([&] { interop::parseDmisProgram(text, "fuzz.dmi"); });
  return fuzz::expectRefusalOrSuccess([&] { interop::parseDmisOutput(text, "fuzz.dmo"); });
}
