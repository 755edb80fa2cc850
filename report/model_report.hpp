// HTML report of an error-model fit and, optionally, of its diagnosis (issue 5, item 5).
//
// Contract:
// - Input: `fit` is the JSON of `probeloop model fit --json`; `diagnosis` the JSON of
//   `probeloop model diagnose --json`, or nullptr for a report without a diagnosis. `fit`
//   must be an object with a "channels" array (else InputError); every other field may be
//   missing or null: it is then shown as "—" or left out (a channel without a series has
//   no plots; without "before" there are no before → after columns and no dashed line).
// - Output: one HTML5 page (UTF-8) that opens offline: the Vega 5 runtime is inlined and
//   every plot is a declarative Vega spec (JSON in <script type="application/json">) that
//   Vega renders as SVG when the page loads; there is no drawing code of our own.
// - Plots: for each fit channel with a non-empty "series", two plots in this order:
//   (1) measured (points, each with its U from the series as a bar value ± U), model
//   prediction (line) with the ±U band around it (area: the measured point lies in the band
//   exactly when |residual| <= U), the "before" prediction (dashed line) when
//   predicted_before is present, against time in hours, the validation window shaded;
//   (2) residual = measured − model (points, red beyond U) with the ±U band about zero.
//   Marks are named and drawn in this order: validation_window, band_area,
//   model_before_line, error_bar_rules, measured_points (residual_points), model_line,
//   validation_label: the model line lies over the
//   points, and the label, centred over its window and not clipped, over everything. Above
//   150 points they are smaller and translucent. A channel without U gets no bars and no
//   band, and its captions say the input holds no U for it.
// - Verdict strength: wherever the page says "within 1.5 u" (and in each fit channel's
//   summary) it gives u / residual RMS, and the sentence of model/verdict_strength.hpp when
//   u >= 2x the residual; p-values below 1e-4 read "< 1e-4". Plot k (1, 2, … in page order) is <div class="vega-plot" id="plot-k">
//   with its spec in <script type="application/json" id="plot-k-spec">. The data values
//   in a spec are the input's, unchanged (hours, residual and band are Vega formulas).
// - Render errors: the page writes every script error and every Vega error into
//   <div id="vega-errors">, which stays empty when all plots render; a plot container
//   gets data-rendered="true" once its view has run.
// - Tables: files and training/validation windows; per channel the indicators (n, RMSE,
//   SMAPE %, PV ratio %, P99) for training and validation, as before → after when "before"
//   is present, and the effects' parameters as value ± u with unit; with a diagnosis: the
//   verdict and message, per channel RMS residual vs u, Ljung–Box Q/p and whiteness, the
//   windows beyond U (first 10), the 5 strongest cross-correlations, and the ranked
//   candidates (sentence, per channel validation RMSE and MDL before → after, parameters,
//   the command in a <code> block). Units are shown as reports speak them (um → µm,
//   urad → µrad) in every column name or cell.
// - Text: every string from the input is HTML-escaped; JSON inside <script> elements has
//   <, > and & written as \u003c, \u003e, \u0026, so no input can end a script element.
// - Deterministic: the same inputs and Vega files give byte-identical output (no clock,
//   no locale, numbers printed in the C locale, JSON keys sorted).
// - Vega: vega_js_path is either one file holding a Vega 5 bundle (upstream vega.min.js),
//   inlined as is, or a directory holding the per-module builds as Debian's libjs-vega
//   installs them (Debian ships no single bundle): the modules the report needs are
//   inlined behind a small CommonJS shim that assembles the `vega` global. A missing path
//   or module throws InputError naming the file and the Debian package to install.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

namespace probeloop::report {

// Where Debian's libjs-vega installs Vega 5: /usr/share/javascript/vega (a directory).
std::string defaultVegaPath();

std::string modelReportHtml(const nlohmann::json& fit, const nlohmann::json* diagnosis,
                            const std::string& vega_js_path = defaultVegaPath());

}  // namespace probeloop::report
