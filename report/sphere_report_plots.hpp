// The plots of the sphere-campaign report (report/sphere_report.hpp is the contract): the
// seven location errors, the inputs.csv columns grouped by unit, and what both need (the
// errors' names and units, the inputs read and grouped). Internal to report/.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/csv.hpp"

namespace probeloop::report::sphere {

using nlohmann::json;

// The location errors of the C axis as evaluation.json names them (docs/conventions.md).
struct ErrorInfo {
  const char* id;     // "EX0C_um": budgets[].quantity, least_squares key, errors.csv column
  const char* label;  // "EX0C"
  const char* unit;   // display unit
  const char* what;   // what a change of it means
  const char* eq;     // seed 004 equation
};
extern const ErrorInfo kErrors[7];

// Hours on the log's clock shared by every plot: [lo, hi].
using Domain = std::pair<double, double>;

// Whether a budget of evaluation.json is this error's: its quantity is the label ("EX0C", unit
// "um"; evaluate/location_budget.hpp), or the id ("EX0C_um").
bool isBudgetOf(const json& budget, const ErrorInfo& e);
// One error's rows {time_s, cycle, value, U} (U null when the cycle has no budget for it);
// cycles without a time or a value are left out.
json errorRows(const json& evaluation, const ErrorInfo& e);
// The cycle's value and U of one error: its budget, else least_squares without U.
std::pair<std::optional<double>, std::optional<double>> cycleValue(const json& cycle, const ErrorInfo& e);

json errorPlotSpec(const ErrorInfo& e, const json& rows, const Domain& x_h);

// The run's inputs.csv.
struct InputColumn {
  std::string name;  // as in the file
  std::string unit;  // display unit ("" = none: a state or a count)
  int col = 0;       // in the table
};
struct InputGroup {
  std::string unit, title, axis;  // "°C", "Temperatures", "temperature (°C)"
  std::vector<int> columns;       // indices into Inputs::columns
  bool steps = false;             // states and counts: drawn as steps
};
struct Inputs {
  std::string file;
  CsvTable table;
  std::vector<double> time_s;  // per row
  std::vector<InputColumn> columns;
  std::vector<InputGroup> groups;  // °C, rpm, then others in file order, unitless last
};
// InputError naming `file`: no time_s column, no signal column, an error series.
Inputs readInputs(const std::string& text, const std::string& file);
// The display unit a column's name carries ("T_env_C" -> "°C", "feed_mm_per_min" -> "mm/min").
std::string unitOfColumn(const std::string& name);

json inputsPlotSpec(const Inputs& in, const InputGroup& g, const Domain& x_h);

}  // namespace probeloop::report::sphere
