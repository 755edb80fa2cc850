#include "core/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstring>

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

bool isWordChar(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
}
std::string lowerAscii(std::string s) {
  for (auto& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}
std::size_t skipBlanks(const std::string& s, std::size_t i) {
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return i;
}

// An XML declaration's encoding="UTF-16" (or utf-16, UTF-16LE/BE, UTF16) relabelled UTF-8.
std::string relabelUtf16Declaration(std::string decl) {
  const std::size_t k = lowerAscii(decl).find("encoding");
  if (k == std::string::npos) return decl;
  std::size_t i = skipBlanks(decl, k + 8);
  if (i >= decl.size() || decl[i] != '=') return decl;
  i = skipBlanks(decl, i + 1);
  if (i >= decl.size() || (decl[i] != '"' && decl[i] != '\'')) return decl;
  const char quote = decl[i];
  const std::size_t close = decl.find(quote, i + 1);
  if (close == std::string::npos) return decl;
  const std::string value = lowerAscii(decl.substr(i + 1, close - i - 1));
  if (value != "utf-16" && value != "utf16" && value != "utf-16le" && value != "utf-16be") return decl;
  return decl.substr(0, i + 1) + "UTF-8" + decl.substr(close);
}

// The value of `key: value` or `"key": "value"` when it is a name of 1..40 word characters.
std::string nameAfter(const std::string& s, std::size_t i) {
  std::size_t e = i;
  while (e < s.size() && isWordChar(s[e]) && e - i < 41) ++e;
  return e > i && e - i <= 40 ? s.substr(i, e - i) : "";
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
      out = relabelUtf16Declaration(out.substr(0, end)) + out.substr(end);
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

namespace {

// A regular file opened for reading (`actual` may be a pending output's temporary, `path` names
// it in messages), its size checked against the cap; closed when it goes out of scope.
struct OpenInput {
  int fd = -1;
  std::size_t size = 0;
  OpenInput(const std::string& path, const std::string& actual, const InputLimit& limit) {
    const std::string problem = problemOf(actual);
    if (!problem.empty()) throw InputError(path, 0, problem);
    // O_NONBLOCK: if a FIFO took the file's place since the check, open() returns at once
    // instead of waiting for a writer; fstat below then refuses it.
    fd = ::open(actual.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd);
      throw InputError(path, 0, "is not a regular file (it changed while opened)");
    }
    size = static_cast<std::size_t>(st.st_size);
    if (size > limit.max_bytes) {
      ::close(fd);
      throw InputError(path, 0, "the file has " + mib(size) + ", more than the " + mib(limit.max_bytes) + " " + limit.what +
                                    " may have: not read (is it the right file?)");
    }
  }
  ~OpenInput() { ::close(fd); }
  OpenInput(const OpenInput&) = delete;
  OpenInput& operator=(const OpenInput&) = delete;
};

}  // namespace

std::string readFile(const std::string& path, const InputLimit& limit) {
  // An output this command wrote earlier (an open OutputBatch): its pending content.
  const std::string pending = pendingOutput(path);
  const std::string& actual = pending.empty() ? path : pending;
  const OpenInput in(path, actual, limit);
  const int fd = in.fd;
  const std::size_t size = in.size;
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

FileTail readFileTail(const std::string& path, std::size_t offset, const InputLimit& limit) {
  const OpenInput in(path, path, limit);
  const int fd = in.fd;
  FileTail t;
  t.file_size = in.size;
  if (t.file_size < offset) return t;  // shrank: the caller decides what that means
  // Only up to the size seen now: a writer appending meanwhile is read next time.
  t.bytes.resize(t.file_size - offset);
  std::size_t got = 0;
  while (got < t.bytes.size()) {
    const ssize_t n = ::pread(fd, t.bytes.data() + got, t.bytes.size() - got, static_cast<off_t>(offset + got));
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(path, 0, std::string("read failed: ") + std::strerror(errno));
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  t.bytes.resize(got);
  if (t.bytes.find('\0') != std::string::npos)
    throw InputError(path, 0, "a NUL byte after byte " + std::to_string(offset) + ": the file is not text (or was overwritten)");
  return t;
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
    const std::size_t k = head.find("\"kind\"");
    if (k != std::string::npos) {
      std::size_t i = head.find_first_not_of(" \t\r\n", k + 6);
      if (i != std::string::npos && head[i] == ':') i = head.find_first_not_of(" \t\r\n", i + 1);
      if (i != std::string::npos && head[i] == '"') {
        const std::string name = nameAfter(head, i + 1);
        if (!name.empty() && i + 1 + name.size() < head.size() && head[i + 1 + name.size()] == '"')
          return "a JSON document (kind: " + name + ")";
      }
    }
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
    first = l.substr(0, 200);
    break;
  }
  for (const char* d : {"DMISMN", "FILNAM", "DMISMD", "DMISMN/", "FILNAM/"})
    if (first.rfind(d, 0) == 0) return "a DMIS file";
  if (first.rfind("PT ", 0) == 0 || first.rfind("START ", 0) == 0) return "a probe log (PT lines)";
  // A top-level `kind: name` line.
  for (std::size_t a = 0; a < head.size();) {
    std::size_t e = head.find('\n', a);
    if (e == std::string::npos) e = head.size();
    std::string l = head.substr(a, e - a);
    a = e + 1;
    while (!l.empty() && (l.back() == '\r' || l.back() == ' ' || l.back() == '\t')) l.pop_back();
    if (l.rfind("kind:", 0) != 0) continue;
    const std::size_t i = skipBlanks(l, 5);
    const std::string name = nameAfter(l, i);
    if (!name.empty() && i + name.size() == l.size()) return "a YAML description (kind: " + name + ")";
  }
  // G-code: a first block that starts like one (a tape mark, a program number, a numbered
  // block, a G or M word, a comment, a parameter) and holds no comma.
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  const auto at = [&](std::size_t i) { return i < first.size() ? first[i] : '\0'; };
  bool gcode = false;
  if (first.find(',') == std::string::npos) {
    const char c0 = at(0), c1 = at(1);
    if (c0 == '%' || c0 == '(' || ((c0 == 'G' || c0 == 'M') && digit(c1)) || (c0 == 'O' && (digit(c1) || c1 == '<')) ||
        (c0 == '#' && (digit(c1) || c1 == '<'))) {
      gcode = true;
    } else if (c0 == 'N' && digit(c1)) {
      std::size_t i = 1;
      while (digit(at(i))) ++i;
      i = skipBlanks(first, i);
      gcode = at(i) == 'G' || at(i) == 'M' || at(i) == 'O' || at(i) == '#';
    }
  }
  if (gcode) return "a G-code program";
  if (first.find(',') != std::string::npos || first.find(';') != std::string::npos) {
    // probeloop's own tables by their header (docs/formats.md), so that a file given in
    // another's place is named: the evaluated errors, the logged inputs, probe points.
    const std::string quoted = "'" + first.substr(0, 60) + (first.size() > 60 ? "...'" : "'");
    auto has = [&](const char* column) {
      const std::string c(column);
      const std::size_t i = first.find(c);
      return i != std::string::npos && (i == 0 || first[i - 1] == ',' || first[i - 1] == ';') &&
             (i + c.size() == first.size() || first[i + c.size()] == ',' || first[i + c.size()] == ';');
    };
    if (first.rfind("time_s", 0) == 0) {
      if (has("cycle") && first.find("U_") != std::string::npos)
        return "an errors.csv of `probeloop evaluate` (first line " + quoted + ")";
      if (!has("cycle") && !has("x_mm") && (first.find("T_") != std::string::npos || has("c_rpm") || has("spindle_rpm")))
        return "an inputs.csv of logged machine inputs (first line " + quoted + ")";
    }
    if (has("x_mm") && has("y_mm") && has("z_mm")) return "a points CSV (first line " + quoted + ")";
    return "a CSV table (first line " + quoted + ")";
  }
  // `key:` or `key: value`: a YAML mapping.
  if (!first.empty() && (std::isalpha(static_cast<unsigned char>(first[0])) || first[0] == '_')) {
    std::size_t i = 0;
    while (i < first.size() && (isWordChar(first[i]) || first[i] == ' ')) ++i;
    if (i < first.size() && first[i] == ':' && (i + 1 == first.size() || first[i + 1] == ' ')) return "a YAML document";
  }
  return "";
}

std::string readProgramFile(const std::string& path) {
  std::string text = readFile(path, kProgramInput);
  // Only kinds a program cannot be mistaken for: a ';' comment line looks like a CSV table
  // and a `word:` line like YAML, so those are left to the interpreter's own messages.
  const std::string kind = describeContent(text);
  for (const char* other : {"a JSON", "a glTF", "a QIF", "an XML", "an HTML", "a YAML description", "a DMIS",
                            "a probe log", "an errors.csv", "an inputs.csv", "a points CSV"})
    if (kind.rfind(other, 0) == 0)
      throw InputError(path, 0, "this is " + kind + ", not a G-code program (.ngc for LinuxCNC, .nc for Fanuc macro B)");
  return text;
}

}  // namespace probeloop
