#include "core/csv.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/error.hpp"

namespace probeloop {
namespace {
std::string trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}
std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == sep) {
      out.push_back(trim(cur));
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  out.push_back(trim(cur));
  return out;
}
}  // namespace

int CsvTable::column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return static_cast<int>(i);
  return -1;
}

bool parseFiniteNumber(const std::string& text, double& value) {
  if (text.empty() || text.find_first_not_of("0123456789+-.eE") != std::string::npos) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

bool CsvTable::tryNumber(const CsvRow& row, int col, double& v) const {
  if (col < 0 || col >= static_cast<int>(row.fields.size())) return false;
  std::string f = row.fields[static_cast<std::size_t>(col)];
  if (separator == ';' && f.find(',') != std::string::npos) {
    if (f.find('.') != std::string::npos || f.find(',') != f.rfind(',')) return false;
    f[f.find(',')] = '.';
  }
  return parseFiniteNumber(f, v);
}

std::vector<std::string> csvHeaderFields(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (n == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string tl = trim(line);
    if (tl.empty() || tl[0] == '#') continue;
    const bool semi = tl.find(';') != std::string::npos, comma = tl.find(',') != std::string::npos;
    return split(tl, semi && !comma ? ';' : ',');
  }
  return {};
}

double CsvTable::number(const CsvRow& row, int col) const {
  if (col < 0 || col >= static_cast<int>(row.fields.size()))
    throw InputError(file, row.line, "missing field '" + header.at(col) + "'");
  const std::string& f = row.fields[col];
  double v = 0;
  if (separator == ';' && f.find(',') != std::string::npos) {
    if (f.find('.') != std::string::npos || f.find(',') != f.rfind(','))
      throw InputError(file, row.line,
                       "field '" + header[col] + "': '" + f +
                           "' is not a number: one decimal mark, a comma or a point, and no thousands separators");
    std::string g = f;
    g[g.find(',')] = '.';
    if (parseFiniteNumber(g, v)) return v;
  } else if (parseFiniteNumber(f, v)) {
    return v;
  }
  throw InputError(file, row.line, "field '" + header[col] + "': '" + f + "' is not a finite number");
}

CsvTable parseCsv(const std::string& text, const std::string& file_name) {
  CsvTable t;
  t.file = file_name;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (n == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);  // UTF-8 byte-order mark
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string tl = trim(line);
    if (tl.empty() || tl[0] == '#') continue;
    if (t.header.empty()) {
      const bool semi = tl.find(';') != std::string::npos, comma = tl.find(',') != std::string::npos;
      if (semi && comma)
        throw InputError(file_name, n, "the header holds both ',' and ';': which one separates the columns cannot be told");
      t.separator = semi ? ';' : ',';
      t.header = split(tl, t.separator);
      t.header_line = n;
      continue;
    }
    auto fields = split(tl, t.separator);
    if (fields.size() != t.header.size())
      throw InputError(file_name, n,
                       "expected " + std::to_string(t.header.size()) + " fields (header line " +
                           std::to_string(t.header_line) + "), found " + std::to_string(fields.size()) +
                           (t.separator == ',' && fields.size() > t.header.size()
                                ? " (decimal commas? a comma-separated file cannot hold them: separate the columns with ';')"
                                : ""));
    t.rows.push_back({n, std::move(fields)});
  }
  if (t.header.empty()) throw InputError(file_name, 0, "no header row");
  return t;
}

std::string formatSignificant4(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string formatNumber(double v, int decimals) {
  char buf[64];
  if (decimals >= 0) {
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    std::string s(buf);
    if (s == "-0" || (s.rfind("-0.", 0) == 0 && s.find_first_not_of("-0.") == std::string::npos))
      s.erase(0, 1);  // no negative zero in outputs
    return s;
  }
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  (void)ec;
  return std::string(buf, p);
}

}  // namespace probeloop
