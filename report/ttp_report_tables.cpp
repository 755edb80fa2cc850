// The thermal-test-piece report's tables: values per cycle, spans, the comparison, budgets,
// formulas with their references, the inputs, and the note and appendix on Eqs. 7.1 and 7.2
// as printed (report/ttp_report_parts.hpp).
#include <algorithm>
#include <cmath>

#include "report/ttp_report_parts.hpp"

namespace probeloop::report::ttp_detail {
namespace {

using namespace web;

std::string twoDecimals(const std::optional<double>& x) { return x ? fixed(*x, 2) : kDash; }

std::string phaseText(const std::string& phase) {
  if (phase == "warm_up") return "warm-up";
  return phase.empty() ? kDash : phase;
}

std::string cycleHours(const json& c, double t0_s) {
  const auto t = number(c, "time_s");
  return t ? hoursMinutes(*t - t0_s) : kDash;
}

// E_TTP by Eq. 7.9 beside the quantities: a form the thesis gives, not a misprint.
struct Also {
  const char* key;
  const char* title;
};
constexpr Also kAlso[] = {{"ETTP_7_9_um", "E_TTP, Eq. 7.9 \u00b1 U (\u00b5m)"}};
constexpr Also kPrinted[] = {{"EX_printed_um", "E_X, Eq. 7.1 as printed (\u00b5m)"},
                             {"EY_printed_um", "E_Y, Eq. 7.2 as printed (\u00b5m)"}};

}  // namespace

void cycleTable(Page& page, const Route& r, double t0_s) {
  const json& eval = *r.eval;
  const auto quantities = routeQuantities(eval);
  const json& cycles = array(eval, "cycles");
  page.html += "<h3>" + esc(r.label) + ": values per cycle (value \u00b1 U; t = hours:minutes since the reference cut)</h3>\n";
  if (cycles.empty()) {
    page.html += "<p class=\"note\">No cycles in the evaluation.</p>\n";
    return;
  }
  bool any_missing = false;
  for (const auto& c : cycles) any_missing |= !array(c, "missing").empty();
  page.html += "<table class=\"cycles\">\n<thead><tr>" + th("cycle", true) + th("phase") +
               th("t (h:mm)", true);
  for (const auto& [id, unit] : quantities) {
    const auto [label, u] = labelAndUnit(id, unit);
    page.html += th(columnTitle(label, u, " \u00b1 U"), true);
  }
  if (any_missing) page.html += th("missing");
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& c : cycles) {
    page.html += "<tr>" + td(whole(number(c, "cycle")), true) + td(phaseText(text(c, "phase"))) +
                 td(cycleHours(c, t0_s), true);
    for (const auto& [id, unit] : quantities) {
      const json* v = findValue(c, id);
      page.html += v ? tdValueU(number(*v, "value"), number(*v, "U")) : td(kDash, true);
    }
    if (any_missing) {
      const std::string m = listText(array(c, "missing"));
      page.html += td(m.empty() ? kDash : m);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";

  std::vector<const Also*> also;
  for (const auto& a : kAlso)
    for (const auto& c : cycles)
      if (number(object(c, "also"), a.key)) {
        also.push_back(&a);
        break;
      }
  if (also.empty()) return;
  page.html += "<h3>" + esc(r.label) +
               ": E_TTP by Eq. 7.9 beside it (the dial-gauge form, one-sided: exactly half of Eq. 7.3 from "
               "the same facets, so U is half of E_TTP's)</h3>\n"
               "<table class=\"also\">\n<thead><tr>" +
               th("cycle", true) + th("t (h:mm)", true);
  for (const auto* a : also) page.html += th(a->title, true);
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& c : cycles) {
    page.html += "<tr>" + td(whole(number(c, "cycle")), true) + td(cycleHours(c, t0_s), true);
    for (const auto* a : also) {
      const auto v = number(object(c, "also"), a->key);
      page.html += v ? tdValueU(v, eq79U(c, *v)) : td(kDash, true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

namespace {

std::string periodHours(const std::optional<double>& period_h) {
  return period_h ? hoursMinutes(*period_h * 3600.0) : kDash;
}

std::string periodText(const json& row) {
  std::string s = periodHours(number(row, "period_h"));
  const json& cyc = array(row, "cycles");
  if (cyc.size() == 2 && number(&cyc[0]) && number(&cyc[1]))
    s += " (cycles " + whole(number(&cyc[0])) + "\u2013" + whole(number(&cyc[1])) + ")";
  return s;
}

}  // namespace

// Table 7.2's layout: one row per period, one column (group) per quantity.
void spanTable(Page& page, const Route& r) {
  const json& spans = array(*r.eval, "spans");
  page.html += "<h3>" + esc(r.label) + ": spans of the changes (Table 7.2 layout)</h3>\n";
  if (spans.empty()) {
    page.html += "<p class=\"note\">No spans in the evaluation.</p>\n";
    return;
  }
  std::vector<std::string> ids;
  for (const auto& q : kQuantities)
    for (const auto& s : spans)
      for (const auto& v : array(s, "values"))
        if (text(v, "quantity") == q.id && std::find(ids.begin(), ids.end(), q.id) == ids.end()) ids.push_back(q.id);
  for (const auto& s : spans)
    for (const auto& v : array(s, "values"))
      if (const std::string id = text(v, "quantity"); !id.empty() && std::find(ids.begin(), ids.end(), id) == ids.end())
        ids.push_back(id);
  page.html += "<table class=\"spans\">\n<thead><tr>" + th("period (h:mm)");
  for (const auto& id : ids) {
    const auto [label, unit] = labelAndUnit(id, "");
    page.html += th(columnTitle(label, unit, " span \u00b1 U"), true);
  }
  page.html += "</tr></thead>\n<tbody>\n";
  for (const auto& s : spans) {
    page.html += "<tr>" + th(periodText(s));
    for (const auto& id : ids) {
      const json* found = nullptr;
      for (const auto& v : array(s, "values"))
        if (text(v, "quantity") == id) found = &v;
      page.html += found ? tdValueU(number(*found, "span"), number(*found, "U")) : td(kDash, true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

void comparisonTable(Page& page, const Route& r) {
  const json* cmp = field(*r.eval, "comparison");
  if (cmp == nullptr || !cmp->is_object()) return;
  const json& rows = array(*cmp, "rows");
  const std::string against = text(*cmp, "against");
  page.html += "<h3>" + esc(r.label) + ": spans compared (Table 7.2 layout)</h3>\n<p class=\"note\">this: " +
               esc(r.file.empty() ? r.label : r.file) + "; against: " + esc(against.empty() ? kDash : against) +
               "; reduction = (this \u2212 against) / this, this run taken as the uncompensated one (UC) and the other as "
               "the compensated one (C), as in seed 004 Table 7.2.</p>\n";
  if (rows.empty()) {
    page.html += "<p class=\"note\">No rows in the comparison.</p>\n";
    return;
  }
  std::vector<double> periods;
  std::vector<std::string> ids;
  for (const auto& q : kQuantities)
    for (const auto& row : rows)
      if (text(row, "quantity") == q.id && std::find(ids.begin(), ids.end(), q.id) == ids.end()) ids.push_back(q.id);
  for (const auto& row : rows) {
    if (const std::string id = text(row, "quantity"); !id.empty() && std::find(ids.begin(), ids.end(), id) == ids.end())
      ids.push_back(id);
    if (const auto p = number(row, "period_h"); p && std::find(periods.begin(), periods.end(), *p) == periods.end())
      periods.push_back(*p);
  }
  page.html += "<table class=\"comparison\">\n<thead><tr><th rowspan=\"2\">period (h:mm)</th>";
  for (const auto& id : ids) {
    const auto [label, unit] = labelAndUnit(id, "");
    page.html += "<th colspan=\"3\" class=\"group\">" + esc(columnTitle(label, unit)) + "</th>";
  }
  page.html += "</tr>\n<tr>";
  for (std::size_t i = 0; i < ids.size(); ++i)
    page.html += th("this", true) + th("against", true) + th("reduction (%)", true);
  page.html += "</tr></thead>\n<tbody>\n";
  for (const double p : periods) {
    page.html += "<tr>" + th(periodHours(p));
    for (const auto& id : ids) {
      const json* found = nullptr;
      for (const auto& row : rows)
        if (text(row, "quantity") == id && number(row, "period_h") == p) found = &row;
      if (found == nullptr) {
        page.html += td(kDash, true) + td(kDash, true) + td(kDash, true);
        continue;
      }
      page.html += td(sig(number(*found, "this"), 3), true) + td(sig(number(*found, "other"), 3), true) +
                   td(number(*found, "reduction_percent") ? fixed(*number(*found, "reduction_percent"), 1) : kDash, true);
    }
    page.html += "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

// Per quantity, the largest contribution (by |u|) in the last cycle that has the quantity.
void budgetTable(Page& page, const Route& r) {
  const auto quantities = routeQuantities(*r.eval);
  const json& cycles = array(*r.eval, "cycles");
  std::string rows;
  for (const auto& [id, unit_field] : quantities) {
    const json* cycle = nullptr;
    const json* value = nullptr;
    for (const auto& c : cycles)
      if (const json* v = findValue(c, id); v && number(*v, "value")) cycle = &c, value = v;
    if (value == nullptr) continue;
    const auto [label, unit] = labelAndUnit(id, unit_field);
    const json* largest = nullptr;
    for (const auto& k : array(*value, "contributions"))
      if (number(k, "u") && (largest == nullptr || std::abs(*number(k, "u")) > std::abs(*number(*largest, "u"))))
        largest = &k;
    rows += "<tr>" + th(columnTitle(label, unit)) + td(whole(number(*cycle, "cycle")), true) +
            tdValueU(number(*value, "value"), number(*value, "U")) + td(sig(number(*value, "u_c"), 2), true) +
            td(sig(number(*value, "nu_eff"), 3), true) + td(sig(number(*value, "k"), 3), true);
    if (largest == nullptr) {
      rows += td(kDash) + td(kDash) + td(kDash) + td(kDash, true) + td(kDash, true) + td(kDash) + "</tr>\n";
      continue;
    }
    const std::string input = text(*largest, "input");
    rows += td(input.empty() ? kDash : input) + td(text(*largest, "type").empty() ? kDash : text(*largest, "type")) +
            td(text(*largest, "distribution").empty() ? kDash : text(*largest, "distribution")) +
            td(withUnit(sig(number(*largest, "u"), 2), unit), true) + td(sig(number(*largest, "dof"), 3), true) +
            td(text(*largest, "basis").empty() ? kDash : readerSource(text(*largest, "basis"))) + "</tr>\n";
  }
  page.html += "<h3>" + esc(r.label) + ": largest budget contribution per quantity (last cycle that has it)</h3>\n";
  if (rows.empty()) {
    page.html += "<p class=\"note\">No budgets in the evaluation.</p>\n";
    return;
  }
  page.html += "<table class=\"budget\">\n<thead><tr>" + th("quantity") + th("cycle", true) + th("value \u00b1 U", true) +
               th("u_c", true) + th("\u03bd_eff", true) + th("k", true) + th("largest input") + th("type") +
               th("distribution") + th("u", true) + th("dof", true) + th("basis") + "</tr></thead>\n<tbody>\n" + rows +
               "</tbody>\n</table>\n";
}

void formulaTable(Page& page, const json& formulas, const std::string& heading) {
  page.html += "<h3>" + esc(heading) + "</h3>\n";
  if (formulas.empty()) {
    page.html += "<p class=\"note\">No formulas in the evaluation.</p>\n";
    return;
  }
  page.html += "<table class=\"formulas\">\n<thead><tr>" + th("output") + th("formula") + th("source") + th("features") +
               "</tr></thead>\n<tbody>\n";
  for (const auto& f : formulas) {
    const auto cellText = [&f](const char* k) {
      const std::string s = text(f, k);
      return s.empty() ? kDash : s;
    };
    // The thesis's section and equation for the known outputs; otherwise the evaluation's
    // source without our notes' paths and line numbers.
    const Quantity* q = findQuantity(text(f, "output"));
    const std::string source = q ? std::string(kThesis) + ", " + q->reference : readerSource(cellText("source"));
    page.html += "<tr>" + td(cellText("output")) + td(cellText("formula")) + td(source) +
                 td(cellText("features")) + "</tr>\n";
  }
  page.html += "</tbody>\n</table>\n";
}

void inputsTable(Page& page, const std::vector<Route>& routes, const RTest* r, const MachineInputs* in, double t0_s,
                 const std::vector<std::pair<std::string, RTestChannel>>& channels) {
  page.html += "<table class=\"meta\">\n";
  const auto row = [&page](const std::string& name, const std::string& value) {
    page.html += "<tr>" + th(name) + td(value.empty() ? kDash : value) + "</tr>\n";
  };
  for (const auto& rt : routes) {
    const json& in = object(*rt.eval, "input");
    const std::string prefix = routes.size() > 1 ? "route " + std::to_string(rt.index + 1) + " " : "";
    row(prefix + "evaluation", rt.file);
    std::string what = rt.label;
    const std::string file = text(in, "file"), format = text(in, "format"), by = text(in, "assigned_by");
    if (!file.empty()) what += ": " + file;
    std::string facts;
    if (!format.empty()) facts += "format " + format;
    if (const auto n = number(in, "points")) facts += (facts.empty() ? "" : ", ") + whole(*n) + " points";
    if (!by.empty()) facts += (facts.empty() ? "" : ", ") + std::string("assigned by ") + by;
    if (!facts.empty()) what += " (" + facts + ")";
    row(prefix + "measured", what);
    row(prefix + "manifest", text(*rt.eval, "manifest"));
    const json& scatter = object(*rt.eval, "point_scatter");
    if (number(scatter, "type_a_sigma_um") || number(scatter, "type_b_sigma_um"))
      row(prefix + "point scatter", "type A \u03c3 = " + withUnit(sig(number(scatter, "type_a_sigma_um"), 2), "\u00b5m") +
                                        " (\u03bd = " + whole(number(scatter, "type_a_dof")) + "), type B \u03c3 = " +
                                        withUnit(sig(number(scatter, "type_b_sigma_um"), 2), "\u00b5m") + "; used: " +
                                        (text(scatter, "used").empty() ? kDash : text(scatter, "used")));
    if (rt.index > 0) {
      const auto t = referenceTime(*rt.eval);
      if (t && std::abs(*t - t0_s) > 1.0)
        row(prefix + "reference cut", "at " + withUnit(sig(*t, 7), "s") + ", not at the first route's " +
                                          withUnit(sig(t0_s, 7), "s") + ": its points are drawn on the common clock");
    }
  }
  row("reference cut (time_s on the common clock)", withUnit(sig(t0_s, 7), "s"));
  if (r != nullptr) {
    std::string span;
    if (!r->time_s.empty()) {
      const auto [lo, hi] = std::minmax_element(r->time_s.begin(), r->time_s.end());
      span = ", " + hoursMinutes(*lo - t0_s) + " \u2013 " + hoursMinutes(*hi - t0_s) + " (h:mm)";
    }
    row("R-test", (r->file.empty() ? std::string("R-test error series") : r->file) + " (" +
                      std::to_string(r->table.rows.size()) + " cycles" + span + ")");
    std::string ref;
    for (const auto& [column, ch] : channels) {
      if (ch.rows.empty()) continue;
      const auto [label, unit] = rTestLabelAndUnit(column);
      ref += (ref.empty() ? "" : "; ") + label + ": " +
             (ch.re_referenced ? withUnit(sig(ch.offset, 3), unit) : std::string("not covered, as given"));
    }
    row("R-test value at the reference cut, subtracted", ref);
    row("Eq. 7.10 for the table", "\u03b1 = " + sig(r->alpha, 3) + " \u00b5m/(m\u00b7K), R = " + sig(r->radius_mm, 4) +
                                      " mm: \u0394T = E_R0T / (\u03b1 R)");
  }
  if (in != nullptr) {
    std::string cols;
    for (const auto& s : in->temperatures) cols += (cols.empty() ? "" : ", ") + s.column + " (\u00b0C)";
    if (in->c_rpm) cols += (cols.empty() ? "" : ", ") + std::string("c_rpm (rpm)");
    row("machine inputs", (in->file.empty() ? std::string("logged inputs") : in->file) + ": " + cols);
  }
  page.html += "</table>\n";
}

bool hasPrintedForms(const std::vector<Route>& routes) {
  for (const auto& r : routes)
    for (const auto& c : array(*r.eval, "cycles"))
      for (const auto& p : kPrinted)
        if (number(object(c, "also"), p.key)) return true;
  return false;
}

// What is printed, why it cannot be the thermal error, and what the page uses instead. The
// printed value's size comes from the data: about -d_X1(t0), the facet's whole distance.
void printedFormsNote(Page& page, const std::vector<Route>& routes) {
  std::optional<double> example_um;
  for (const auto& r : routes)
    for (const auto& c : array(*r.eval, "cycles"))
      if (const auto v = number(object(c, "also"), "EX_printed_um"); v && !example_um && text(c, "phase") != "reference")
        example_um = v;
  page.html += "<section class=\"printed-forms\">\n<h3>Note: Eqs. 7.1 and 7.2 as printed</h3>\n<p>" +
               esc(std::string(kThesis)) +
               ", Sec. 7.2, prints Eq. 7.1 as</p>\n<pre>E_X(t_i) = [ d_X2(t_i) \u2212 d_X2(t_0) \u2212 d_X1(t_i) \u2212 "
               "d_X1(t_0) ] / 2</pre>\n<p>and Eq. 7.2 likewise for Y. As printed, the reference distance d_X1(t_0) "
               "does not cancel: the result is about \u2212d_X1(t_0), the facet's whole distance to the piece's origin"
               " (" +
               (example_um ? esc(withUnit(sig(*example_um / 1000.0, 4), "mm")) + " here"
                           : std::string("some \u221297.5 mm on the shipped piece")) +
               "), not a thermal change. This report uses the form in which each facet's distance is referred to its "
               "own reference cut, the one the thesis's dial-gauge form (Eq. 7.7, Sec. 7.2) computes:</p>\n"
               "<pre>E_X(t_i) = [ (d_X2(t_i) \u2212 d_X2(t_0)) \u2212 (d_X1(t_i) \u2212 d_X1(t_0)) ] / 2</pre>\n"
               "<p class=\"note\">The printed forms' values are listed in the appendix, for comparison only.</p>\n"
               "</section>\n";
}

void printedFormsAppendix(Page& page, const std::vector<Route>& routes, double t0_s) {
  page.html += "<section class=\"appendix\" id=\"appendix-printed\">\n<h2>Appendix: Eqs. 7.1 and 7.2 as printed</h2>\n"
               "<p class=\"note\">Not thermal errors: the printed forms keep the reference distance d_X1(t_0) "
               "(d_Y1(t_0)); see the note under Formulas. No U: they are shown only to make the misprint visible.</p>\n";
  for (const auto& r : routes) {
    const json& cycles = array(*r.eval, "cycles");
    std::vector<const Also*> cols;
    for (const auto& p : kPrinted)
      for (const auto& c : cycles)
        if (number(object(c, "also"), p.key)) {
          cols.push_back(&p);
          break;
        }
    if (cols.empty()) continue;
    std::string table = "<table class=\"printed\">\n<thead><tr>" + th("cycle", true) + th("t (h:mm)", true);
    for (const auto* p : cols) table += th(p->title, true);
    table += "</tr></thead>\n<tbody>\n";
    for (const auto& c : cycles) {
      table += "<tr>" + td(whole(number(c, "cycle")), true) + td(cycleHours(c, t0_s), true);
      for (const auto* p : cols) table += td(twoDecimals(number(object(c, "also"), p->key)), true);
      table += "</tr>\n";
    }
    table += "</tbody>\n</table>\n";
    page.html += "<h3>" + esc(r.label) + "</h3>\n" + tableWrap(table);
  }
  page.html += "</section>\n";
}

}  // namespace probeloop::report::ttp_detail
