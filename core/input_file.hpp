// The one way every reader opens an input file (docs/reliability.md#opening-inputs).
//
// Contract of readFile(path, limit):
// - Regular files only, after following symbolic links: a FIFO, socket, device, directory,
//   dangling link or link loop is refused at once with an InputError naming the path and what
//   it is. The file is opened non-blocking and checked again on the open descriptor, so a FIFO
//   swapped in after the check cannot block the reader.
// - At most `limit.max_bytes` (per format, see the constants below): a larger file is refused
//   before it is read, naming its size and the cap; a file that grows past the cap while it is
//   read is refused too.
// - Encoding: UTF-8 with or without a byte-order mark (the BOM is removed). UTF-16 with a BOM
//   (LE or BE) is transcoded to UTF-8 (and an XML declaration's encoding="UTF-16" rewritten to
//   UTF-8, since the bytes now are). UTF-32 and BOM-less UTF-16 (NUL bytes in every other
//   place) are refused naming the encoding; any other NUL byte makes the file binary: refused,
//   unless the format may be binary (limit.binary: PLY).
// - The returned text is what the file says, in UTF-8; nothing else is changed.
#pragma once
#include <cstddef>
#include <string>

namespace probeloop {

struct InputLimit {
  std::size_t max_bytes;
  const char* what;  // "a YAML description", "a G-code program", ...: for the message
  bool binary = false;  // NUL bytes allowed (binary PLY); the BOM rules still apply
};

// Caps per kind of input, chosen an order of magnitude above the largest real file of the
// kind (docs/reliability.md lists the reasoning).
inline constexpr InputLimit kAnyInput{std::size_t{2} << 30, "an input file"};          // 2 GiB
inline constexpr InputLimit kYamlInput{std::size_t{16} << 20, "a YAML description"};    // 16 MiB
inline constexpr InputLimit kJsonInput{std::size_t{512} << 20, "a JSON file"};          // 512 MiB
inline constexpr InputLimit kProgramInput{std::size_t{256} << 20, "a G-code program"};  // 256 MiB
inline constexpr InputLimit kPointCloudInput{std::size_t{2} << 30, "a point cloud", true};  // 2 GiB, text or binary PLY

std::string readFile(const std::string& path, const InputLimit& limit = kAnyInput);

// The bytes a growing file (a controller log, a data logger's CSV) has from `offset` on, as they
// are (UTF-8 text: no byte-order mark handling; a NUL byte is refused), with the same checks on
// what the path is and the same cap on its whole size as readFile. A file shorter than `offset`
// gives no bytes and its size, for the caller to refuse (it was replaced or truncated).
struct FileTail {
  std::string bytes;
  std::size_t file_size = 0;
};
FileTail readFileTail(const std::string& path, std::size_t offset, const InputLimit& limit = kAnyInput);

// Empty when `path` names a readable regular file (after links); else the reason, starting
// with the path ("x.yaml: is a directory, not a file"). For command-line validation.
std::string regularFileProblem(const std::string& path);

// What a text looks like, for messages when a reader gets a file of another kind: "a QIF
// (XML) document", "a DMIS file", "a JSON document", "a YAML description (kind: ...)",
// "a LinuxCNC probe log", "a G-code program", "an errors.csv of `probeloop evaluate`",
// "an inputs.csv of logged machine inputs", "a points CSV", "a CSV table (first line ...)";
// empty when nothing is recognised.
std::string describeContent(const std::string& text);

// readFile(path, kProgramInput), refusing a file that is plainly of another kind (a plan
// manifest, a probe log, a YAML description, ...) with a sentence naming what it is.
std::string readProgramFile(const std::string& path);

}  // namespace probeloop
