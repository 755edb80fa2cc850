#include "evaluate/point_cloud.hpp"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"

namespace probeloop::evaluate {
namespace {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string extensionFormat(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const std::string ext = dot == std::string::npos ? "" : lower(path.substr(dot + 1));
  if (ext == "csv") return "csv";
  if (ext == "ds") return "ds";
  if (ext == "xyz" || ext == "txt" || ext == "asc") return "xyz";
  if (ext == "ply") return "ply";
  if (ext == "qif") return "qif";
  if (ext == "dmo") return "dmis";
  throw InputError(path, 0, "cannot tell the point format from the extension '." + ext +
                                "'; give --format csv|ds|xyz|ply|qif|dmis");
}

// Splits a line on blanks and commas.
std::vector<std::string> tokens(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (std::isspace(static_cast<unsigned char>(c)) || c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

Eigen::Vector3d threeNumbers(const std::vector<std::string>& t, const std::string& file, int line) {
  if (t.size() < 3)
    throw InputError(file, line, "expected 3 coordinates x y z, found " + std::to_string(t.size()) +
                                     " field(s)");
  Eigen::Vector3d p;
  static const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k)
    if (!parseFiniteNumber(t[static_cast<size_t>(k)], p[k]))
      throw InputError(file, line, std::string(names[k]) + ": '" + t[static_cast<size_t>(k)] +
                                       "' is not a finite number");
  return p;
}

// "S1, S2, S3 … S5" for a hint: the distinct values of a column in file order.
std::string listValues(const std::vector<std::string>& values) {
  std::string out;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i == 3 && values.size() > 4) return out + " ... " + values.back();
    out += (i ? ", " : "") + values[i];
  }
  return out;
}

void readCsv(PointCloud& pc, const std::string& text, const PointSelection& select) {
  const std::string& feature = select.feature;
  const CsvTable t = parseCsv(text, pc.file);
  auto col = [&](const char* a, const char* b) {
    const int c = t.column(a);
    return c >= 0 ? c : t.column(b);
  };
  const int cx = col("x_mm", "x"), cy = col("y_mm", "y"), cz = col("z_mm", "z");
  if (cx < 0 || cy < 0 || cz < 0)
    throw InputError(pc.file, t.header_line,
                     "header needs columns x_mm,y_mm,z_mm (or x,y,z); found " +
                         std::to_string(t.header.size()) + " columns");
  const int nx = t.column("nx"), ny = t.column("ny"), nz = t.column("nz");
  const bool has_n = nx >= 0 && ny >= 0 && nz >= 0;
  if (!has_n && (nx >= 0 || ny >= 0 || nz >= 0))
    throw InputError(pc.file, t.header_line, "approach direction needs all of nx,ny,nz");
  const int cf = t.column("feature");
  if (!feature.empty() && cf < 0)
    throw InputError(pc.file, t.header_line, "--feature given but the file has no 'feature' column");
  const int cc = t.column("cycle");
  if (!select.cycle.empty() && cc < 0)
    throw InputError(pc.file, t.header_line, "--cycle given but the file has no 'cycle' column");
  // A campaign file (simulate's points.csv, a probe log turned CSV) holds several features and
  // cycles; fitting them as one cloud gives a meaningless element, so the file must be narrowed.
  auto distinct = [&](int column) {
    std::vector<std::string> values;
    if (column < 0) return values;
    for (const auto& row : t.rows) {
      const std::string& v = row.fields[static_cast<size_t>(column)];
      if (std::find(values.begin(), values.end(), v) == values.end()) values.push_back(v);
    }
    return values;
  };
  const auto features = distinct(cf), cycles = distinct(cc);
  if (feature.empty() && features.size() > 1)
    throw InputError(pc.file, t.header_line,
                     "the file holds " + std::to_string(features.size()) + " features (" + listValues(features) +
                         "): choose one with --feature NAME" +
                         (cycles.size() > 1 ? " and one of its " + std::to_string(cycles.size()) +
                                                  " cycles with --cycle N"
                                            : ""));
  if (select.cycle.empty() && cycles.size() > 1)
    throw InputError(pc.file, t.header_line,
                     "the file holds " + std::to_string(cycles.size()) + " cycles (" + listValues(cycles) +
                         "): choose one with --cycle N");
  for (const auto& row : t.rows) {
    if (!feature.empty() && row.fields[static_cast<size_t>(cf)] != feature) continue;
    if (!select.cycle.empty() && row.fields[static_cast<size_t>(cc)] != select.cycle) continue;
    pc.points_mm.emplace_back(t.number(row, cx), t.number(row, cy), t.number(row, cz));
    pc.source_lines.push_back(row.line);
    if (has_n) {
      const Eigen::Vector3d n(t.number(row, nx), t.number(row, ny), t.number(row, nz));
      if (std::abs(n.norm() - 1.0) > 1e-3)
        throw InputError(pc.file, row.line, "approach direction nx,ny,nz must be a unit vector (length " +
                                                formatNumber(n.norm(), 6) + ")");
      pc.approach.push_back(n);
    }
  }
  if (!feature.empty() && std::find(features.begin(), features.end(), feature) == features.end())
    throw InputError(pc.file, 0, "no rows with feature '" + feature + "'; the file's features: " + listValues(features));
  if (!select.cycle.empty() && std::find(cycles.begin(), cycles.end(), select.cycle) == cycles.end())
    throw InputError(pc.file, 0, "no rows of cycle " + select.cycle + "; the file's cycles: " + listValues(cycles));
  if (pc.points_mm.empty())
    throw InputError(pc.file, 0, "no rows of feature '" + feature + "' in cycle " + select.cycle);
}

// The largest count of points or PLY elements a header may declare (far above any cloud that
// fits in memory); larger ones are refused before they are converted to an integer.
constexpr double kMaxCount = 2147483647.0;

void readDs(PointCloud& pc, const std::string& text) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  long expected = -1;
  while (std::getline(in, line)) {
    ++n;
    const auto t = tokens(line);
    if (t.empty()) continue;
    if (expected < 0) {
      double v = 0;
      // Bounded before the conversion: a count beyond long was undefined behaviour (fuzz/nist_ds).
      if (t.size() != 1 || !parseFiniteNumber(t[0], v) || v < 1 || v != std::floor(v) || v > kMaxCount)
        throw InputError(pc.file, n, "NIST .ds: the first line must be the number of points (a whole number from 1 to " +
                                         formatNumber(kMaxCount) + "), found '" + line + "'");
      expected = static_cast<long>(v);
      continue;
    }
    if (t.size() != 3) throw InputError(pc.file, n, "NIST .ds: expected 'x y z'");
    pc.points_mm.push_back(threeNumbers(t, pc.file, n));
    pc.source_lines.push_back(n);
  }
  if (expected < 0) throw InputError(pc.file, 0, "NIST .ds: empty file");
  if (static_cast<long>(pc.points_mm.size()) != expected)
    throw InputError(pc.file, 1, "NIST .ds: header says " + std::to_string(expected) +
                                     " points, the file has " + std::to_string(pc.points_mm.size()));
}

