#include "report/sphere_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "report/sphere_report_plots.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
using namespace web;
using sphere::ErrorInfo;
using sphere::kErrors;

constexpr std::size_t kOpenTableCycles = 24;  // longer cycle tables start collapsed

void checkEvaluation(const json& j, const std::string& file) {
  const std::string what = "sphere-campaign report: the evaluation";
  if (!j.is_object())
    throw InputError(file, 0, what + " is not a JSON object (expected the evaluation.json of `probeloop evaluate`)");
  const std::string kind = text(j, "kind");
  bool sphere = kind == "sphere_artifact";
  if (kind.empty() && text(j, "format") == "probeloop-evaluation")  // written before "kind" existed
    for (const auto& c : array(j, "cycles")) sphere |= field(c, "least_squares") != nullptr;
  if (!sphere)
    throw InputError(file, 0,
                     what + (kind.empty() ? " has no \"kind\"" : " has kind \"" + kind + "\"") +
                         ", expected \"sphere_artifact\" (the evaluation.json of `probeloop evaluate` for a "
                         "sphere-artifact campaign; a thermal test piece has `probeloop report ttp`, a stepped "
                         "workpiece `probeloop report stepped`)");
  const json* cycles = field(j, "cycles");
  if (cycles == nullptr || !cycles->is_array()) throw InputError(file, 0, what + " has no \"cycles\" array");
}

void checkManifest(const parts::PlanManifest& m, const json& evaluation, const std::string& file) {
  if (m.kind != "sphere_artifact")
    throw InputError(file, 0,
                     "sphere-campaign report: the manifest has kind \"" + m.kind +
                         "\", expected \"sphere_artifact\" (the plan.json `probeloop plan` wrote for the campaign)");
  for (const auto& c : array(evaluation, "cycles"))
    if (const auto n = number(c, "cycle"); n && *n > m.cycles)
      throw InputError(file, 0,
                       "sphere-campaign report: the manifest plans " + std::to_string(m.cycles) +
                           " cycles, the evaluation holds cycle " + whole(*n) +
                           ": not the plan of this campaign (expected the plan.json the evaluation used)");
}

std::string hMin(double seconds) {  // "71:58" (h:mm)
  const long long minutes = std::llround(std::abs(seconds) / 60.0);
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s%lld:%02lld", seconds < 0 ? "\u2212" : "", minutes / 60, minutes % 60);
  return buf;
}

std::string hoursAt(double time_s) { return fixed(time_s / 3600.0, 2) + " h"; }

// A number from a description as written there (up to 4 decimals, no trailing zeros): "160", "12.5".
std::string plain(double x) {
  std::string s = fixed(x, 4);
  if (s.find('.') != std::string::npos) {
    s.erase(s.find_last_not_of('0') + 1);
    if (s.back() == '.') s.pop_back();
  }
  return dropNegativeZero(s);
}

std::string orDash(const std::string& s) { return s.empty() ? kDash : s; }

std::string infOr(const std::optional<double>& x, int digits) { return x ? sig(*x, digits) : "\u221e"; }

struct Row {  // one error in one cycle
  double time_s = 0;
  std::optional<double> cycle, value, U;
};

std::vector<Row> rowsOf(const json& rows) {
  std::vector<Row> out;
  for (const auto& r : rows) out.push_back({*number(r, "time_s"), number(r, "cycle"), number(r, "value"), number(r, "U")});
  std::stable_sort(out.begin(), out.end(), [](const Row& a, const Row& b) { return a.time_s < b.time_s; });
  return out;
}

// U of a − b for any correlation of a and b: JCGM 100 Eq. (16) for y = a − b gives
// u²(y) = u_a² + u_b² − 2 r u_a u_b ≤ (u_a + u_b)² for every r ≥ −1; with the same k, U ≤ U_a + U_b.
std::optional<double> sumU(const Row& a, const Row& b) {
  if (!a.U || !b.U) return std::nullopt;
  return *a.U + *b.U;
}

