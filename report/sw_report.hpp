// HTML report of a stepped workpiece (seed 000, Yaqoob 2017; issue 14): the components
// separated from one part with their U, and, for a compensated part, every feature's error
// before and after the compensation against the fall it promised (Ch. 6). Given the part cut
// plain and the part cut compensated, both are shown side by side: the plain part's numbers
// are the ones `probeloop evaluate` prints for it.
//
// Contract:
// - Inputs: `evaluation`, the evaluation.json of `probeloop evaluate` for a stepped workpiece
//   (kind "stepped_workpiece", with "separation" and "cmm"; docs/stepped-workpiece.md §6–7);
//   `compensated`, nullptr or the evaluation of the same experiment cut with the compensation
//   and evaluated with `--compare` against `evaluation` (its "before_after"). Anything else,
//   and a compensated evaluation whose before values are not `evaluation`'s CMM errors (it
//   was compared with another part), is an InputError naming the file. Without `compensated`
//   the one evaluation is shown alone (with its own before/after when it has one: the old
//   form). A missing value is left out of the plots and shown as "—"; nothing is invented.
// - Plots (Vega 5, as report/vega.hpp; each series a data set of rows {x, value, U, step},
//   points with ±U error bars as rule marks; the compensated part's points open): (1) e_pos_x
//   and e_pos_y against the probe's travel (mm) with the fitted lines k·L; (2) e_proc_x and
//   e_proc_y (two walls) against the feed (mm/min); (3) e_splz against the Temp state (min);
//   (4) only with a before/after: per feature the CMM error before and after, each ± its U
//   (U = 2 u of the CMM's measurement of the width or depth, from each part's separation),
//   and the error the compensation promised (before − promised fall) ± its U.
// - Tables, each inside <div class="table-wrap"> (a scroll container: nothing is cut off):
//   per part and step the components value ± U; per part, route and step the widths and the
//   depth error ± U (CMM: 2 u of its measurement; on the machine: the probe's share of
//   e_pos's budget, u_c² − u_CMM²); the orientations ± U (wall tilts, floor slopes, Oz = the
//   angle between the X and the Y walls' normals − 90°) in a table of their own; the
//   before/after ± U; per component of the last step its largest budget line. Every value
//   with |value| ≤ U carries class "ns" (web::tdValueU): "n.s." for errors, "not resolved"
//   for orientations, with a sentence saying what it means.
// - Render errors, escaping, determinism, offline Vega: as report/model_report.hpp.
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "report/vega.hpp"

namespace probeloop::report {

std::string steppedWorkpieceReportHtml(const nlohmann::json& evaluation, const std::string& evaluation_file,
                                       const std::string& vega_js_path = defaultVegaPath(),
                                       const nlohmann::json* compensated = nullptr,
                                       const std::string& compensated_file = "");

}  // namespace probeloop::report
