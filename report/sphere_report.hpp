// HTML report of a sphere-artifact campaign (seed 004 Ch. 5; issue 32 item 3): the seven
// location errors of the C axis (EX0C, EY0C, EZ0T, ER0T, EA0C, EB0C, EC0C; Eqs. 5.4-5.10,
// signs in docs/conventions.md) against time with their U (k = 2) bands, every cycle's values,
// the uncertainty budgets as the evaluation states them, the planned schedule, and the
// machine's logged temperatures and loads on the same time axis.
//
// Contract:
// - Inputs: `evaluation` is the evaluation.json of `probeloop evaluate` for a sphere artifact
//   (kind "sphere_artifact"; an evaluation without "kind" is accepted when its format is
//   "probeloop-evaluation" and its cycles carry "least_squares"); `inputs_csv_text` the text
//   of the run's inputs.csv (time_s, then one column per signal, the unit in its name), or
//   nullptr; `manifest` the campaign's plan manifest (kind sphere_artifact), or nullptr.
//   Refused with an InputError naming the option's file: anything that is not a sphere
//   campaign's evaluation (e.g. a thermal test piece's) or has no "cycles" array; an inputs
//   text without a time_s column, without any signal column, or that is an error series
//   (errors.csv: cycle and location-error columns); a manifest of another kind, or one that
//   plans fewer cycles than the evaluation holds. Every other field may be missing or null: a
//   value absent from a cycle is left out of the plots and shown as "—" in the tables.
// - Values: each cycle's error and U come from its budgets[] (quantity "EX0C" ..., value, U),
//   else the value from least_squares ("EX0C_um" ...) with no U; the reference cycle is 0 ± 0
//   by definition.
// - Time: every plot's x is time_s / 3600 (hours on the clock of the log and of inputs.csv:
//   the simulator's, or a Fanuc log's), one explicit domain for all plots (the extent of the
//   cycles and the input samples), so the plots line up under each other.
// - Plots (Vega 5 declarative specs, SVG), in this order: one per location error present
//   (EX0C ... EC0C): data set "cycles" with rows {time_s, cycle, value, U}, an area mark
//   "u_band" from value − U to value + U over its rows that have U (data set "cycles_U"), a line
//   "value_line" and a symbol mark "values" (one symbol per cycle), usermeta {kind: "error",
//   error, label, unit}; then, with inputs, one
//   plot per unit group of the inputs' columns (°C first, then rpm, then the others in the
//   file's order, columns without a unit last): data set "inputs" with rows {time_s, v0, v1,
//   ...}, one line mark "input_k" per column, usermeta {kind: "inputs", group, unit, columns:
//   [{field: "vk", column: <name in the file>}]}. Plot k is <div class="vega-plot"
//   id="plot-k"> with its spec in <script type="application/json" id="plot-k-spec">.
// - Tables: the inputs; a summary per error (first, last, last − first, min, max, range with
//   U; the U of a difference bounded by the sum of the two U, which holds for any correlation);
//   every cycle's value ± U (inside <details>, open up to 24 cycles); per error the range of U
//   over the cycles and its largest contribution; every budget of the last evaluated cycle
//   (input, type, distribution, u, share of u_c², dof, basis); the point scatter and the
//   centre repeatability (seed 004 Table 5.3 statistics); the schedule from the manifest (each
//   cycle's planned first and last probe point, the gap to the next cycle, and the evaluated
//   cycle's time against the planned mean of its points); incomplete cycles with the reason.
// - Scene: with options.scene_href, a link to the glTF scene (href as given, escaped).
// - Render errors, escaping, determinism, offline Vega: as report/vega.hpp (#vega-errors,
//   data-rendered="true", every input string escaped, byte-identical output for the same
//   inputs).
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "parts/plan_manifest.hpp"
#include "report/vega.hpp"

namespace probeloop::report {

struct SphereReportOptions {
  // File names shown on the page and named in errors ("" = a generic name).
  std::string evaluation_file, inputs_file, manifest_file;
  // The glTF scene, relative to the page's folder ("" = no link).
  std::string scene_href;
};

std::string sphereCampaignReportHtml(const nlohmann::json& evaluation, const std::string* inputs_csv_text,
                                     const parts::PlanManifest* manifest,
                                     const std::string& vega_js_path = defaultVegaPath(),
                                     const SphereReportOptions& options = {});

}  // namespace probeloop::report
