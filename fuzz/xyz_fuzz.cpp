// XYZ point clouds (probeloop fit): one point per line, blanks or commas, # comments.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "evaluate/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".xyz");
  const std::string& path = file.write(data, size);
  return fuzz::expectRefusalOrSuccess([&] { evaluate::readPointCloud(path, "xyz"); });
}