void readXyz(PointCloud& pc, const std::string& text) {
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    const auto t = tokens(line);
    if (t.empty()) continue;
    pc.points_mm.push_back(threeNumbers(t, pc.file, n));
    pc.source_lines.push_back(n);
  }
}

// --- PLY -------------------------------------------------------------------------------
struct PlyProperty {
  std::string name, type, count_type;  // count_type non-empty for lists
};
struct PlyElement {
  std::string name;
  long count = 0;
  std::vector<PlyProperty> properties;
};

int plyTypeSize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

double plyBinary(const unsigned char* p, const std::string& t, bool big) {
  unsigned char b[8];
  const int n = plyTypeSize(t);
  std::memcpy(b, p, static_cast<size_t>(n));
  if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
  if (t == "char" || t == "int8") { std::int8_t v; std::memcpy(&v, b, 1); return v; }
  if (t == "uchar" || t == "uint8") { std::uint8_t v; std::memcpy(&v, b, 1); return v; }
  if (t == "short" || t == "int16") { std::int16_t v; std::memcpy(&v, b, 2); return v; }
  if (t == "ushort" || t == "uint16") { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
  if (t == "int" || t == "int32") { std::int32_t v; std::memcpy(&v, b, 4); return v; }
  if (t == "uint" || t == "uint32") { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
  if (t == "float" || t == "float32") { float v; std::memcpy(&v, b, 4); return v; }
  double v;
  std::memcpy(&v, b, 8);
  return v;
}

void readPly(PointCloud& pc, const std::string& text) {
  size_t pos = 0;
  int line_no = 0;
  auto nextLine = [&]() -> std::string {
    if (pos >= text.size()) throw InputError(pc.file, line_no, "PLY header ends without 'end_header'");
    const size_t e = text.find('\n', pos);
    std::string l = text.substr(pos, e == std::string::npos ? std::string::npos : e - pos);
    pos = e == std::string::npos ? text.size() : e + 1;
    ++line_no;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    return l;
  };
  if (nextLine() != "ply") throw InputError(pc.file, 1, "not a PLY file: first line must be 'ply'");
  std::string encoding;
  std::vector<PlyElement> elements;
  for (;;) {
    const std::string l = nextLine();
    const auto t = tokens(l);
    if (t.empty()) continue;
    if (t[0] == "end_header") break;
    if (t[0] == "comment" || t[0] == "obj_info") continue;
    if (t[0] == "format") {
      if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" &&
                            t[1] != "binary_big_endian"))
        throw InputError(pc.file, line_no, "PLY format must be ascii, binary_little_endian or "
                                           "binary_big_endian");
      encoding = t[1];
    } else if (t[0] == "element") {
      double c = 0;
      // A whole count within kMaxCount: 1e20 was converted to long unchecked (fuzz/ply).
      if (t.size() != 3 || !parseFiniteNumber(t[2], c) || c < 0 || c != std::floor(c) || c > kMaxCount)
        throw InputError(pc.file, line_no, "PLY: expected 'element <name> <count>' with a whole count from 0 to " +
                                               formatNumber(kMaxCount) + ", found '" + l + "'");
      elements.push_back({t[1], static_cast<long>(c), {}});
    } else if (t[0] == "property") {
      if (elements.empty()) throw InputError(pc.file, line_no, "PLY: property before any element");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        p = {t[4], t[3], t[2]};
      } else if (t.size() == 3) {
        p = {t[2], t[1], ""};
      } else {
        throw InputError(pc.file, line_no, "PLY: expected 'property <type> <name>'");
      }
      if (plyTypeSize(p.type) == 0 || (!p.count_type.empty() && plyTypeSize(p.count_type) == 0))
        throw InputError(pc.file, line_no, "PLY: unknown property type '" + p.type + "'");
      // A list's length is an integer (PLY); a float count read as a size was undefined (fuzz/ply).
      if (!p.count_type.empty() && (p.count_type.rfind("float", 0) == 0 || p.count_type == "double"))
        throw InputError(pc.file, line_no, "PLY: the count type of list '" + p.name +
                                               "' must be an integer type, found '" + p.count_type + "'");
      elements.back().properties.push_back(p);
    } else {
      throw InputError(pc.file, line_no, "PLY: unexpected header line '" + l + "'");
    }
  }
  if (encoding.empty()) throw InputError(pc.file, 0, "PLY: no 'format' line in the header");
  const bool ascii = encoding == "ascii";
  const bool big = encoding == "binary_big_endian";
  const auto vertex_it = std::find_if(elements.begin(), elements.end(),
                                      [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex_it == elements.end()) throw InputError(pc.file, 0, "PLY: no 'vertex' element");
  int ix = -1, iy = -1, iz = -1;
  for (size_t k = 0; k < vertex_it->properties.size(); ++k) {
    const auto& p = vertex_it->properties[k];
    if (!p.count_type.empty()) continue;
    if (p.name == "x") ix = static_cast<int>(k);
    if (p.name == "y") iy = static_cast<int>(k);
    if (p.name == "z") iz = static_cast<int>(k);
  }
  if (ix < 0 || iy < 0 || iz < 0)
    throw InputError(pc.file, 0, "PLY: the vertex element needs scalar properties x, y and z");

  std::istringstream ain;
  if (ascii) ain.str(text.substr(pos));
  for (const auto& el : elements) {
    const bool is_vertex = &el == &*vertex_it;
    if (!ascii) {
      // Each entry takes at least this many bytes; a count the data cannot hold is refused here,
      // before a loop of 2^31 empty entries (a hang, fuzz/ply).
      std::size_t least = 0;
      for (const auto& p : el.properties)
        least += static_cast<std::size_t>(plyTypeSize(p.count_type.empty() ? p.type : p.count_type));
      if (least == 0) continue;  // no properties: nothing to read
      if (static_cast<std::size_t>(el.count) > (text.size() - pos) / least)
        throw InputError(pc.file, 0, "PLY: binary data ends inside element '" + el.name + "': it declares " +
                                         std::to_string(el.count) + " entries of at least " + std::to_string(least) +
                                         " bytes, " + std::to_string(text.size() - pos) + " bytes are left");
    }
    for (long i = 0; i < el.count; ++i) {
      Eigen::Vector3d v = Eigen::Vector3d::Zero();
      if (ascii) {
        std::string l;
        do {
          if (!std::getline(ain, l))
            throw InputError(pc.file, line_no, "PLY: file ends inside element '" + el.name + "'");
          ++line_no;
        } while (tokens(l).empty());
        const auto t = tokens(l);
        size_t at = 0;
        for (size_t k = 0; k < el.properties.size(); ++k) {
          const auto& p = el.properties[k];
          double val = 0;
          auto take = [&]() {
            if (at >= t.size() || !parseFiniteNumber(t[at], val))
              throw InputError(pc.file, line_no, "PLY: element '" + el.name + "' property '" +
                                                     p.name + "': expected a finite number");
            ++at;
          };
          take();
          if (!p.count_type.empty()) {
            // Checked before the conversion: 1e300 was undefined, a negative count read nothing.
            if (val < 0 || val != std::floor(val) || val > static_cast<double>(t.size() - at))
              throw InputError(pc.file, line_no, "PLY: element '" + el.name + "' list '" + p.name + "': count " +
                                                     t[at - 1] + " is not a whole number of the " +
                                                     std::to_string(t.size() - at) + " values left on the line");
            const long cnt = static_cast<long>(val);
            for (long j = 0; j < cnt; ++j) take();
          } else if (is_vertex) {
            if (static_cast<int>(k) == ix) v.x() = val;
            if (static_cast<int>(k) == iy) v.y() = val;
            if (static_cast<int>(k) == iz) v.z() = val;
          }
        }
        if (is_vertex) pc.source_lines.push_back(line_no);
      } else {
        for (size_t k = 0; k < el.properties.size(); ++k) {
          const auto& p = el.properties[k];
          auto need = [&](size_t bytes) {
            if (bytes > text.size() - pos)
              throw InputError(pc.file, 0, "PLY: binary data ends inside element '" + el.name +
                                               "' number " + std::to_string(i + 1));
          };
          if (!p.count_type.empty()) {
            const size_t cs = static_cast<size_t>(plyTypeSize(p.count_type));
            need(cs);
            const double cnt = plyBinary(reinterpret_cast<const unsigned char*>(text.data() + pos),
                                         p.count_type, big);
            pos += cs;
            // A negative count became a huge size_t (undefined, then pos wrapped: fuzz/ply).
            if (cnt < 0)
              throw InputError(pc.file, 0, "PLY: element '" + el.name + "' number " + std::to_string(i + 1) +
                                               " list '" + p.name + "': negative count " + formatNumber(cnt));
            const size_t bytes = static_cast<size_t>(cnt) * static_cast<size_t>(plyTypeSize(p.type));
            need(bytes);
            pos += bytes;
            continue;
          }
          const size_t s = static_cast<size_t>(plyTypeSize(p.type));
          need(s);
          const double val =
              plyBinary(reinterpret_cast<const unsigned char*>(text.data() + pos), p.type, big);
          pos += s;
          if (is_vertex) {
            if (static_cast<int>(k) == ix) v.x() = val;
            if (static_cast<int>(k) == iy) v.y() = val;
            if (static_cast<int>(k) == iz) v.z() = val;
          }
        }
        if (is_vertex) {
          if (!v.allFinite())
            throw InputError(pc.file, 0, "PLY: vertex " + std::to_string(i + 1) + " is not finite");
          pc.source_lines.push_back(0);
        }
      }
      if (is_vertex) pc.points_mm.push_back(v);
    }
  }
}

}  // namespace

