// Minimal CSV reading with line numbers: '#' starts a comment line, blank lines skipped, no
// quoting (none of the project's formats needs it); CRLF line ends and a UTF-8 byte-order mark
// are accepted.
//
// Separator and decimal mark, decided from the header line alone so that a number can never be
// misread: a header with ';' and no ',' makes the file semicolon-separated, and then a number
// may use a decimal comma ("1,25") or a decimal point, never both in one field (no thousands
// separators); otherwise the file is comma-separated with decimal points, and a row with more
// fields than the header is refused with the hint that decimal commas need ';'. A header with
// both ',' and ';' is refused: which one separates cannot be told.
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
  char separator = ',';        // ';' when the header says so (see above)

  int column(const std::string& name) const;  // -1 if absent
  // Parses fields[col] of a row as a finite double (a decimal comma in a ';' file);
  // InputError with file:line:column name.
  double number(const CsvRow& row, int col) const;
  // The same rules without throwing: false for a missing or non-numeric field.
  bool tryNumber(const CsvRow& row, int col, double& value) const;
};

// Parses the whole string as a finite decimal double: sign, digits, one point, exponent (no
// trailing characters, no hexadecimal, NaN or inf).
bool parseFiniteNumber(const std::string& text, double& value);

// A CSV text's header line split by its separator (the rules above), the byte-order mark and
// comments skipped; empty when there is none. For readers that sniff a file's kind.
std::vector<std::string> csvHeaderFields(const std::string& text);

CsvTable parseCsv(const std::string& text, const std::string& file_name);

// Shortest round-trip decimal of a double ("%.17g" trimmed), for deterministic output.
std::string formatNumber(double v, int decimals = -1);
// Four significant digits ("%.4g"), for reports whose numbers span orders of magnitude.
std::string formatSignificant4(double v);

}  // namespace probeloop
