// Helpers of the parts/ unit tests: a shipped description with one text replaced.
#pragma once
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <unistd.h>

namespace probeloop::parts::test {

// `file` with the first `from` replaced by `to`, in a fresh temporary file (its path).
inline std::string variantOf(const std::string& file, const std::string& from, const std::string& to) {
  std::ifstream in(file);
  std::string s(std::istreambuf_iterator<char>(in), {});
  const auto at = s.find(from);
  if (at == std::string::npos) throw std::logic_error("no '" + from + "' in " + file);
  s.replace(at, from.size(), to);
  static int n = 0;
  const auto p = std::filesystem::temp_directory_path() /
                 ("probeloop-parts-" + std::to_string(::getpid()) + "-" + std::to_string(n++) + ".yaml");
  std::ofstream(p) << s;
  return p.string();
}

}  // namespace probeloop::parts::test