// A value ± U with the cycle and time it belongs to on a second line (markup, escaped).
std::string atCycle(const Row& r, const std::optional<double>& reference) {
  return tdHtml(esc(valueU(r.value, r.U)) + "<br><span class=\"at\">" +
                    esc(std::string(r.cycle && r.cycle == reference ? "reference cycle " : "cycle ") + whole(r.cycle) +
                        ", " + hoursAt(r.time_s)) +
                    "</span>",
                true);
}

// ---------------------------------------------------------------------------------------
// Header.

void metaRow(Page& page, const std::string& name, const std::string& value) {
  page.html += "<tr>" + th(name) + td(orDash(value)) + "</tr>\n";
}

void header(Page& page, const json& eval, const sphere::Inputs* in, const parts::PlanManifest* m,
            const SphereReportOptions& o, const std::string& title) {
  const json& cycles = array(eval, "cycles");
  std::vector<double> times;
  for (const auto& c : cycles)
    if (const auto t = number(c, "time_s")) times.push_back(*t);
  std::sort(times.begin(), times.end());
  const std::string span = times.empty() ? kDash
                                         : hMin(times.back() - times.front()) + " (h:mm), from " +
                                               hoursAt(times.front()) + " to " + hoursAt(times.back()) +
                                               " on the log's clock";
  page.html += "<header>\n<h1>" + esc(title) + "</h1>\n<p>The location errors of the C axis measured with the "
               "sphere artifact (Blaser 2020, ETH Diss. 26709, Ch. 5): every cycle probes the spheres at their C positions, fits their "
               "centres and turns the centres' change since the reference cycle into EX0C, EY0C, EZ0T, ER0T, EA0C, "
               "EB0C and EC0C (Eqs. 5.4\u20135.10; signs: docs/conventions.md), each with its GUM budget "
               "(docs/uncertainty.md).</p>\n<table class=\"meta\">\n";
  metaRow(page, "machine", m ? m->machine_name : "not known without the plan (--manifest)");
  std::string artifact;
  if (m) {
    artifact = "spheres of \u00d8 " + plain(2 * m->sphere_radius_mm) + " mm at d/2 = " +
               plain(m->radius_from_axis_mm) + " mm from the C axis, " + std::to_string(m->spheres.size()) +
               " positions (C =";
    for (std::size_t i = 0; i < m->spheres.size(); ++i)
      artifact += (i ? ", " : " ") + plain(m->spheres[i].c_deg) + "\u00b0";
    artifact += ")";
  } else if (const auto d = number(eval, "d_m")) {
    artifact = "d = " + plain(*d * 1e3) + " mm (the evaluation's; the spheres are in the plan)";
  }
  metaRow(page, "artifact", artifact);
  std::string count = std::to_string(cycles.size()) + " evaluated";
  if (const auto ref = number(eval, "reference_cycle")) count += ", reference cycle " + whole(*ref);
  if (!array(eval, "incomplete_cycles").empty())
    count += ", " + std::to_string(array(eval, "incomplete_cycles").size()) + " incomplete";
  if (m) count += "; " + std::to_string(m->cycles) + " planned";
  metaRow(page, "cycles", count);
  metaRow(page, "span (first to last cycle)", span);
  metaRow(page, "evaluation", o.evaluation_file.empty() ? "evaluation" : o.evaluation_file);
  metaRow(page, "measured points (the evaluation's input)", text(eval, "points_file"));
  metaRow(page, "plan manifest (the evaluation's)", text(eval, "manifest"));
  std::string positions;
  for (const auto& p : array(eval, "least_squares_positions")) positions += (positions.empty() ? "" : " ") + whole(number(&p));
  metaRow(page, "least squares over positions", positions);
  if (o.manifest_file.size()) metaRow(page, "schedule from", o.manifest_file);
  if (in != nullptr) {
    std::string cols;
    for (const auto& c : in->columns) cols += (cols.empty() ? "" : ", ") + c.name;
    std::string what = (in->file.empty() ? std::string("inputs") : in->file) + ": " +
                       std::to_string(in->table.rows.size()) + " samples";
    if (!in->time_s.empty()) {
      const auto [lo, hi] = std::minmax_element(in->time_s.begin(), in->time_s.end());
      what += " from " + hoursAt(*lo) + " to " + hoursAt(*hi);
    }
    metaRow(page, "logged inputs", what + "; columns " + cols);
  } else {
    metaRow(page, "logged inputs", "none given (--inputs RUN/inputs.csv adds the temperatures and loads)");
  }
  page.html += "</table>\n";
  if (!o.scene_href.empty())
    page.html += "<p class=\"scene\">3D scene: <a href=\"" + esc(o.scene_href) + "\">" + esc(o.scene_href) +
                 "</a> (glTF 2.0: the table, the C axis, the spheres, the probed points and each cycle's "
                 "sphere-centre displacements as exaggerated vectors; the link is relative to this page's folder). "
                 "Open it in any glTF 2.0 viewer, e.g. Blender (File \u203a Import \u203a glTF 2.0).</p>\n";
  page.html +=
      "<h2>How to read this page</h2>\n<ul class=\"how\">\n"
      "<li>Each error has its own plot against time in hours: the points are the cycles, the band is value "
      "\u00b1 U (k = 2). The reference cycle is 0 by definition; a band that does not include 0 is a change the "
      "campaign resolved.</li>\n"
      "<li>Lengths are in \u00b5m, angles in \u00b5rad (= \u00b5m/m). All plots share one time axis: the "
      "temperatures and loads below line up with the errors above them.</li>\n"
      "<li>The tables give every number with its U; the budgets say what U is made of (the last evaluated "
      "cycle's, every term as the evaluation states it), and the schedule compares the plan with when the "
      "cycles were measured.</li>\n</ul>\n</header>\n";
}

