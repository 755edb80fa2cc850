#include "report/vega.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace probeloop::report {

std::string defaultVegaPath() { return "/usr/share/javascript/vega"; }

namespace web {
namespace {

constexpr const char* kVegaInstallHint =
    "Vega 5 comes with the Debian package libjs-vega (apt-get install libjs-vega; scripts/setup.sh installs it)";

// Debian's libjs-vega: one UMD build per module and no single bundle. These are the modules
// the report's specs need (no geo/projection, which would need d3 modules Debian does not
// ship with it), in an order where every module comes after the ones it requires. The first
// name is what the modules `require`; vega-functions asks for "vega-selections".
struct VegaModule {
  const char* name;
  const char* file;
};
constexpr VegaModule kVegaModules[] = {
    {"vega-util", "vega-util.min.js"},
    {"vega-canvas", "vega-canvas.min.js"},
    {"vega-statistics", "vega-statistics.min.js"},
    {"vega-time", "vega-time.min.js"},
    {"vega-format", "vega-format.min.js"},
    {"vega-loader", "vega-loader.min.js"},
    {"vega-dataflow", "vega-dataflow.min.js"},
    {"vega-scale", "vega-scale.min.js"},
    {"vega-scenegraph", "vega-scenegraph.min.js"},
    {"vega-expression", "vega-expression.min.js"},
    {"vega-selections", "vega-selection.min.js"},
    {"vega-functions", "vega-functions.min.js"},
    {"vega-event-selector", "vega-event-selector.min.js"},
    {"vega-parser", "vega-parser.min.js"},
    {"vega-runtime", "vega-runtime.min.js"},
    {"vega-view", "vega-view.min.js"},
    {"vega-transforms", "vega-transforms.min.js"},
    {"vega-view-transforms", "vega-view-transforms.min.js"},
    {"vega-encode", "vega-encode.min.js"},
};

std::string readFile(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string(), 0, std::string("cannot read the Vega JavaScript; ") + kVegaInstallHint);
  std::ostringstream s;
  s << in.rdbuf();
  std::string content = s.str();
  if (content.empty()) throw InputError(p.string(), 0, std::string("the Vega JavaScript is empty; ") + kVegaInstallHint);
  return content;
}

// Script text that cannot end its <script> element: "</script" and "<!--" only occur in
// string or regular-expression literals of minified code, where \x3C means the same "<".
std::string scriptSafe(std::string js) {
  const auto replaceAll = [&js](const std::string& from_lower, const std::string& to) {
    std::string lower = js;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    for (std::size_t pos = lower.rfind(from_lower); pos != std::string::npos;
         pos = pos == 0 ? std::string::npos : lower.rfind(from_lower, pos - 1))
      js.replace(pos, 1, to);
  };
  replaceAll("</script", "\\x3C");
  replaceAll("<!--", "\\x3C");
  return js;
}

// The trailing "//# sourceMappingURL=..." would make a browser's developer tools look for a
// file next to the page.
std::string dropSourceMap(std::string js) {
  const std::size_t pos = js.rfind("//# sourceMappingURL=");
  if (pos == std::string::npos) return js;
  const std::size_t eol = js.find('\n', pos);
  if (eol == std::string::npos || js.find_first_not_of(" \t\r\n", eol) == std::string::npos) js.erase(pos);
  return js;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Reading optional fields: null and missing are the same, a wrong type counts as missing.

const json* field(const json& o, const char* key) {
  if (!o.is_object()) return nullptr;
  const auto it = o.find(key);
  if (it == o.end() || it->is_null()) return nullptr;
  return &*it;
}

std::optional<double> number(const json* v) {
  if (v == nullptr || !v->is_number()) return std::nullopt;
  const double d = v->get<double>();
  if (!std::isfinite(d)) return std::nullopt;
  return d;
}
std::optional<double> number(const json& o, const char* key) { return number(field(o, key)); }

std::string text(const json& o, const char* key) {
  const json* v = field(o, key);
  if (v == nullptr) return "";
  if (v->is_string()) return v->get<std::string>();
  return v->dump(-1, ' ', false, json::error_handler_t::replace);
}

const json& array(const json& o, const char* key) {
  static const json empty = json::array();
  const json* v = field(o, key);
  return v != nullptr && v->is_array() ? *v : empty;
}

const json& object(const json& o, const char* key) {
  static const json empty = json::object();
  const json* v = field(o, key);
  return v != nullptr && v->is_object() ? *v : empty;
}

std::optional<bool> boolean(const json& o, const char* key) {
  const json* v = field(o, key);
  if (v == nullptr || !v->is_boolean()) return std::nullopt;
  return v->get<bool>();
}

// ---------------------------------------------------------------------------------------
// Text: HTML escaping, units, numbers (C locale, "—" for anything not a finite number).

const std::string kDash = "\u2014";

std::string esc(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

// JSON for a <script> element: the only characters that could end the element or open a
// comment are <, > and &, which JSON allows only inside strings, where \uXXXX means the same.
std::string scriptJson(const json& j) {
  const std::string s = j.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    if (c == '<') out += "\\u003c";
    else if (c == '>') out += "\\u003e";
    else if (c == '&') out += "\\u0026";
    else out += c;
  }
  return out;
}

// "um" -> "µm", "urad" -> "µrad" wherever they stand as a word ("um/rpm" -> "µm/rpm").
std::string displayUnit(const std::string& u) {
  std::string out;
  std::size_t i = 0;
  while (i < u.size()) {
    if (std::isalpha(static_cast<unsigned char>(u[i]))) {
      std::size_t j = i;
      while (j < u.size() && std::isalnum(static_cast<unsigned char>(u[j]))) ++j;
      const std::string word = u.substr(i, j - i);
      out += word == "um" ? "\u00b5m" : word == "urad" ? "\u00b5rad" : word;
      i = j;
    } else {
      out += u[i++];
    }
  }
  return out;
}

// "-0.00" -> "0.00".
std::string dropNegativeZero(std::string s) {
  if (!s.empty() && s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string fixed(double x, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return dropNegativeZero(buf);
}

// `digits` significant digits, plain notation between 1e-4 and 1e7.
std::string sig(double x, int digits) {
  if (!std::isfinite(x)) return kDash;
  if (x == 0.0) return "0";
  const int e = static_cast<int>(std::floor(std::log10(std::abs(x))));
  if (e < -4 || e >= 7) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*e", digits - 1, x);
    return buf;
  }
  return fixed(x, std::max(0, digits - 1 - e));
}
std::string sig(const std::optional<double>& x, int digits) { return x ? sig(*x, digits) : kDash; }

// GUM style: u with two significant digits, the value to the same decimal place.
std::string valueU(const std::optional<double>& v, const std::optional<double>& u) {
  if (!v) return kDash;
  if (!u || *u <= 0.0) return sig(*v, 4);
  const int eu = static_cast<int>(std::floor(std::log10(*u)));
  if (eu < -9 || eu > 9 || std::abs(*v) >= 1e9) return sig(*v, 4) + " \u00b1 " + sig(*u, 2);
  const int decimals = std::max(0, 1 - eu);
  return fixed(*v, decimals) + " \u00b1 " + fixed(*u, decimals);
}

// Counts (samples, lags, ranks): integers as integers.
std::string whole(const std::optional<double>& x) {
  if (!x) return kDash;
  if (std::abs(*x) < 1e15 && *x == std::round(*x)) return fixed(*x, 0);
  return sig(*x, 6);
}

std::string hours(const std::optional<double>& s) { return s ? fixed(*s / 3600.0, 2) : kDash; }

std::string withUnit(const std::string& value, const std::string& unit) {
  return unit.empty() || value == kDash ? value : value + " " + unit;
}

json filterTx(const std::string& expr) { return {{"type", "filter"}, {"expr", expr}}; }
json formulaTx(const std::string& as, const std::string& expr) {
  return {{"type", "formula"}, {"as", as}, {"expr", expr}};
}


json baseSpec(const std::string& description, int height) {
  json spec = json::object();
  spec["$schema"] = "https://vega.github.io/schema/vega/v5.json";
  spec["description"] = description;
  spec["width"] = kPlotWidth;
  spec["height"] = height;
  spec["padding"] = 5;
  spec["autosize"] = {{"type", "pad"}};
  spec["config"] = {{"axis", {{"labelFont", "sans-serif"}, {"titleFont", "sans-serif"}, {"labelFontSize", 11},
                              {"titleFontSize", 12}, {"titleFontWeight", "normal"}, {"gridColor", "#ececec"}}},
                    {"legend", {{"labelFont", "sans-serif"}, {"labelFontSize", 11}}}};
  return spec;
}

void addLegend(json& spec, const std::vector<LegendEntry>& entries) {
  json domain = json::array(), shape = json::array(), fill = json::array(), stroke = json::array(),
       dash = json::array();
  for (const auto& e : entries) {
    domain.push_back(e.name);
    shape.push_back(e.shape);
    fill.push_back(e.fill);
    stroke.push_back(e.stroke);
    dash.push_back(e.dash);
  }
  const auto scale = [&](const char* name, const json& range) {
    spec["scales"].push_back({{"name", name}, {"type", "ordinal"}, {"domain", domain}, {"range", range}});
  };
  scale("legend_shape", shape);
  scale("legend_fill", fill);
  scale("legend_stroke", stroke);
  scale("legend_dash", dash);
  spec["legends"] = json::array({{{"shape", "legend_shape"},
                                  {"fill", "legend_fill"},
                                  {"stroke", "legend_stroke"},
                                  {"strokeDash", "legend_dash"},
                                  {"orient", "top"},
                                  {"direction", "horizontal"},
                                  {"symbolStrokeWidth", 1.5},
                                  {"symbolSize", 80}}});
}

// ---------------------------------------------------------------------------------------
// The Vega runtime, inlined.

std::string vegaRuntime(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  if (fs::is_regular_file(p, ec)) return scriptSafe(readFile(p));
  if (!fs::is_directory(p, ec))
    throw InputError(path, 0, std::string("Vega JavaScript not found; ") + kVegaInstallHint);
  std::string js =
      "/* Vega 5, from the per-module builds of Debian's libjs-vega, behind a CommonJS shim. */\n"
      "(function () {\n"
      "var M = {};\n"
      "function R(name) { if (!(name in M)) throw new Error('Vega module not loaded: ' + name); return M[name]; }\n";
  for (const auto& m : kVegaModules) {
    const fs::path file = p / m.file;
    if (!fs::is_regular_file(file, ec))
      throw InputError(file.string(), 0, std::string("Vega module missing; ") + kVegaInstallHint);
    js += "/* " + std::string(m.file) + " */\n(function (exports, module, require) {\n" +
          dropSourceMap(readFile(file)) + "\n})(M['" + m.name + "'] = {}, {}, R);\n";
  }
  // The namespace the upstream bundle (packages/vega/index.js) exports, as far as a page
  // that parses and views specs needs it, and the same transform registry.
  js += R"JS(var vega = {};
['vega-statistics', 'vega-time', 'vega-util', 'vega-loader', 'vega-scenegraph'].forEach(function (n) { Object.assign(vega, M[n]); });
var df = M['vega-dataflow'];
['Dataflow', 'EventStream', 'Parameters', 'Pulse', 'MultiPulse', 'Operator', 'Transform', 'changeset', 'ingest',
 'isTuple', 'definition', 'transform', 'transforms', 'tupleid'].forEach(function (n) { vega[n] = df[n]; });
M['vega-util'].extend(df.transforms, M['vega-transforms'], M['vega-view-transforms'], M['vega-encode']);
['scale', 'scheme', 'interpolate', 'interpolateColors', 'interpolateRange'].forEach(function (n) { vega[n] = M['vega-scale'][n]; });
vega.View = M['vega-view'].View;
vega.parse = M['vega-parser'].parse;
vega.expressionFunction = M['vega-functions'].expressionFunction;
vega.formatLocale = M['vega-format'].formatLocale;
vega.timeFormatLocale = M['vega-format'].timeFormatLocale;
window.vega = vega;
})();
)JS";
  return scriptSafe(js);
}

