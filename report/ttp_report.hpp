// HTML report of a thermal test piece (seed 004 Ch. 7; issue 13): the errors E_X, E_Y, E_Z,
// E_B, E_TTP and the temperature equivalent ΔT against time, as seed 004 Fig. 7.10 / 7.12
// show them, beside the R-test's (sphere cycle, Ch. 5) location errors of the same machine.
//
// Contract:
// - Inputs: `evaluation` is the evaluation.json of `probeloop evaluate` for a thermal test
//   piece (kind "thermal_test_piece"; docs/report-thermal-test-piece.md lists the fields read);
//   `second_route` the other route's evaluation of the same piece (CMM vs on-machine), or
//   nullptr; `r_test_errors_csv_text` the text of an R-test errors.csv
//   (time_s,cycle,EX0C_um,...,U_EX0C_um,...; `#` comments), or nullptr. Anything that is not
//   a JSON object of kind "thermal_test_piece" with a "cycles" array, and an R-test text
//   without a time_s column or without any location-error column, is an InputError naming
//   options' file name. Every other field may be missing or null: a value absent from a cycle
//   (the gauge route has no E_Z and E_B; a feature was not measured) is left out of plots and
//   shown as "—" in tables; nothing is invented.
// - Time: every series is drawn against hours since the reference cut (the time_s of the
//   first evaluation's cycle with phase "reference", else of its lowest cycle); all time_s
//   are on one clock (the simulator's when the files come from probeloop). The R-test is
//   relative to its own first cycle: each of its channels is re-referenced to its value at
//   the reference cut (linear interpolation between its two neighbouring cycles; U kept as
//   given), so that every series is zero at t = 0; when the R-test does not cover the
//   reference cut it is drawn as given, and the page says so.
// - Plots (Vega 5 declarative specs, SVG; one per quantity present in a route, in this
//   order): (1) E_X with the R-test's E_X0C (apparent), (2) E_Y with E_Y0C, (3) E_Z with
//   E_Z0T, (4) E_B with −E_B0C (E_B = −ΔE_B0C, docs/thermal-test-piece.md §4), (5) E_TTP
//   (Eq. 7.3) with the Eq. 7.9 form of each route, (6) ΔT of the piece (the evaluation's
//   dT_K) with ΔT of the table from the R-test: E_R0T / (α_table · R_r-test) (Eq. 7.10;
//   11 µm/(m·K) and 160 mm by default, seed 004 Sec. 7.3). Routes are points with ±U error
//   bars (rule marks), the R-test a line with its ±U band. Then, with options.inputs_csv_text,
//   the machine's temperatures (every column ending in _C, one line each) and the C axis's
//   speed (c_rpm, a step line) over the errors' hours; usermeta {"inputs": "temperatures" |
//   "c_load", "series": [{data, column}]}; an inputs text without time_s, or with neither a
//   temperature nor c_rpm, is an InputError naming options.inputs_file. Plot k is <div
//   class="vega-plot" id="plot-k"> with its spec in <script type="application/json"
//   id="plot-k-spec">; the spec's "usermeta" names the quantity and its series; every series
//   is a data set whose rows are {time_s, cycle, value, U} (R-test rows also carry the
//   file's number as "input"; input rows are {time_s, value}). The time axes are labelled h:mm.
// - Tables: inputs; per route and cycle value ± U of every quantity (unit in the column
//   name: µm, µrad, K; t as h:mm) and E_TTP by Eq. 7.9; the spans in Table 7.2's layout
//   (period as h:mm × quantity) and the comparison with reductions when present; per quantity
//   the largest budget contribution in the last cycle that has it; the formulas with the
//   thesis's section and equation ("Blaser 2020 (ETH Diss. 26709), Sec. 7.2, Eq. 7.1"), never
//   our notes' paths or the source file's line numbers. Every value ± U with |value| ≤ U is
//   marked not significant (web::tdValueU: class "ns", "n.s."). Eqs. 7.1 and 7.2 as printed
//   (the evaluation's also.EX_printed_um, EY_printed_um) are not in these tables: a note
//   under the formulas shows the printed equation and why it is wrong, and an appendix at the
//   end lists their values.
// - Render errors, escaping, determinism, offline Vega: as report/model_report.hpp
//   (#vega-errors, data-rendered="true", every input string escaped, byte-identical output
//   for the same inputs).
#pragma once
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "report/vega.hpp"

namespace probeloop::report {

struct TtpReportOptions {
  // File names shown on the page and named in errors ("" = a generic name).
  std::string evaluation_file, second_file, r_test_file;
  // Eq. 7.10 for the machine table (seed 004 L2177): cast iron, the R-test sphere's radius.
  double table_alpha_um_per_m_K = 11.0;
  double r_test_radius_mm = 160.0;
  // The machine's logged inputs (inputs.csv: time_s, temperatures in columns ending in _C, the
  // C axis's speed c_rpm), on the evaluation's clock, and its file name; nullopt: no such plots.
  std::optional<std::string> inputs_csv_text;
  std::string inputs_file;
};

std::string thermalTestPieceReportHtml(const nlohmann::json& evaluation, const nlohmann::json* second_route,
                                       const std::string* r_test_errors_csv_text,
                                       const std::string& vega_js_path = defaultVegaPath(),
                                       const TtpReportOptions& options = {});

}  // namespace probeloop::report
