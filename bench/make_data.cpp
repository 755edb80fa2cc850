// probeloop_bench_data DIR [--max-ls N] [--max-mz N]
// Writes the deterministic benchmark point files into DIR (bench_data.hpp):
//   {plane,sphere,cylinder}_{1000..10000000}.bin   least-squares fits
//   {roundness,flatness}_{100..100000}.bin          minimum-zone fits
// A file that already exists with the expected size is kept (the bytes are deterministic).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>

#include "bench/bench_data.hpp"

namespace fs = std::filesystem;
using probeloop::bench::DataKind;

namespace {

std::uintmax_t expectedBytes(DataKind kind, std::size_t n) {
  const std::uintmax_t per_point = kind == DataKind::Cylinder ? 48 : 24;
  return 256 + per_point * n;
}

void make(const fs::path& dir, DataKind kind, std::size_t n) {
  const fs::path path = dir / (std::string(probeloop::bench::dataKindName(kind)) + "_" +
                               std::to_string(n) + ".bin");
  std::error_code ec;
  if (fs::exists(path, ec) && fs::file_size(path, ec) == expectedBytes(kind, n)) return;
  probeloop::bench::writeDataSet(path.string(), probeloop::bench::generate(kind, n));
  std::printf("wrote %s\n", path.string().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DIR [--max-ls N] [--max-mz N]\n", argv[0]);
    return 2;
  }
  std::size_t max_ls = 10'000'000, max_mz = 100'000;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const auto value = static_cast<std::size_t>(std::strtoull(argv[i + 1], nullptr, 10));
    if (flag == "--max-ls") max_ls = value;
    else if (flag == "--max-mz") max_mz = value;
    else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  try {
    const fs::path dir = argv[1];
    fs::create_directories(dir);
    for (std::size_t n = 1000; n <= max_ls; n *= 10)
      for (DataKind k : {DataKind::Plane, DataKind::Sphere, DataKind::Cylinder}) make(dir, k, n);
    for (std::size_t n = 100; n <= max_mz; n *= 10)
      for (DataKind k : {DataKind::Roundness, DataKind::Flatness}) make(dir, k, n);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "probeloop_bench_data: %s\n", e.what());
    return 1;
  }
  return 0;
}
