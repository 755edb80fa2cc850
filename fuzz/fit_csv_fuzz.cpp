// Point-cloud CSV (probeloop fit): x_mm,y_mm,z_mm or x,y,z, optional nx,ny,nz, a feature filter.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.hpp"
#include "evaluate/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace probeloop;
  if (size > fuzz::kMaxInput) return 0;
  static fuzz::ScratchFile file(".csv");
  const std::string& path = file.write(data, size);
  fuzz::expectRefusalOrSuccess([&] { evaluate::readPointCloud(path, "csv"); });
  fuzz::expectRefusalOrSuccess([&] { evaluate::readPointCloud(path, "csv", {"S1", ""}); });
  return fuzz::expectRefusalOrSuccess([&] { evaluate::readPointCloud(path, "csv", {"S1", "2"}); });
}
