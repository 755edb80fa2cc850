// Error types. Contract: every error a user can cause says where (file, line, field),
// what was found and what was expected; the CLI prints what() and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace probeloop {

// A message as it is printed: a quoted token ('...') of more than 120 bytes keeps its first 60
// and says how long it was, and the whole message is cut at 2000 bytes, so that a hostile
// input (a 5 MB line) cannot flood stderr; cuts fall on UTF-8 character boundaries.
inline std::string clipMessage(const std::string& m) {
  constexpr std::size_t kToken = 120, kKeep = 60, kMessage = 2000;
  auto boundary = [](const std::string& s, std::size_t n) {
    while (n > 0 && n < s.size() && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
    return n;
  };
  // A quote opens where no letter or digit stands before it and closes where none follows it,
  // so the apostrophe of "OPERATOR'S" quotes nothing.
  auto alnum = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'); };
  auto opening = [&](std::size_t from) {
    for (std::size_t k = m.find('\'', from); k != std::string::npos; k = m.find('\'', k + 1))
      if (k == 0 || !alnum(m[k - 1])) return k;
    return std::string::npos;
  };
  auto closing = [&](std::size_t from) {
    for (std::size_t k = m.find('\'', from); k != std::string::npos; k = m.find('\'', k + 1))
      if (k + 1 >= m.size() || !alnum(m[k + 1])) return k;
    return std::string::npos;
  };
  std::string out;
  std::size_t i = 0;
  while (i < m.size()) {
    const std::size_t open = opening(i);
    const std::size_t close = open == std::string::npos ? std::string::npos : closing(open + 1);
    if (close == std::string::npos) {
      out.append(m, i, std::string::npos);
      break;
    }
    out.append(m, i, open + 1 - i);
    const std::string token = m.substr(open + 1, close - open - 1);
    if (token.size() > kToken)
      out += token.substr(0, boundary(token, kKeep)) + "...' (" + std::to_string(token.size()) + " characters)";
    else
      out += token + "'";
    i = close + 1;
  }
  if (out.size() > kMessage)
    out = out.substr(0, boundary(out, kMessage)) + "... (message cut at " + std::to_string(kMessage) + " of " +
          std::to_string(out.size()) + " characters)";
  return out;
}

// Bad input: a file, a line (0 = whole file) and a message.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, int line, const std::string& message)
      : std::runtime_error(format(file, line, message)), file_(file), line_(line) {}
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  static std::string format(const std::string& file, int line, const std::string& m) {
    const std::string c = clipMessage(m);
    if (file.empty()) return c;
    return line > 0 ? file + ":" + std::to_string(line) + ": " + c : file + ": " + c;
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
  explicit SafetyError(const std::string& m) : std::runtime_error(clipMessage(m)) {}
};

}  // namespace probeloop
