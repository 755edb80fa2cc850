#include "core/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <regex>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace probeloop {
namespace {

std::string mib(std::size_t bytes) {
  if (bytes < (std::size_t{1} << 20)) return std::to_string(bytes) + " bytes";
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  return b;
}

// What is wrong with `path` as an input file, without the path; empty when it is a regular file.
std::string problemOf(const std::string& path) {
  if (path.empty()) return "no file named (an empty file name)";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    struct stat lst {};
    if (err == ELOOP) return "is a loop of symbolic links, not a file";
    if (err == ENOENT && ::lstat(path.c_str(), &lst) == 0 && S_ISLNK(lst.st_mode))
      return "is a symbolic link to nothing (its target does not exist)";
    if (err == ENOENT) return "does not exist";
    if (err == ENOTDIR) return "does not exist (a part of the path is not a folder)";
    return std::string("cannot be read: ") + std::strerror(err);
  }
  if (S_ISREG(st.st_mode)) return ::access(path.c_str(), R_OK) == 0 ? "" : "cannot be read: permission denied";
  if (S_ISDIR(st.st_mode)) return "is a folder, not a file";
  if (S_ISFIFO(st.st_mode))
    return "is a named pipe (FIFO), not a regular file: probeloop reads whole files, not streams";
  if (S_ISSOCK(st.st_mode)) return "is a socket, not a regular file";
  if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) return "is a device, not a regular file";
  return "is not a regular file";
}

void appendUtf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

// UTF-16 (after its BOM) to UTF-8; an odd length or a lone surrogate is refused.
std::string fromUtf16(const std::string& path, const std::string& raw, bool little_endian) {
  const char* name = little_endian ? "UTF-16LE" : "UTF-16BE";
  if ((raw.size() - 2) % 2 != 0)
    throw InputError(path, 0, std::string("the file is ") + name + " (byte-order mark) but has an odd number of bytes: truncated?");
  std::string out;
  out.reserve(raw.size() / 2);
  auto unit = [&](std::size_t i) -> std::uint32_t {
    const auto a = static_cast<unsigned char>(raw[i]), b = static_cast<unsigned char>(raw[i + 1]);
    return little_endian ? (a | (b << 8)) : ((a << 8) | b);
  };
  for (std::size_t i = 2; i < raw.size(); i += 2) {
    std::uint32_t u = unit(i);
    if (u >= 0xD800 && u <= 0xDBFF && i + 3 < raw.size()) {
      const std::uint32_t lo = unit(i + 2);
      if (lo >= 0xDC00 && lo <= 0xDFFF) {
        appendUtf8(out, 0x10000 + ((u - 0xD800) << 10) + (lo - 0xDC00));
        i += 2;
        continue;
      }
    }
    if (u >= 0xD800 && u <= 0xDFFF)
      throw InputError(path, 0, std::string("the file is ") + name + " but has a lone surrogate at byte " + std::to_string(i) +
                                    ": not valid UTF-16");
    appendUtf8(out, u);
  }
  // The XML declaration named the encoding the bytes had; they are UTF-8 now.
  if (out.rfind("<?xml", 0) == 0) {
    const std::size_t end = out.find("?>");
    if (end != std::string::npos && end < 400) {
      static const std::regex enc(R"(encoding\s*=\s*(["'])[Uu][Tt][Ff]-?16(?:[LlBb][Ee])?(["']))");
      out = std::regex_replace(out.substr(0, end), enc, "encoding=$1UTF-8$2") + out.substr(end);
    }
  }
  return out;
}

std::string decode(const std::string& path, std::string raw, bool binary) {
  auto starts = [&](const char* b, std::size_t n) { return raw.size() >= n && std::memcmp(raw.data(), b, n) == 0; };
  if (starts("\xFF\xFE\x00\x00", 4) || starts("\x00\x00\xFE\xFF", 4))
    throw InputError(path, 0, std::string("the file is UTF-32") + (raw[0] == '\xFF' ? "LE" : "BE") +
                                  " (byte-order mark): probeloop reads UTF-8 or UTF-16; save it as UTF-8");
  if (starts("\xFF\xFE", 2) || starts("\xFE\xFF", 2)) {
    std::string text = fromUtf16(path, raw, raw[0] == '\xFF');
    const std::size_t nul = binary ? std::string::npos : text.find('\0');
    if (nul != std::string::npos)
      throw InputError(path, 0, "a NUL character at character " + std::to_string(nul) + " of the UTF-16 text: not a text file");
    return text;
  }
  if (starts("\xEF\xBB\xBF", 3)) raw.erase(0, 3);
  const std::size_t nul = binary ? std::string::npos : raw.find('\0');
  if (nul != std::string::npos) {
    std::string kind = "binary data, not text";
    if (raw.size() >= 4 && raw[0] != '\0' && raw[1] == '\0' && raw[2] != '\0' && raw[3] == '\0')
      kind = "UTF-16LE text without a byte-order mark; save it as UTF-8 (or UTF-16 with the mark)";
    else if (raw.size() >= 4 && raw[0] == '\0' && raw[1] != '\0' && raw[2] == '\0' && raw[3] != '\0')
      kind = "UTF-16BE text without a byte-order mark; save it as UTF-8 (or UTF-16 with the mark)";
    throw InputError(path, 0, "a NUL byte at byte " + std::to_string(nul) + ": the file looks like " + kind);
  }
  return raw;
}

}  // namespace