// Runs first: every later script error lands in #vega-errors.
const char* const kErrorHook = R"JS(
window.probeloopReportError = function (where, e) {
  var p = document.createElement('p');
  p.textContent = where + ': ' + (e && e.message ? e.message : String(e));
  document.getElementById('vega-errors').appendChild(p);
};
window.addEventListener('error', function (e) { window.probeloopReportError('script error', e.message); });
window.addEventListener('unhandledrejection', function (e) { window.probeloopReportError('script error', e.reason); });
)JS";

// Runs last: renders every plot as SVG; Vega's errors (parse, dataflow) go to #vega-errors.
const char* const kRender = R"JS(
(function () {
  var report = window.probeloopReportError;
  if (typeof vega === 'undefined' || typeof vega.View !== 'function') {
    report('report', 'the Vega runtime did not load');
    return;
  }
  Array.prototype.forEach.call(document.querySelectorAll('div.vega-plot'), function (div) {
    var base = vega.logger(vega.Warn);
    var logger = {
      level: function (l) { if (arguments.length) { base.level(l); return logger; } return base.level(); },
      error: function () { report(div.id, Array.prototype.join.call(arguments, ' ')); return logger; },
      warn: function () { base.warn.apply(base, arguments); return logger; },
      info: function () { base.info.apply(base, arguments); return logger; },
      debug: function () { base.debug.apply(base, arguments); return logger; }
    };
    try {
      var spec = JSON.parse(document.getElementById(div.id + '-spec').textContent);
      new vega.View(vega.parse(spec), {renderer: 'svg', container: div, hover: false, logger: logger})
        .runAsync()
        .then(function () { div.setAttribute('data-rendered', 'true'); },
              function (e) { report(div.id, e); });
    } catch (e) {
      report(div.id, e);
    }
  });
})();
)JS";

