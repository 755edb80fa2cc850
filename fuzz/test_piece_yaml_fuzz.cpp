// Test-piece descriptions: loadTestPiece reads kind: and hands the file to the sphere artifact, thermal test piece, stepped workpiece or workpiece loader.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "parts/piece_kinds.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".yaml");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { parts::loadTestPiece(path); });
}