std::string regularFileProblem(const std::string& path) {
  const std::string p = problemOf(path);
  return p.empty() ? p : path + ": " + p;
}

std::string readFile(const std::string& path, const InputLimit& limit) {
  // An output this command wrote earlier (an open OutputBatch): its pending content.
  const std::string pending = pendingOutput(path);
  const std::string& actual = pending.empty() ? path : pending;
  const std::string problem = problemOf(actual);
  if (!problem.empty()) throw InputError(path, 0, problem);
  // O_NONBLOCK: if a FIFO took the file's place since the check, open() returns at once
  // instead of waiting for a writer; fstat below then refuses it.
  const int fd = ::open(actual.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) throw InputError(path, 0, "is not a regular file (it changed while opened)");
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size > limit.max_bytes)
    throw InputError(path, 0, "the file has " + mib(size) + ", more than the " + mib(limit.max_bytes) + " " + limit.what +
                                  " may have: not read (is it the right file?)");
  std::string raw;
  raw.resize(size + 1);  // one byte more: a file that grew while being read is noticed
  std::size_t got = 0;
  for (;;) {
    if (got == raw.size()) {
      if (raw.size() > limit.max_bytes)
        throw InputError(path, 0, "the file grew past the " + mib(limit.max_bytes) + " " + limit.what + " may have while it was read");
      raw.resize(std::min(limit.max_bytes + 1, raw.size() * 2 + 4096));
    }
    const ssize_t n = ::read(fd, raw.data() + got, raw.size() - got);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, 0, std::string("read failed: ") + std::strerror(errno));
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  raw.resize(got);
  return decode(path, std::move(raw), limit.binary);
}

std::string describeContent(const std::string& text) {
  std::size_t p = text.find_first_not_of(" \t\r\n");
  if (p == std::string::npos) return text.empty() ? "an empty file" : "a file of blanks only";
  const std::string head = text.substr(p, 8192);
  if (head[0] == '<') {
    if (head.find("QIFDocument") != std::string::npos) return "a QIF (XML) document";
    if (head.find("<gltf") != std::string::npos || head.find("<html") != std::string::npos ||
        head.find("<!DOCTYPE html") != std::string::npos)
      return "an HTML page";
    return "an XML document";
  }
  if (head[0] == '{' || head[0] == '[') {
    static const std::regex kind(R"re("kind"\s*:\s*"([A-Za-z0-9_]{1,40})")re");
    std::smatch m;
    if (std::regex_search(head, m, kind)) return "a JSON document (kind: " + m[1].str() + ")";
    if (head.find("\"asset\"") != std::string::npos) return "a glTF scene (JSON)";
    return "a JSON document";
  }
  // The first line that is not a comment or blank.
  std::size_t q = 0;
  std::string first;
  while (q < head.size()) {
    std::size_t e = head.find('\n', q);
    if (e == std::string::npos) e = head.size();
    std::string l = head.substr(q, e - q);
    q = e + 1;
    while (!l.empty() && (l.back() == '\r' || l.back() == ' ' || l.back() == '\t')) l.pop_back();
    if (l.empty() || l[0] == '#' || l == "%") continue;  // '%': a Fanuc tape mark (programs and DPRNT captures)
    first = l.substr(0, 200);  // the regexes below recurse per character
    break;
  }
  for (const char* d : {"DMISMN", "FILNAM", "DMISMD", "DMISMN/", "FILNAM/"})
    if (first.rfind(d, 0) == 0) return "a DMIS file";
  if (first.rfind("PT ", 0) == 0 || first.rfind("START ", 0) == 0) return "a probe log (PT lines)";
  static const std::regex yaml_kind(R"(^kind:\s*([A-Za-z0-9_]{1,40})\s*\r?$)");
  std::smatch m;
  for (std::size_t a = 0; a < head.size();) {
    std::size_t e = head.find('\n', a);
    if (e == std::string::npos) e = head.size();
    const std::string l = head.substr(a, e - a);
    if (std::regex_search(l, m, yaml_kind)) return "a YAML description (kind: " + m[1].str() + ")";
    a = e + 1;
  }
  static const std::regex gcode(R"(^(%|O[0-9<]|N[0-9]+ *[GMO#]|G[0-9]|M[0-9]|\(|#[0-9<])[^,]*$)");
  if (std::regex_search(first, gcode)) return "a G-code program";
  if (first.find(',') != std::string::npos || first.find(';') != std::string::npos)
    return "a CSV table (first line '" + first.substr(0, 60) + (first.size() > 60 ? "...'" : "'") + ")";
  static const std::regex yaml_key(R"(^[A-Za-z_][A-Za-z0-9_ ]*:( |$))");
  if (std::regex_search(first, yaml_key)) return "a YAML document";
  return "";
}

}  // namespace probeloop
