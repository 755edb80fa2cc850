#include "model/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/csv.hpp"
#include "core/input_file.hpp"
#include "core/error.hpp"

namespace probeloop::model {
namespace {

// `expected` is the kind the caller reads ("an inputs.csv", "an errors.csv"): the other one,
// given in its place (the two options swapped), is named as what it is.
CsvTable readTable(const std::string& path, const char* expected, const char* option) {
  const std::string text = readFile(path);
  const std::string kind = describeContent(text);
  for (const char* other : {"an inputs.csv", "an errors.csv", "a points CSV"})
    if (kind.rfind(other, 0) == 0 && kind.rfind(expected, 0) != 0)
      throw InputError(path, 0, std::string("this is ") + kind + "; " + option + " expects " + expected +
                                    (std::string(expected) == "an inputs.csv"
                                         ? " (time_s and the logged inputs: temperatures, speeds)"
                                         : " (time_s, cycle and the evaluated errors with their U_ columns)"));
  CsvTable t = parseCsv(text, path);
  if (t.header.empty()) throw InputError(path, 0, "no header line: expected time_s and the data columns");
  if (t.header[0] != "time_s")
    throw InputError(path, t.header_line, "the first column must be time_s, found '" + t.header[0] + "'");
  return t;
}

double field(const CsvTable& t, const CsvRow& row, int col) {
  if (col >= static_cast<int>(row.fields.size()))
    throw InputError(t.file, row.line, t.header[col] + ": missing field (expected " + std::to_string(t.header.size()) +
                                           " comma-separated fields)");
  return t.number(row, col);  // NaN, inf, empty, text -> file:line: column
}

void checkIncreasing(const CsvTable& t, const std::vector<double>& times) {
  for (std::size_t k = 1; k < times.size(); ++k)
    if (!(times[k] > times[k - 1]))
      throw InputError(t.file, t.rows[k].line,
                       "time_s " + formatNumber(times[k]) + " does not follow " + formatNumber(times[k - 1]) +
                           " (line " + std::to_string(t.rows[k - 1].line) + "): times must increase");
}

}  // namespace

int InputSeries::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

int ErrorSeries::channel(const std::string& name) const {
  for (std::size_t i = 0; i < channels.size(); ++i)
    if (channels[i] == name || channels[i].rfind(name + "_", 0) == 0) return static_cast<int>(i);
  return -1;
}

std::string channelUnit(const std::string& channel) {
  const auto p = channel.rfind('_');
  return p == std::string::npos ? "" : channel.substr(p + 1);
}

InputSeries loadInputs(const std::string& path) {
  const CsvTable t = readTable(path, "an inputs.csv", "--inputs");
  InputSeries s;
  s.file = path;
  s.names.assign(t.header.begin() + 1, t.header.end());
  if (s.names.empty()) throw InputError(path, t.header_line, "no input columns after time_s");
  if (t.rows.size() < 2) throw InputError(path, 0, "needs at least 2 samples, has " + std::to_string(t.rows.size()));
  s.columns.assign(s.names.size(), {});
  for (const auto& row : t.rows) {
    s.t_s.push_back(field(t, row, 0));
    for (std::size_t i = 0; i < s.names.size(); ++i) s.columns[i].push_back(field(t, row, static_cast<int>(i) + 1));
  }
  checkIncreasing(t, s.t_s);
  // The step is the most common spacing; a campaign logger writes a uniform grid.
  std::vector<double> d;
  for (std::size_t k = 1; k < s.t_s.size(); ++k) d.push_back(s.t_s[k] - s.t_s[k - 1]);
  std::vector<double> sorted = d;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  s.step_s = sorted[sorted.size() / 2];
  for (std::size_t k = 0; k < d.size(); ++k)
    if (d[k] > 1.5 * s.step_s)
      throw InputError(path, t.rows[k + 1].line,
                       "gap in the inputs: " + formatNumber(d[k]) + " s since line " + std::to_string(t.rows[k].line) +
                           ", the log is every " + formatNumber(s.step_s) +
                           " s; a lag model cannot bridge missing inputs (re-log, or split the campaign)");
  return s;
}

ErrorSeries loadErrors(const std::string& path) {
  const CsvTable t = readTable(path, "an errors.csv", "--errors");
  ErrorSeries s;
  s.file = path;
  std::vector<int> value_col, u_col;
  for (std::size_t c = 1; c < t.header.size(); ++c) {
    const std::string& h = t.header[c];
    if (h == "cycle" || h.rfind("U_", 0) == 0) continue;
    s.channels.push_back(h);
    value_col.push_back(static_cast<int>(c));
    u_col.push_back(t.column("U_" + h));
  }
  if (s.channels.empty()) throw InputError(path, t.header_line, "no error channels after time_s");
  if (t.rows.empty()) throw InputError(path, 0, "no samples");
  s.values.assign(s.channels.size(), {});
  s.U.assign(s.channels.size(), {});
  for (const auto& row : t.rows) {
    s.t_s.push_back(field(t, row, 0));
    for (std::size_t i = 0; i < s.channels.size(); ++i) {
      s.values[i].push_back(field(t, row, value_col[i]));
      const double U = u_col[i] < 0 ? 0.0 : field(t, row, u_col[i]);
      if (U < 0) throw InputError(path, row.line, t.header[u_col[i]] + ": an expanded uncertainty cannot be negative");
      s.U[i].push_back(U);
    }
  }
  checkIncreasing(t, s.t_s);
  return s;
}

Campaign loadCampaign(const std::string& inputs_path, const std::string& errors_path) {
  Campaign c{loadInputs(inputs_path), loadErrors(errors_path)};
  const double a = c.inputs.t_s.front(), b = c.inputs.t_s.back();
  const double lo = c.errors.t_s.front(), hi = c.errors.t_s.back();
  if (lo < a - 1e-9 || hi > b + 1e-9)
    throw InputError(errors_path, 0,
                     "misaligned time bases: the errors span " + formatNumber(lo, 3) + ".." + formatNumber(hi, 3) +
                         " s but the inputs (" + inputs_path + ") span " + formatNumber(a, 3) + ".." + formatNumber(b, 3) +
                         " s; both must come from the same campaign clock (time_s from its start)");
  return c;
}

std::vector<double> Campaign::atErrorTimes(const std::vector<double>& g) const {
  const auto& t = inputs.t_s;
  std::vector<double> out;
  out.reserve(errors.t_s.size());
  std::size_t k = 0;
  for (double te : errors.t_s) {
    while (k + 2 < t.size() && t[k + 1] <= te) ++k;
    const double w = std::clamp((te - t[k]) / (t[k + 1] - t[k]), 0.0, 1.0);
    out.push_back(g[k] + w * (g[k + 1] - g[k]));
  }
  return out;
}

}  // namespace probeloop::model