PointCloud readPointCloud(const std::string& path, const std::string& format_in,
                          const PointSelection& select) {
  const std::string& feature = select.feature;
  PointCloud pc;
  pc.file = path;
  pc.format = format_in == "auto" || format_in.empty() ? extensionFormat(path) : format_in;
  const bool exchange = pc.format == "qif" || pc.format == "dmis";
  if (!feature.empty() && pc.format != "csv" && !exchange)
    throw InputError(path, 0, "--feature selects rows of a points CSV or a feature of a QIF/DMIS file; this file is " + pc.format);
  if (!select.cycle.empty() && pc.format != "csv")
    throw InputError(path, 0, "--cycle selects rows of a points CSV; this file is " + pc.format);
  // Binary PLY holds NUL bytes; every other format is text (NUL refused, UTF-16 transcoded).
  const std::string text = readFile(path, pc.format == "ply" ? kPointCloudInput : kAnyInput);
  if (pc.format == "csv") readCsv(pc, text, select);
  else if (pc.format == "ds") readDs(pc, text);
  else if (pc.format == "xyz") readXyz(pc, text);
  else if (pc.format == "ply") readPly(pc, text);
  else if (exchange) readCmmExchange(pc, text, select);
  else throw InputError(path, 0, "unknown point format '" + pc.format + "'; expected csv, ds, xyz, ply, qif or dmis");
  if (pc.points_mm.empty()) throw InputError(path, 0, "no points in the file");
  return pc;
}

}  // namespace probeloop::evaluate
