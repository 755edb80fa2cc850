// What the project's HTML reports share (report/model_report, report/ttp_report): reading
// optional JSON fields, HTML escaping, numbers as reports print them, the Vega 5 runtime
// inlined from Debian's libjs-vega, the render-error contract, the base style and the page
// builder.
//
// Contract of a page built with these pieces (the model report's, unchanged):
// - every string from an input goes through esc() (text) or scriptJson() (a spec inside a
//   <script type="application/json">): <, > and & never reach the page raw, so no input can
//   open or close an element or a script;
// - every plot is a declarative Vega spec in <div class="vega-plot" id="plot-k"> with the
//   spec in <script type="application/json" id="plot-k-spec"> (Page::plot); the script
//   kErrorHook (first, right after <div id="vega-errors">) and kRender (last, after the
//   runtime) make every script error and every Vega error land in #vega-errors and mark a
//   plot container data-rendered="true" once its view has run;
// - numbers in the C locale; JSON keys sorted (nlohmann::json's std::map): deterministic.
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace probeloop::report {

// Where Debian's libjs-vega installs Vega 5: /usr/share/javascript/vega (a directory).
std::string defaultVegaPath();

namespace web {

using nlohmann::json;

// ---- Reading optional fields: null and missing are the same, a wrong type counts as missing.
const json* field(const json& o, const char* key);
std::optional<double> number(const json* v);  // finite numbers only
std::optional<double> number(const json& o, const char* key);
std::string text(const json& o, const char* key);  // "" when absent; non-strings dumped
const json& array(const json& o, const char* key);   // [] when absent or not an array
const json& object(const json& o, const char* key);  // {} when absent or not an object
std::optional<bool> boolean(const json& o, const char* key);

// ---- Text and numbers.
extern const std::string kDash;  // "—": what a missing value shows
std::string esc(std::string_view s);
std::string scriptJson(const json& j);
std::string displayUnit(const std::string& u);  // "um" -> "µm", "urad" -> "µrad" as words
std::string dropNegativeZero(std::string s);
std::string fixed(double x, int decimals);
std::string sig(double x, int digits);
std::string sig(const std::optional<double>& x, int digits);
// GUM style: u with two significant digits, the value to the same decimal place.
std::string valueU(const std::optional<double>& v, const std::optional<double>& u);
std::string whole(const std::optional<double>& x);
std::string hours(const std::optional<double>& s);  // seconds -> "1.25"
std::string withUnit(const std::string& value, const std::string& unit);

// ---- Vega specs.
constexpr int kPlotWidth = 760;
json filterTx(const std::string& expr);
json formulaTx(const std::string& as, const std::string& expr);
json baseSpec(const std::string& description, int height);

// One legend for mixed marks: four ordinal scales over the same entry names.
struct LegendEntry {
  std::string name, shape, fill, stroke;
  json dash;
};
void addLegend(json& spec, const std::vector<LegendEntry>& entries);

// ---- The page.
// The Vega runtime as script text: a single bundle file inlined as is, or Debian's per-module
// builds behind a CommonJS shim. InputError naming the file and the package when missing.
std::string vegaRuntime(const std::string& path);
extern const char* const kErrorHook;  // first script: errors -> #vega-errors
extern const char* const kRender;     // last script: renders every div.vega-plot as SVG
extern const char* const kStyle;      // the reports' CSS

class Page {
 public:
  std::string html;
  int plots = 0;
  // Appends plot k = ++plots: its container, its spec and its caption (escaped).
  void plot(const json& spec, const std::string& caption);
};

// ---- Significance and time, shared by every report (thermal test piece, stepped workpiece,
// sphere campaign). Each page that uses them puts kMarkStyle in its <style>.
//
// A measured value is not significant when |value| <= U (U expanded, k = 2): the measurement
// cannot tell it from zero. notSignificant() is false when either is missing or U <= 0.
bool notSignificant(const std::optional<double>& value, const std::optional<double>& U);
// A numeric table cell showing valueU(value, U). When notSignificant: <td class="num ns"> and
// a trailing <span class="ns-mark">n.s.</span> (`marker` replaces "n.s.", e.g. "not resolved"
// for an orientation; escaped). Put kNotSignificantNote (or your own sentence) once on the page.
std::string tdValueU(const std::optional<double>& value, const std::optional<double>& U,
                     const std::string& marker = "n.s.");
extern const char* const kNotSignificantNote;  // <p class="note ns-legend">…</p>: what "n.s." means
// CSS: .ns (grey), .ns-mark, and .table-wrap (a scroll container: a wide table scrolls
// inside it instead of running past the page; wrap tables in tableWrap()).
extern const char* const kMarkStyle;
// `table_html` (a whole <table>…</table>) inside <div class="table-wrap">.
std::string tableWrap(const std::string& table_html);
// Seconds as hours and minutes, "h:mm", rounded to the minute: 3633 -> "1:01", 29100 ->
// "8:05", -1800 -> "−0:30" (U+2212); "—" when missing or not finite.
std::string hoursMinutes(const std::optional<double>& seconds);
// The same format in a Vega axis: put {"labels", hoursMinutesAxisLabels()} in an axis's
// "encode" when the axis's scale is in hours (ticks at whole or simple fractional hours).
json hoursMinutesAxisLabels();

std::string th(const std::string& s, bool num = false);
std::string tdHtml(const std::string& html, bool num = false);  // `html` is already markup
std::string td(const std::string& s, bool num = false);

// The input file's reader warnings (evaluation.json's input_warnings [{file, line, what}],
// issue 34): a section "Input warnings" with one item each, escaped; "" when the evaluation has
// none, so a page from a clean file is unchanged.
std::string inputWarningsSection(const json& evaluation);

}  // namespace web
}  // namespace probeloop::report
