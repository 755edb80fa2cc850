// What every harness shares: the input cap, the fuzz input as a string or as a file for the
// readers that take a path, and the one rule of what counts as a bug.
//
// Contract of a harness: LLVMFuzzerTestOneInput hands the input to a reader and returns 0. A
// std::exception (InputError, GeometryError, ExpressionError, YAML::Exception, ...) is the
// reader refusing bad input: expected. A crash, a sanitizer report, a hang, a leak or any
// other exception escaping is a bug in the reader.
#pragma once
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>

namespace probeloop::fuzz {

// Inputs above this are skipped: a reader's cost grows with its input and a 10 MB input would
// only measure the harness (scripts/fuzz.sh passes the same -max_len).
constexpr std::size_t kMaxInput = 64 * 1024;

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A scratch file of this process, rewritten for every input, removed at exit.
class ScratchFile {
 public:
  explicit ScratchFile(const std::string& extension) {
    const char* dir = std::getenv("TMPDIR");
    path_ = std::string(dir && *dir ? dir : "/tmp") + "/probeloop_fuzz_" + std::to_string(getpid()) +
            "_" + std::to_string(counter()++) + extension;
  }
  ~ScratchFile() { std::remove(path_.c_str()); }
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;

  const std::string& write(const std::uint8_t* data, std::size_t size) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    out.close();
    if (!out) {
      std::fprintf(stderr, "fuzz harness: cannot write %s\n", path_.c_str());
      std::abort();  // the harness, not the reader, failed: stop rather than fuzz nothing
    }
    return path_;
  }
  const std::string& path() const { return path_; }

 private:
  static int& counter() {
    static int n = 0;
    return n;
  }
  std::string path_;
};

// Runs one reader call; a std::exception is the expected refusal of bad input.
template <class F>
int expectRefusalOrSuccess(F&& read) {
  try {
    read();
  } catch (const std::exception&) {
    // bad input, refused with an error: the contract
  }
  return 0;
}

}  // namespace probeloop::fuzz
