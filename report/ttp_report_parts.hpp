// What the thermal-test-piece report's files share (report/ttp_report.hpp is the contract):
// the quantities and their references (ttp_report_data.cpp), the routes, the R-test and the
// machine's logged inputs read from their files (ttp_report_data.cpp), the Vega specs
// (ttp_report_plots.cpp) and the tables (ttp_report_tables.cpp). Internal to the report.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/csv.hpp"
#include "report/ttp_report.hpp"
#include "report/vega.hpp"

namespace probeloop::report::ttp_detail {

using nlohmann::json;

// ---- The quantities and what the R-test shows beside each.
enum class RTestScale { none, same, negated, table_temperature };

struct Quantity {
  const char* id;            // as in the evaluation: "EX_um"
  const char* label;         // "E_X"
  const char* unit;          // display unit
  const char* what;          // heading
  const char* r_test;        // R-test column shown beside it, or nullptr
  const char* r_test_name;   // "E_X0C"
  RTestScale scale;
  const char* r_test_label;  // legend
  const char* reference;     // where the reader finds the formula in the thesis
};
extern const Quantity kQuantities[6];
// "Blaser 2020 (ETH Diss. 26709)": how the page names the thesis (seed 004).
extern const char* const kThesis;

const Quantity* findQuantity(const std::string& id);
std::pair<std::string, std::string> labelAndUnit(const std::string& id, const std::string& unit_field);
std::pair<std::string, std::string> rTestLabelAndUnit(const std::string& column);
std::string columnTitle(const std::string& label, const std::string& unit, const std::string& middle = "");
// A source text from the evaluation as a reader can follow it: "seed 004" becomes the thesis's
// name, and our notes' paths and the source file's line numbers ("L2177") are left out.
std::string readerSource(const std::string& source);

// ---- Routes (one or two evaluations).
struct Route {
  const json* eval = nullptr;
  std::string file;   // as shown
  std::string label;  // "CMM"
  int index = 0;      // 0, 1
};
std::string routeName(const std::string& route);
void checkEvaluation(const json& j, const std::string& file);
const json* findValue(const json& cycle, const std::string& quantity);
std::optional<double> referenceTime(const json& eval);
json routeRows(const json& eval, const std::string& quantity);  // {time_s, cycle, value, U}
json alsoRows(const json& eval, const char* key);  // {time_s, cycle, value, U}; U only for Eq. 7.9, see eq79U
// U of E_TTP by Eq. 7.9 in a cycle: half of E_TTP's (Eq. 7.3) when the value is exactly half.
std::optional<double> eq79U(const json& cycle, double eq79_value);
// Quantities present in a route (id, unit field), known ones first in their order.
std::vector<std::pair<std::string, std::string>> routeQuantities(const json& eval);
std::string listText(const json& a);

// ---- The R-test.
struct RTest {
  std::string file;
  CsvTable table;
  std::vector<double> time_s;  // per row
  std::optional<double> t0;    // the reference cut, if any
  double alpha = 11.0, radius_mm = 160.0;
};
RTest readRTest(const std::string& text_in, const std::string& file, const TtpReportOptions& o);

struct RTestChannel {
  json rows = json::array();
  bool re_referenced = false;
  double offset = 0;  // subtracted, in the column's unit (before the scale)
  double scale = 1;   // value shown = scale * (input - offset)
};
RTestChannel rTestChannel(const RTest& r, const char* column, RTestScale scale);

// ---- The machine's logged inputs (inputs.csv): temperatures (columns ending in _C) and the
// C axis's speed (c_rpm), each a series of rows {time_s, value}.
struct InputSeries {
  std::string column;
  json rows = json::array();
};
struct MachineInputs {
  std::string file;
  std::vector<InputSeries> temperatures;
  std::optional<InputSeries> c_rpm;
};
MachineInputs readMachineInputs(const std::string& text_in, const std::string& file);

// ---- Vega specs (ttp_report_plots.cpp).
struct Series {
  std::string data, label, kind;  // kind: route | eq_7_9 | r_test
  int route = -1;
  json rows;
};
using WarmUp = std::optional<std::pair<double, double>>;  // seconds on the common clock
json plotSpec(const Quantity& q, const std::vector<Series>& series, double t0_s, const WarmUp& warm_up_s);
std::string plotCaption(const Quantity& q, const RTest* r, const RTestChannel* ch, bool has_eq79);
// The temperatures (one line per column, °C) or the C axis's speed (rpm, a step line) against
// the same hours since the reference cut as the errors: x spans `range_s` (the errors' first
// and last time_s) when given, the inputs' rows outside it are left out (one sample beyond
// each end kept) and the lines clipped. cLoadSpec only when in.c_rpm.
using TimeRange = std::optional<std::pair<double, double>>;
json temperatureSpec(const MachineInputs& in, double t0_s, const WarmUp& warm_up_s, const TimeRange& range_s);
json cLoadSpec(const MachineInputs& in, double t0_s, const WarmUp& warm_up_s, const TimeRange& range_s);

// ---- Tables (ttp_report_tables.cpp).
void cycleTable(web::Page& page, const Route& r, double t0_s);
void spanTable(web::Page& page, const Route& r);
void comparisonTable(web::Page& page, const Route& r);
void budgetTable(web::Page& page, const Route& r);
void formulaTable(web::Page& page, const json& formulas, const std::string& heading);
void inputsTable(web::Page& page, const std::vector<Route>& routes, const RTest* r, const MachineInputs* in,
                 double t0_s, const std::vector<std::pair<std::string, RTestChannel>>& channels);
// The note on Eqs. 7.1 and 7.2 as printed (what is printed, why it is wrong, what is used)
// when a route reports the printed forms; the appendix with their values per cycle.
bool hasPrintedForms(const std::vector<Route>& routes);
void printedFormsNote(web::Page& page, const std::vector<Route>& routes);
void printedFormsAppendix(web::Page& page, const std::vector<Route>& routes, double t0_s);

}  // namespace probeloop::report::ttp_detail
