// Shared by the sim/ tests: temporary files and truths written from YAML text.
#pragma once
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

#include "sim/machine_truth.hpp"

namespace probeloop::sim::test {

inline std::string src(const std::string& rel) { return std::string(PROBELOOP_SOURCE_DIR) + "/" + rel; }

// A fresh folder per call, so tests running in parallel never share a file.
inline std::filesystem::path tempDir() {
  static std::atomic<int> n{0};
  const auto d = std::filesystem::temp_directory_path() /
                 ("probeloop-sim-" + std::to_string(::getpid()) + "-" + std::to_string(n++));
  std::filesystem::create_directories(d);
  return d;
}

inline std::string writeTemp(const std::string& name, const std::string& text) {
  const auto p = tempDir() / name;
  std::ofstream(p) << text;
  return p.string();
}

inline MachineTruth truthFrom(const std::string& yaml) {
  return loadMachineTruth(writeTemp("truth.yaml", "kind: machine_truth\n" + yaml));
}

}  // namespace probeloop::sim::test
