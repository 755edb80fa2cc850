// The live loop's HTML dashboard (`campaign run --html`), rewritten after every pass.
//
// Contract (the page contract of report/vega.hpp: offline, Vega specs rendered by the inlined
// runtime, every input string escaped, render errors in #vega-errors, deterministic):
// - header: store, machine, TALC phase now, the options, the latest evaluated cycle's seven
//   errors with U (k = 2);
// - one plot per TALC channel against time in hours: the uncompensated error (measured, or
//   measured + the offset in effect when the offsets were applied) with its U as error bars,
//   the prediction on the grid (line), the compensated residual of each measurement after the
//   CP (red beyond the action limit), the action limits (dashed), the calibration and
//   No-Good phases as shaded bands; plot k is <div class="vega-plot" id="plot-k">;
// - Table 6.5's layout over the compensation phase so far (P99 uncompensated, compensated,
//   reduction), the model versions, and the event list.
#pragma once
#include <string>

#include "campaign/live_loop.hpp"
#include "campaign/store.hpp"

namespace probeloop::campaign {

std::string liveDashboardHtml(CampaignStore& store, const LiveLoop& loop, const std::string& vega_js_path);

// Table 6.5's layout over the measurements after the calibration phase: P99 (Hazen) of the
// uncompensated error and of the compensated one (with the offsets applied: what the cycle
// measured; replayed: the residual against the prediction), reduction; rounded to 0.1.
std::string liveSummaryText(const LiveLoop& loop);

}  // namespace probeloop::campaign
