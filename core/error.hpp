// Error types. Contract: every error a user can cause says where (file, line, field),
// what was found and what was expected; the CLI prints what() and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace probeloop {

// Bad input: a file, a line (0 = whole file) and a message.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, int line, const std::string& message)
      : std::runtime_error(format(file, line, message)), file_(file), line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  static std::string format(const std::string& file, int line, const std::string& m) {
    if (file.empty()) return m;
    return line > 0 ? file + ":" + std::to_string(line) + ": " + m : file + ": " + m;
  }
  std::string file_;
  int line_;
};

// Degenerate geometry or an ill-posed estimation: explained, never a NaN.
class GeometryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A plan that would be unsafe to run (travel limits, collisions, clearance).
class SafetyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace probeloop