const char* const kStyle = R"CSS(
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #222; max-width: 1000px; margin: 2em auto; padding: 0 1em; }
h1 { font-size: 1.5em; margin: 0 0 .4em; }
h2 { font-size: 1.2em; margin: 2.2em 0 .5em; padding-bottom: .2em; border-bottom: 1px solid #ddd; }
h3 { font-size: 1em; margin: 1.3em 0 .3em; }
table { border-collapse: collapse; margin: .3em 0 1em; }
th, td { padding: .25em .7em; border-bottom: 1px solid #e4e4e4; text-align: left; vertical-align: top; }
th { font-weight: 600; background: #f6f6f6; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.meta th { background: none; font-weight: normal; color: #555; }
.before { color: #777; }
.new { font-size: .8em; background: #e3f0e3; color: #256325; padding: 0 .35em; border-radius: 3px; }
.note { color: #555; }
.verdict { font-size: 1.05em; }
figure { margin: .6em 0; }
figcaption { font-size: .85em; color: #555; }
pre { background: #f4f4f4; padding: .4em .6em; margin: .4em 0 0; overflow-x: auto; }
code { font-family: ui-monospace, "DejaVu Sans Mono", monospace; font-size: .9em; }
td.rank { font-weight: 600; text-align: center; }
tbody.candidate { border-top: 2px solid #ccc; }
.errors { border: 1px solid #c0392b; background: #fdecea; color: #8e2a1f; padding: .5em 1em; margin: 1em 0; }
.errors:empty { display: none; }
)CSS";

// ---------------------------------------------------------------------------------------
// HTML.

void Page::plot(const json& spec, const std::string& caption) {
  const std::string id = "plot-" + std::to_string(++plots);
  html += "<figure>\n<div class=\"vega-plot\" id=\"" + id + "\"></div>\n<script type=\"application/json\" id=\"" +
          id + "-spec\">" + scriptJson(spec) + "</script>\n<figcaption>" + esc(caption) + "</figcaption>\n</figure>\n";
}

// ---------------------------------------------------------------------------------------
// Significance and time.

bool notSignificant(const std::optional<double>& value, const std::optional<double>& U) {
  return value && U && std::isfinite(*value) && std::isfinite(*U) && *U > 0.0 && std::abs(*value) <= *U;
}

std::string tdValueU(const std::optional<double>& value, const std::optional<double>& U, const std::string& marker) {
  if (!notSignificant(value, U)) return td(valueU(value, U), true);
  return "<td class=\"num ns\">" + esc(valueU(value, U)) + " <span class=\"ns-mark\">" + esc(marker) + "</span></td>";
}

const char* const kNotSignificantNote =
    "<p class=\"note ns-legend\"><span class=\"ns\">Grey, marked <span class=\"ns-mark\">n.s.</span></span>: "
    "not significant, |value| \u2264 U (k = 2): the measurement cannot tell the value from zero.</p>";

const char* const kMarkStyle = R"CSS(
td.ns, .ns { color: #8a8a8a; }
.ns-mark { font-size: .75em; font-style: italic; color: #8a8a8a; margin-left: .25em; }
.table-wrap { max-width: 100%; overflow-x: auto; margin: .3em 0 1em; }
.table-wrap > table { margin: 0; }
)CSS";

std::string tableWrap(const std::string& table_html) { return "<div class=\"table-wrap\">\n" + table_html + "</div>\n"; }

std::string inputWarningsSection(const json& evaluation) {
  const json& ws = array(evaluation, "input_warnings");
  if (ws.empty()) return "";
  std::string o = "<section class=\"input-warnings\">\n<h2>Input warnings</h2>\n<p class=\"note\">The input file was read "
                  "leniently (docs/interop.md#lenient-reading): what its producer got wrong without changing the meaning, "
                  "and what was done. <code>--strict</code> refuses the file instead.</p>\n<ul>\n";
  for (const auto& w : ws)
    o += "<li><code>" + esc(text(w, "file")) + "</code> line " + esc(whole(number(w, "line"))) + ": " + esc(text(w, "what")) + "</li>\n";
  return o + "</ul>\n</section>\n";
}

std::string hoursMinutes(const std::optional<double>& seconds) {
  if (!seconds || !std::isfinite(*seconds)) return kDash;
  const long long minutes = std::llround(std::abs(*seconds) / 60.0);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%lld:%02lld", minutes / 60, minutes % 60);
  return (*seconds < 0 && minutes > 0 ? "\u2212" : "") + std::string(buf);
}

// Vega's expression language: the tick's value in hours as h:mm, as hoursMinutes() does.
json hoursMinutesAxisLabels() {
  const std::string m = "round(abs(datum.value) * 60)";
  return {{"update",
           {{"text",
             {{"signal", "(datum.value < 0 && " + m + " > 0 ? '\u2212' : '') + floor(" + m + " / 60) + ':' + (" + m +
                             " % 60 < 10 ? '0' : '') + (" + m + " % 60)"}}}}}};
}

std::string th(const std::string& s, bool num) {
  return std::string(num ? "<th class=\"num\">" : "<th>") + esc(s) + "</th>";
}
// `html` is already markup.
std::string tdHtml(const std::string& html, bool num) {
  return std::string(num ? "<td class=\"num\">" : "<td>") + html + "</td>";
}
std::string td(const std::string& s, bool num) { return tdHtml(esc(s), num); }

}  // namespace web
}  // namespace probeloop::report
