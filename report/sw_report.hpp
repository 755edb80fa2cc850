// HTML report of a stepped workpiece (seed 000, Yaqoob 2017; issue 14): the components
// separated from one part with their U, and, for a compensated part, every feature's error
// before and after the compensation against the fall it promised (Ch. 6).
//
// Contract:
// - Input: the evaluation.json of `probeloop evaluate` for a stepped workpiece (kind
//   "stepped_workpiece", with "separation" and "cmm"; docs/stepped-workpiece.md §6–7). Anything
//   else is an InputError naming the file. A missing value is left out of the plots and shown
//   as "—"; nothing is invented.
// - Plots (Vega 5, as report/vega.hpp; each series a data set of rows {x, value, U}, points
//   with ±U error bars as rule marks): (1) e_pos_x and e_pos_y against the probe's travel
//   (mm) with the fitted lines k·L; (2) e_proc_x and e_proc_y (two walls) against the feed
//   (mm/min); (3) e_splz against the Temp state (min); (4) only with "before_after": per
//   feature the CMM error before and after, and the error the compensation promised
//   (before − promised fall) with its ±U.
// - Tables: per step and route the geometry (width and depth errors, wall tilts, floor slopes,
//   Oz); per step the components value ± U; per component of the last step its largest
//   budget line; the before/after table.
// - Render errors, escaping, determinism, offline Vega: as report/model_report.hpp.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "report/vega.hpp"

namespace probeloop::report {

std::string steppedWorkpieceReportHtml(const nlohmann::json& evaluation, const std::string& evaluation_file,
                                       const std::string& vega_js_path = defaultVegaPath());

}  // namespace probeloop::report
