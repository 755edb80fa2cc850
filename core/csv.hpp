// Minimal CSV reading with line numbers: comma-separated, '#' starts a comment line,
// blank lines skipped, no quoting (none of the project's formats needs it).
#pragma once
#include <string>
#include <vector>

namespace probeloop {

struct CsvRow {
  int line = 0;                     // 1-based line in the file
  std::vector<std::string> fields;  // trimmed
};

struct CsvTable {
  std::string file;
  int header_line = 0;
  std::vector<std::string> header;
  std::vector<CsvRow> rows;

  int column(const std::string& name) const;  // -1 if absent
  // Parses fields[col] of a row as a finite double; InputError with file:line:column name.
  double number(const CsvRow& row, int col) const;
};

// Parses the whole string as a finite double (no trailing characters, no NaN or inf).
bool parseFiniteNumber(const std::string& text, double& value);

CsvTable parseCsv(const std::string& text, const std::string& file_name);

// Shortest round-trip decimal of a double ("%.17g" trimmed), for deterministic output.
std::string formatNumber(double v, int decimals = -1);
// Four significant digits ("%.4g"), for reports whose numbers span orders of magnitude.
std::string formatSignificant4(double v);

}  // namespace probeloop