// ---------------------------------------------------------------------------------------
// Tables.

void summaryTable(Page& page, const std::vector<std::pair<const ErrorInfo*, json>>& series,
                  const std::optional<double>& ref) {
  page.html += "<h3>Summary per error</h3>\n<p class=\"note\">value \u00b1 U (k = 2). A difference of two cycles "
               "is shown with U_a + U_b, an upper bound whatever the correlation of the two (JCGM 100 Eq. (16) "
               "with r \u2265 \u22121; both are relative to the same reference cycle).</p>\n<table class=\"summary\">\n<thead><tr>" +
               th("error") + th("first cycle", true) + th("last cycle", true) + th("last \u2212 first", true) +
               th("min", true) + th("max", true) + th("max \u2212 min", true) + "</tr></thead>\n<tbody>\n";
  for (const auto& [e, rows_json] : series) {
    const auto rows = rowsOf(rows_json);
    if (rows.empty()) continue;
    const Row &first = rows.front(), &last = rows.back();
    const Row* lo = &rows.front();
    const Row* hi = &rows.front();
    for (const auto& r : rows) {
      if (*r.value < *lo->value) lo = &r;
      if (*r.value > *hi->value) hi = &r;
    }
    page.html += "<tr>" + th(std::string(e->label) + " (" + e->unit + ")") +
                 atCycle(first, ref) + atCycle(last, ref) +
                 td(valueU(*last.value - *first.value, sumU(first, last)), true) + atCycle(*lo, ref) +
                 atCycle(*hi, ref) +
                 td(valueU(*hi->value - *lo->value, sumU(*hi, *lo)), true) + "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

void cycleTable(Page& page, const json& eval) {
  const json& cycles = array(eval, "cycles");
  page.html += std::string("<details class=\"cycles\"") + (cycles.size() <= kOpenTableCycles ? " open" : "") +
               "><summary>Every cycle: value \u00b1 U (k = 2), " + std::to_string(cycles.size()) +
               " cycles</summary>\n<div class=\"wide\">\n<table class=\"cycles\">\n<thead><tr>" + th("cycle", true) +
               th("t (h)", true);
  for (const auto& e : kErrors) page.html += th(std::string(e.label) + " \u00b1 U (" + e.unit + ")", true);
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& c : cycles) {
    const auto t = number(c, "time_s");
    page.html += "<tr>" + td(whole(number(c, "cycle")), true) + td(t ? fixed(*t / 3600.0, 3) : kDash, true);
    for (const auto& e : kErrors) {
      const auto [v, U] = sphere::cycleValue(c, e);
      page.html += td(valueU(v, U), true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n</div>\n</details>\n";
}

const json* budgetOf(const json& cycle, const ErrorInfo& e) {
  for (const auto& b : array(cycle, "budgets"))
    if (sphere::isBudgetOf(b, e)) return &b;
  return nullptr;
}

void budgetSection(Page& page, const json& eval) {
  const json& cycles = array(eval, "cycles");
  const auto ref = number(eval, "reference_cycle");
  const auto isReference = [&ref](const json& c) { return ref && number(c, "cycle") == ref; };
  page.html += "<h3>Range of U over the cycles (the reference cycle left out)</h3>\n<table class=\"u-range\">\n"
               "<thead><tr>" + th("error") + th("smallest U", true) + th("largest U", true) +
               th("largest contribution at the largest U") + th("its u", true) + "</tr></thead>\n<tbody>\n";
  bool any = false;
  for (const auto& e : kErrors) {
    const json *lo = nullptr, *hi = nullptr, *lo_c = nullptr, *hi_c = nullptr;
    for (const auto& c : cycles) {
      const json* b = budgetOf(c, e);
      if (isReference(c) || b == nullptr || !number(*b, "U")) continue;
      if (lo == nullptr || *number(*b, "U") < *number(*lo, "U")) lo = b, lo_c = &c;
      if (hi == nullptr || *number(*b, "U") > *number(*hi, "U")) hi = b, hi_c = &c;
    }
    if (hi == nullptr) continue;
    any = true;
    const json* top = nullptr;
    for (const auto& k : array(*hi, "contributions"))
      if (number(k, "u") && (top == nullptr || std::abs(*number(k, "u")) > std::abs(*number(*top, "u")))) top = &k;
    page.html += "<tr>" + th(std::string(e.label) + " (" + e.unit + ")") +
                 td(sig(number(*lo, "U"), 3) + " (cycle " + whole(number(*lo_c, "cycle")) + ")", true) +
                 td(sig(number(*hi, "U"), 3) + " (cycle " + whole(number(*hi_c, "cycle")) + ")", true) +
                 td(top ? orDash(text(*top, "input")) : kDash) +
                 td(top ? withUnit(sig(number(*top, "u"), 2), e.unit) : kDash, true) + "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
  if (!any) page.html += "<p class=\"note\">No budgets in the evaluation.</p>\n";

  const json* last = nullptr;
  for (const auto& c : cycles)
    if (!isReference(c) && !array(c, "budgets").empty()) last = &c;
  if (last == nullptr) return;
  page.html += "<h3>Budgets of cycle " + whole(number(*last, "cycle")) +
               " (the last evaluated), every term as the evaluation states it</h3>\n<p class=\"note\">u: the "
               "term's standard uncertainty in the error's unit (its sensitivity applied); share: u\u00b2 / "
               "u_c\u00b2. A term the description does not state is listed with 0 and says so "
               "(docs/uncertainty.md).</p>\n";
  for (const auto& e : kErrors) {
    const json* b = budgetOf(*last, e);
    if (b == nullptr) continue;
    const auto uc = number(*b, "u_c");
    page.html += "<h4>" + esc(std::string(e.label) + " = " + withUnit(valueU(number(*b, "value"), number(*b, "U")), e.unit) +
                              " (k = " + sig(number(*b, "k"), 3) + "): u_c = " + withUnit(sig(uc, 2), e.unit) +
                              ", \u03bd_eff = " + infOr(number(*b, "nu_eff"), 3)) +
                 "</h4>\n<table class=\"budget\">\n<thead><tr>" + th("input") + th("type") + th("distribution") +
                 th("u (" + std::string(e.unit) + ")", true) + th("share of u_c\u00b2 (%)", true) + th("dof", true) +
                 th("basis") + "</tr></thead>\n<tbody>\n";
    for (const auto& k : array(*b, "contributions")) {
      const auto u = number(k, "u");
      const std::string share = u && uc && *uc > 0 ? fixed(100.0 * *u * *u / (*uc * *uc), 1) : kDash;
      page.html += "<tr>" + td(orDash(text(k, "input"))) + td(orDash(text(k, "type"))) +
                   td(orDash(text(k, "distribution"))) + td(sig(u, 2), true) + td(share, true) +
                   td(infOr(number(k, "dof"), 3), true) + td(orDash(text(k, "basis"))) + "</tr>\n";
    }
    page.html += "</tbody>\n</table>\n";
  }
}

void scatterAndRepeatability(Page& page, const json& eval) {
  const json& s = object(eval, "point_scatter");
  if (number(s, "type_a_sigma_um") || number(s, "type_b_sigma_um"))
    page.html += "<p>Probe point scatter: specification \u03c3 = " + withUnit(sig(number(s, "type_b_sigma_um"), 2), "\u00b5m") +
                 " (type B), pooled fit residual s = " + withUnit(sig(number(s, "type_a_sigma_um"), 2), "\u00b5m") +
                 " (type A, \u03bd = " + whole(number(s, "type_a_dof")) + "); the budgets use " +
                 esc(orDash(text(s, "used"))) + ".</p>\n";
  const json& rep = array(eval, "centre_repeatability");
  if (rep.empty()) return;
  page.html += "<h3>Sphere-centre repeatability over the cycles (Blaser 2020, Table 5.3 statistics)</h3>\n<p "
               "class=\"note\">U = 2 s for one measurement and 2 s/\u221an for the mean of n; 3D = root-sum-square "
               "of X, Y, Z. Over a campaign the drift between cycles is included.</p>\n<table class=\"repeatability\">"
               "\n<thead><tr>" + th("position") + th("cycles", true) + th("s X, Y, Z (\u00b5m)", true) +
               th("U X, Y, Z (\u00b5m)", true) + th("U 3D (\u00b5m)", true) + th("U 3D of the mean (\u00b5m)", true) +
               "</tr></thead>\n<tbody>\n";
  const auto triple = [](const json& a) {
    std::string out;
    for (const auto& x : a) out += (out.empty() ? "" : ", ") + sig(number(&x), 2);
    return out.empty() ? kDash : out;
  };
  for (const auto& r : rep)
    page.html += "<tr>" + th(whole(number(r, "position"))) + td(whole(number(r, "cycles")), true) +
                 td(triple(array(r, "s_um")), true) + td(triple(array(r, "U_single_um")), true) +
                 td(sig(number(r, "U_single_3d_um"), 2), true) + td(sig(number(r, "U_mean_3d_um"), 2), true) + "</tr>\n";
  page.html += "</tbody>\n</table>\n";
}

void scheduleSection(Page& page, const json& eval, const parts::PlanManifest* m) {
  page.html += "<section class=\"schedule\">\n<h2>Schedule</h2>\n";
  if (m == nullptr) {
    page.html += "<p class=\"note\">No plan given (--manifest PLAN/plan.json adds the planned cycles).</p>\n</section>\n";
    return;
  }
  double tau_min = 0, tau_max = 0, tau_sum = 0;
  for (std::size_t i = 0; i < m->points.size(); ++i) {
    const double t = m->points[i].time_in_cycle_s;
    tau_min = i ? std::min(tau_min, t) : t;
    tau_max = i ? std::max(tau_max, t) : t;
    tau_sum += t;
  }
  const double tau_mean = m->points.empty() ? 0 : tau_sum / m->points.size();
  std::vector<const json*> evaluated(m->cycles + 1, nullptr);
  for (const auto& c : array(eval, "cycles"))
    if (const auto n = number(c, "cycle"); n && *n >= 1 && *n <= m->cycles && *n == std::round(*n))
      evaluated[static_cast<std::size_t>(*n)] = &c;
  std::vector<std::string> incomplete(m->cycles + 1);
  for (const auto& c : array(eval, "incomplete_cycles"))
    if (const auto n = number(c, "cycle"); n && *n >= 1 && *n <= m->cycles && *n == std::round(*n))
      incomplete[static_cast<std::size_t>(*n)] = orDash(text(c, "reason"));
  const auto ref = number(eval, "reference_cycle");

  std::string rows;
  double worst = -1;
  int worst_cycle = 0, n_eval = 0;
  for (int c = 1; c <= m->cycles && c <= static_cast<int>(m->cycle_start_s.size()); ++c) {
    const double start = m->cycle_start_s[c - 1];
    const double first = start + tau_min, lastp = start + tau_max;
    std::string gap = kDash;
    if (c < m->cycles && c < static_cast<int>(m->cycle_start_s.size()))
      gap = fixed((m->cycle_start_s[c] + tau_min - lastp) / 60.0, 2);
    std::string measured = kDash, delta = kDash, status;
    if (const json* e = evaluated[c]) {
      ++n_eval;
      status = ref && number(*e, "cycle") == ref ? "reference" : "evaluated";
      if (const auto t = number(*e, "time_s")) {
        measured = fixed(*t / 3600.0, 3);
        const double d = *t - (start + tau_mean);
        delta = fixed(d, 1);
        if (std::abs(d) > worst) worst = std::abs(d), worst_cycle = c;
      }
    } else if (!incomplete[c].empty()) {
      status = "incomplete: " + incomplete[c];
    } else {
      status = "not in the log";
    }
    rows += "<tr>" + td(std::to_string(c), true) + td(fixed(first / 3600.0, 3), true) +
            td(fixed(lastp / 3600.0, 3), true) + td(gap, true) + td(measured, true) + td(delta, true) + td(status) +
            "</tr>\n";
  }
  const double planned_end = m->cycle_start_s.empty() ? 0 : m->cycle_start_s.back() + tau_max;
  page.html += "<p>Planned: " + std::to_string(m->cycles) + " cycles of " + withUnit(sig(m->cycle_time_s, 4), "s") +
               " (a cycle after the first), " + withUnit(sig(m->gap_s, 4), "s") + " between them" +
               (m->tool_change_each_cycle ? ", the probe changed in and out every cycle" : "") +
               "; probing from " + hoursAt(m->cycle_start_s.empty() ? 0 : m->cycle_start_s.front() + tau_min) +
               " to " + hoursAt(planned_end) + " (" + hMin(planned_end) + " h:mm) after the program's start. " +
               std::to_string(n_eval) + " of them are in the evaluation" +
               (worst >= 0 ? "; the evaluated times differ from the planned mean point times by at most " +
                                 withUnit(fixed(worst, 1), "s") + " (cycle " + std::to_string(worst_cycle) + ")"
                           : std::string()) +
               ".</p>\n<p class=\"note\">Planned times count from the program's start, taken as t = 0 of the log's "
               "clock (the simulator's; a Fanuc log's own clock may start elsewhere, which shows as a constant "
               "difference). An evaluated cycle's time is the mean time of its points (logged, or planned when the "
               "log has no clock); it is compared with the planned mean of the same points.</p>\n";
  page.html += std::string("<details class=\"schedule\"") + (m->cycles <= static_cast<int>(kOpenTableCycles) ? " open" : "") +
               "><summary>Every planned cycle</summary>\n<table class=\"schedule\">\n<thead><tr>" + th("cycle", true) +
               th("first point (h)", true) + th("last point (h)", true) + th("gap to the next cycle (min)", true) +
               th("evaluated time (h)", true) + th("evaluated \u2212 planned mean (s)", true) + th("status") +
               "</tr></thead>\n<tbody>\n" + rows + "</tbody>\n</table>\n</details>\n</section>\n";
}

}  // namespace

std::string sphereCampaignReportHtml(const json& evaluation, const std::string* inputs_csv_text,
                                     const parts::PlanManifest* manifest, const std::string& vega_js_path,
                                     const SphereReportOptions& options) {
  checkEvaluation(evaluation, options.evaluation_file);
  if (manifest != nullptr) checkManifest(*manifest, evaluation, options.manifest_file);
  std::optional<sphere::Inputs> inputs;
  if (inputs_csv_text != nullptr) inputs = sphere::readInputs(*inputs_csv_text, options.inputs_file);
  const std::string vega = vegaRuntime(vega_js_path);  // a missing runtime is an error whatever the data

  std::vector<std::pair<const ErrorInfo*, json>> series;
  for (const auto& e : kErrors)
    if (json rows = sphere::errorRows(evaluation, e); !rows.empty()) series.emplace_back(&e, std::move(rows));

  // One time domain for every plot (hours on the log's clock).
  std::optional<double> lo, hi;
  const auto extend = [&lo, &hi](double t_s) {
    lo = lo ? std::min(*lo, t_s) : t_s;
    hi = hi ? std::max(*hi, t_s) : t_s;
  };
  for (const auto& [e, rows] : series)
    for (const auto& r : rows) extend(*number(r, "time_s"));
  if (inputs)
    for (const double t : inputs->time_s) extend(t);
  sphere::Domain x_h{lo.value_or(0) / 3600.0, hi.value_or(0) / 3600.0};
  if (!(x_h.second > x_h.first)) x_h = {x_h.first - 0.5, x_h.first + 0.5};

  const std::string title = "Sphere-artifact campaign: location errors of the C axis" +
                            (manifest && !manifest->machine_name.empty() ? " on " + manifest->machine_name : "");
  Page page;
  header(page, evaluation, inputs ? &*inputs : nullptr, manifest, options, title);
  page.html += "<div id=\"vega-errors\" class=\"errors\" role=\"alert\"></div>\n<script>" + std::string(kErrorHook) +
               "</script>\n";

  page.html += "<section class=\"plots\">\n<h2>Location errors against time</h2>\n";
  for (const auto& [e, rows] : series) {
    page.html += "<h3>" + esc(std::string(e->label) + ": " + e->what + " (" + e->eq + ")") + "</h3>\n";
    page.plot(sphere::errorPlotSpec(*e, rows, x_h),
              std::string(e->label) + " of each of the " + std::to_string(rows.size()) +
                  " cycles (points, line) with value \u00b1 U (k = 2) as the band, in " + e->unit +
                  ", relative to the reference cycle.");
  }
  if (series.empty()) page.html += "<p class=\"note\">No values in the evaluation: nothing to plot.</p>\n";
  page.html += "</section>\n<section class=\"inputs\">\n<h2>Temperatures and loads against time</h2>\n";
  if (inputs) {
    for (const auto& g : inputs->groups) {
      std::string names;
      for (const int i : g.columns) names += (names.empty() ? "" : ", ") + inputs->columns[i].name;
      page.html += "<h3>" + esc(g.title) + "</h3>\n";
      page.plot(sphere::inputsPlotSpec(*inputs, g, x_h),
                "From " + (inputs->file.empty() ? std::string("the inputs") : inputs->file) + ": " + names +
                    (g.unit.empty() ? " (no unit in the name: a state drawn as steps, or a count)" : " (" + g.unit + ")") +
                    ", as logged (the file states no uncertainty), on the errors' time axis.");
    }
  } else {
    page.html += "<p class=\"note\">No inputs given: `--inputs RUN/inputs.csv` (the run's logged temperatures, "
                 "C-axis and spindle speeds) draws them here on the errors' time axis.</p>\n";
  }
  page.html += "</section>\n<section class=\"values\">\n<h2>Values</h2>\n";
  summaryTable(page, series, number(evaluation, "reference_cycle"));
  cycleTable(page, evaluation);
  for (const auto& c : array(evaluation, "incomplete_cycles"))
    page.html += "<p class=\"note\">Cycle " + esc(whole(number(c, "cycle"))) + " not evaluated: " +
                 esc(orDash(text(c, "reason"))) + "</p>\n";
  page.html += "</section>\n<section class=\"budgets\">\n<h2>Uncertainty budgets</h2>\n";
  scatterAndRepeatability(page, evaluation);
  budgetSection(page, evaluation);
  page.html += "</section>\n";
  page.html += inputWarningsSection(evaluation);
  scheduleSection(page, evaluation, manifest);

  std::string out =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<meta name=\"generator\" "
      "content=\"probeloop\">\n<title>" +
      esc(title) + "</title>\n<style>" + kStyle +
      "h4 { font-size: .95em; margin: 1.1em 0 .2em; font-weight: 600; }\n"
      "details > summary { cursor: pointer; color: #1f5f9f; margin: .4em 0; }\n"
      "span.at { font-size: .85em; color: #666; }\n"
      "div.wide { overflow-x: auto; }\ntable.cycles th, table.cycles td { padding: .2em .45em; }\n</style>\n</head>\n<body>\n";
  out += page.html;
  out += "<script>\n" + vega + "\n</script>\n<script>" + kRender + "</script>\n</body>\n</html>\n";
  return out;
}

}  // namespace probeloop::report
