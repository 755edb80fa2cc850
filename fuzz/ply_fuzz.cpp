// PLY point clouds (probeloop fit): ascii, binary_little_endian, binary_big_endian headers and bodies.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "evaluate/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".ply");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { evaluate::readPointCloud(path, "ply"); });
}
