// A file inside an output folder, as the commands name their outputs ("out/plan.json").
#pragma once
#include <filesystem>
#include <string>

namespace probeloop {

inline std::string pathIn(const std::string& dir, const std::string& file) {
  return (std::filesystem::path(dir) / file).string();
}

}  // namespace probeloop
