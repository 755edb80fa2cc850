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

std::string th(const std::string& s, bool num = false);
std::string tdHtml(const std::string& html, bool num = false);  // `html` is already markup
std::string td(const std::string& s, bool num = false);

}  // namespace web
}  // namespace probeloop::report
