// QIF 3.0 documents (libxml2 underneath): the plan reader and the results reader see every input.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "interop/qif.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  const std::string text = fuzz::text(data, size);
  fuzz::expectRefusalOrSuccess([&] { interop::parseQifPlan(text, "fuzz.qif"); });
  return fuzz::expectRefusalOrSuccess([&] { interop::parseQifResults(text, "fuzz.qif"); });
}
