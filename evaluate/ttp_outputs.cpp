// Writers of the thermal-test-piece evaluation (formats: docs/thermal-test-piece-evaluation.md §7).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/csv.hpp"
#include "evaluate/budget_json.hpp"
#include "evaluate/thermal_test_piece.hpp"

namespace probeloop::evaluate {

using nlohmann::ordered_json;

namespace {

ordered_json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
ordered_json opt(const std::optional<double>& v) { return v ? ordered_json(*v) : ordered_json(); }

std::string routeWords(const TtpEvaluation& e) {
  switch (e.route) {
    case TtpRoute::Cmm: return e.stated ? "the features a CMM states (" + e.format + ")" : "CMM export";
    case TtpRoute::OnMachine: return "on-machine probing (" + e.format + ")";
    case TtpRoute::Gauge: return "dial gauge on the machine (seed 004 Eqs. 7.7-7.9)";
  }
  return "";
}

std::vector<std::string> columns(const TtpEvaluation& e) {
  if (e.route == TtpRoute::Gauge) return {"EX_um", "EY_um", "ETTP_um"};
  return {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"};
}

std::string pm(const uncertainty::Budget& b, int digits = 3) {
  return formatNumber(b.value, digits) + " +- " + formatNumber(b.U, digits);
}

std::string fixed(double v, int width, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%*.*f", width, decimals, v);
  std::string s(buf);
  // No negative zero.
  const auto minus = s.find('-');
  if (minus != std::string::npos && s.find_first_of("123456789") == std::string::npos) s[minus] = ' ';
  return s;
}

std::string pad(const std::string& s, std::size_t width, bool left = false) {
  if (s.size() >= width) return s;
  return left ? s + std::string(width - s.size(), ' ') : std::string(width - s.size(), ' ') + s;
}

}  // namespace

std::string ttpErrorsCsv(const TtpEvaluation& e) {
  std::ostringstream o;
  const auto cols = columns(e);
  o << "# probeloop thermal test piece errors (seed 004 Ch. 7), route " << ttpRouteName(e.route) << ": " << routeWords(e)
    << ", input " << e.input_file << "; relative to the reference cut (cycle 0); U = expanded uncertainty (k = "
    << formatNumber(e.coverage_k) << ")\n";
  if (e.route == TtpRoute::Gauge)
    o << "# E_X, E_Y by seed 004 Eqs. 7.7/7.8; E_TTP: Eq. 7.3 (diametral), (g_X1 + g_X2 + g_Y1 + g_Y2) / 2 = twice Eq. 7.9, as on "
         "the other routes; evaluation.json has Eq. 7.9 and Eq. 7.10; E_Z and E_B are not measured by the gauge\n";
  else
    o << "# E_X, E_Y: Eqs. 7.1/7.2 with the sign typo corrected; E_TTP: Eq. 7.3 (diametral); evaluation.json has the printed forms, "
         "Eq. 7.9 and Eq. 7.10\n";
  std::vector<const TtpCycleResult*> rows;
  for (const auto& c : e.cycles) {
    bool all = true;
    for (const auto& q : cols)
      if (!c.value(q)) all = false;
    if (all) {
      rows.push_back(&c);
    } else {
      o << "# cycle " << c.cycle << " omitted:";
      for (const auto& m : c.missing) {
        // Only the reasons that concern this file's columns (the gauge never has E_Z, E_B).
        const std::string head = m.substr(0, std::min(m.find(':'), m.find(" not evaluated")));
        bool concerns = false;
        for (const auto& q : cols) concerns = concerns || head.find(q) != std::string::npos;
        if (concerns) o << " " << m << ";";
      }
      o << "\n";
    }
  }
  o << "time_s,cycle";
  for (const auto& q : cols) o << "," << q;
  for (const auto& q : cols) o << ",U_" << q;
  o << "\n";
  for (const auto* c : rows) {
    o << formatNumber(c->time_s, 3) << "," << c->cycle;
    for (const auto& q : cols) o << "," << formatNumber(c->value(q)->value, 4);
    for (const auto& q : cols) o << "," << formatNumber(c->value(q)->U, 4);
    o << "\n";
  }
  return o.str();
}

std::string ttpEvaluationJson(const TtpEvaluation& e) {
  ordered_json j;
  j["format"] = "probeloop-evaluation";
  j["version"] = 1;
  j["kind"] = "thermal_test_piece";
  j["manifest"] = e.manifest_file;
  j["input"] = {{"file", e.input_file},
                {"route", ttpRouteName(e.route)},
                {"format", e.format},
                {"points", e.points},
                {"assigned_by", e.assigned_by}};
  if (e.alignment) {
    const auto& a = *e.alignment;
    ordered_json d = ordered_json::object();
    for (const auto& x : a.datums) d[x.id] = {{"points", x.points}, {"form_um", x.form_um}};
    j["alignment"] = {{"origin_mm", vec(a.frame.origin_mm)},
                      {"x_axis", vec(a.frame.R.row(0).transpose())},
                      {"y_axis", vec(a.frame.R.row(1).transpose())},
                      {"z_axis", vec(a.frame.R.row(2).transpose())},
                      {"file_to_part_rotation_urad", vec(a.rotation_urad)},
                      {"file_to_part_translation_um", vec(a.translation_um)},
                      {"datums", d}};
  } else {
    j["alignment"] = nullptr;
  }
  j["point_scatter"] = {{"type_b_sigma_um", e.scatter.type_b_sigma_mm * 1e3},
                        {"type_a_sigma_um", e.scatter.type_a_sigma_mm * 1e3},
                        {"type_a_dof", e.scatter.type_a_dof},
                        {"used", e.scatter.type_a_used ? "type A" : "type B"}};
  if (e.stated) {
    ordered_json st = ordered_json::array();
    for (const auto& f : e.stated->features)
      st.push_back({{"id", f.id},
                    {"file_id", f.file_id},
                    {"line", f.line},
                    {"matched_by", f.matched_by},
                    {"n_points_stated", f.n_stated},
                    {"n_points_planned", f.n_planned},
                    {"form_um", opt(f.form_um)},
                    {"point_sigma_um", f.sigma_um},
                    {"point_sigma_from", f.sigma_from}});
    j["stated_features"] = {{"features", st},
                            {"unmatched", e.stated->unmatched},
                            {"rows_of_other_kinds_not_used", e.stated->other_kinds},
                            {"points_placed", e.stated->points_placed},
                            {"notes", e.notes}};
  }
  j["features"] = ordered_json::array();
  for (const auto& f : e.features)
    j["features"].push_back({{"id", f.id},
                             {"group", f.group},
                             {"index", f.index},
                             {"cycle", f.cycle},
                             {"time_s", f.time_s},
                             {"points", f.points},
                             {"rms_um", f.rms_um},
                             {"form_mz_um", f.form_mz_um},
                             {"normal", vec(f.normal)},
                             {"d_mm", opt(f.d_mm)},
                             {"depth_mm", opt(f.depth_mm)},
                             {"beta_urad", opt(f.beta_urad)},
                             {"u_d_um", f.u_d_um}});
  j["cycles"] = ordered_json::array();
  for (const auto& c : e.cycles) {
    ordered_json jc;
    jc["cycle"] = c.cycle;
    jc["phase"] = c.phase;
    jc["time_s"] = c.time_s;
    jc["values"] = ordered_json::array();
    for (const auto& b : c.values) jc["values"].push_back(budgetJson(b));
    jc["also"] = {{"EX_printed_um", opt(c.EX_printed_um)}, {"EY_printed_um", opt(c.EY_printed_um)}, {"ETTP_7_9_um", opt(c.ETTP_7_9_um)}};
    jc["missing"] = c.missing;
    j["cycles"].push_back(jc);
  }
  j["spans"] = ordered_json::array();
  for (const auto& s : e.spans) {
    ordered_json js{{"period_h", s.period_h}, {"cycles", {s.first, s.last}}, {"values", ordered_json::array()}};
    for (const auto& v : s.values)
      js["values"].push_back({{"quantity", v.quantity},
                              {"complete", v.complete()},
                              {"span", v.complete() ? ordered_json(v.span) : ordered_json()},
                              {"U", v.complete() ? ordered_json(v.U) : ordered_json()},
                              {"missing_cycles", v.missing_cycles}});
    j["spans"].push_back(js);
  }
  if (e.comparison) {
    ordered_json jc{{"against", e.comparison->against},
                    {"this_route", e.comparison->this_route},
                    {"other_route", e.comparison->other_route},
                    {"rows", ordered_json::array()},
                    {"left_out", e.comparison->left_out}};
    for (const auto& r : e.comparison->rows)
      jc["rows"].push_back({{"period_h", r.period_h},
                            {"quantity", r.quantity},
                            {"this", r.this_span},
                            {"other", r.other_span},
                            {"reduction_percent", opt(r.reduction_percent)}});
    j["comparison"] = jc;
  } else {
    j["comparison"] = nullptr;
  }
  j["formulas"] = ordered_json::array();
  for (const auto& f : e.formulas)
    j["formulas"].push_back({{"output", f.output}, {"formula", f.formula}, {"source", f.source}, {"features", f.features}});
  return j.dump(1) + "\n";
}

std::string ttpReport(const TtpEvaluation& e) {
  std::ostringstream o;
  const auto cols = columns(e);
  o << "# Thermal test piece (seed 004 Ch. 7): errors and uncertainty budgets\n\n";
  o << "Manifest `" << e.manifest_file << "`, input `" << e.input_file << "`: " << routeWords(e) << ", ";
  if (e.stated)
    o << e.stated->features.size() << " features, matched by " << e.assigned_by << " (no points: the plan's " << e.stated->points_placed
      << " placed on them)";
  else
    o << e.points << (e.route == TtpRoute::Gauge ? " readings" : " points") << ", assigned to features by " << e.assigned_by;
  o << ". Every value is relative to the reference cut (cycle 0); U is the expanded uncertainty (k = " << formatNumber(e.coverage_k)
    << "). Definitions, formulas and budget terms: docs/thermal-test-piece-evaluation.md.\n\n";
  for (const auto& n : e.notes) o << "- " << n << "\n";
  if (!e.notes.empty()) o << "\n";
  if (e.alignment) {
    const auto& a = *e.alignment;
    o << "## Datum frame (seed 004 L2055)\n\n"
         "Top plane (TOP) -> Z axis and Z origin; the flanks of the large notch (FLANK_P, FLANK_N) -> X direction; the "
         "least-squares circle of the datum band (CYL) -> X/Y origin.\n\n";
    o << "| | x | y | z |\n|---|---|---|---|\n";
    o << "| origin in the file frame (mm) | " << formatNumber(a.frame.origin_mm.x(), 4) << " | " << formatNumber(a.frame.origin_mm.y(), 4)
      << " | " << formatNumber(a.frame.origin_mm.z(), 4) << " |\n";
    const char* axn[3] = {"x axis", "y axis", "z axis"};
    for (int r = 0; r < 3; ++r)
      o << "| " << axn[r] << " | " << formatNumber(a.frame.R(r, 0), 9) << " | " << formatNumber(a.frame.R(r, 1), 9) << " | "
        << formatNumber(a.frame.R(r, 2), 9) << " |\n";
    o << "| file -> part rotation vector (urad) | " << formatNumber(a.rotation_urad.x(), 3) << " | " << formatNumber(a.rotation_urad.y(), 3)
      << " | " << formatNumber(a.rotation_urad.z(), 3) << " |\n";
    o << "| file -> part translation (um) | " << formatNumber(a.translation_um.x(), 3) << " | " << formatNumber(a.translation_um.y(), 3)
      << " | " << formatNumber(a.translation_um.z(), 3) << " |\n\n";
    o << "| datum | points | form (um) |\n|---|---|---|\n";
    for (const auto& d : a.datums)
      o << "| " << d.id << " | " << d.points << " | " << (std::isfinite(d.form_um) ? formatNumber(d.form_um, 3) : "-") << " |\n";
    o << "\n";
  }
  if (e.stated) {
    o << "## Stated features\n\nThe file's features as matched to the plan's, their stated point count and form, and the scatter "
         "per placed point the budget used (docs/thermal-test-piece-evaluation.md §10).\n\n"
         "| feature | file's id | line | matched by | n stated | n placed | form (um) | sigma per placed point (um) | from |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& f : e.stated->features)
      o << "| " << f.id << " | " << f.file_id << " | " << f.line << " | " << f.matched_by << " | "
        << (f.n_stated ? std::to_string(f.n_stated) : "not stated") << " | " << f.n_planned << " | "
        << (f.form_um ? formatNumber(*f.form_um, 3) : "not stated") << " | " << formatNumber(f.sigma_um, 3) << " | " << f.sigma_from << " |\n";
    for (const auto& u : e.stated->unmatched) o << "\nNot used (fits no feature of the plan): " << u << "\n";
    o << "\n";
  }
  if (e.route != TtpRoute::Gauge) {
    if (!e.stated)
      o << "Point scatter: specification sigma = " << formatNumber(e.scatter.type_b_sigma_mm * 1e3, 4)
      << " um (RMS over the measurement points), pooled plane-fit residual s = " << formatNumber(e.scatter.type_a_sigma_mm * 1e3, 4)
      << " um (nu = " << formatNumber(e.scatter.type_a_dof) << "); the budgets use the " << (e.scatter.type_a_used ? "type A s" : "specification")
      << ".\n\n";
    o << "## Features\n\n| feature | cycle | points | rms (um) | " << (e.stated ? "form as stated (um)" : "form MZ (um)") << " | d (mm) | depth (mm) | beta (urad) | u point scatter (um) |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& f : e.features)
      o << "| " << f.id << " | " << f.cycle << " | " << f.points << " | " << (e.stated ? "-" : formatNumber(f.rms_um, 3)) << " | "
        << (std::isfinite(f.form_mz_um) ? formatNumber(f.form_mz_um, 3) : "-")
        << " | " << (f.d_mm ? formatNumber(*f.d_mm, 5) : "") << " | " << (f.depth_mm ? formatNumber(*f.depth_mm, 5) : "") << " | "
        << (f.beta_urad ? formatNumber(*f.beta_urad, 2) : "") << " | " << formatNumber(f.u_d_um, 3) << " |\n";
    o << "\n";
  }
  o << "## Errors per cutting cycle (value +- U)\n\n| cycle | phase | time (h) |";
  for (const auto& q : cols) o << " " << q << " |";
  o << " dT_K (Eq. 7.10) |\n|---|---|---|";
  for (std::size_t i = 0; i <= cols.size(); ++i) o << "---|";
  o << "\n";
  for (const auto& c : e.cycles) {
    o << "| " << c.cycle << " | " << c.phase << " | " << formatNumber(c.time_s / 3600, 3) << " |";
    for (const auto& q : cols) o << " " << (c.value(q) ? pm(*c.value(q)) : std::string("-")) << " |";
    o << " " << (c.value("dT_K") ? pm(*c.value("dT_K")) : std::string("-")) << " |\n";
  }
  bool any_missing = false;
  for (const auto& c : e.cycles)
    for (const auto& m : c.missing) {
      if (!any_missing) o << "\nNot evaluated:\n\n";
      any_missing = true;
      o << "- cycle " << c.cycle << ": " << m << "\n";
    }
  if (e.route == TtpRoute::Gauge) {
    o << "\n## The two E_TTP\n\n"
         "With g = d(t_i) - d(t_0) per facet, Eq. 7.3 averages the changes of the two diameters, (g_X1 + g_X2 + g_Y1 + g_Y2) / 2, "
         "Eq. 7.9 the four one-sided changes (÷ 4): ETTP_um is Eq. 7.3, as on the CMM and on-machine routes, and Eq. 7.10 uses "
         "Eq. 7.9: dT = -E_TTP,7.9 / (alpha R) (docs/thermal-test-piece.md §4).\n\n"
         "| cycle | ETTP_um (Eq. 7.3) | ETTP_7_9_um (Eq. 7.9) | dT_K (Eq. 7.10) |\n|---|---|---|---|\n";
    auto val = [](const uncertainty::Budget* b) { return b ? formatNumber(b->value, 3) : std::string("-"); };
    for (const auto& c : e.cycles) {
      if (c.cycle == 0) continue;
      o << "| " << c.cycle << " | " << val(c.value("ETTP_um")) << " | " << (c.ETTP_7_9_um ? formatNumber(*c.ETTP_7_9_um, 3) : "-")
        << " | " << val(c.value("dT_K")) << " |\n";
    }
  } else {
    o << "\n## Printed forms and the two E_TTP\n\n"
         "Eqs. 7.1 and 7.2 are printed with \"- d_X1(t_0)\" (\"- d_Y1(t_0)\"): the reference distance would not cancel "
         "(notes/seed004.md §11 item 10). E_X and E_Y above use \"+\", as the manual form Eq. 7.7 computes; the printed "
         "forms are listed here for comparison. Eq. 7.3 averages the changes of the two diameters l = d_1 + d_2 (÷ 2), "
         "Eq. 7.9 the four one-sided changes (÷ 4): for the same growth Eq. 7.3 reads twice Eq. 7.9 (notes §11 item 11). "
         "Eq. 7.10 is a radius law, so dT uses the radial form: dT = -E_TTP,7.9 / (alpha R) (a piece cut warm is smaller at "
         "20 °C, docs/thermal-test-piece.md §4).\n\n"
         "| cycle | EX_um (corrected) | EX_printed_um | EY_um (corrected) | EY_printed_um | ETTP_um (Eq. 7.3) | ETTP_7_9_um (Eq. 7.9) | dT_K (Eq. 7.10) |\n"
         "|---|---|---|---|---|---|---|---|\n";
    auto val = [](const uncertainty::Budget* b) { return b ? formatNumber(b->value, 3) : std::string("-"); };
    auto optv = [](const std::optional<double>& v) { return v ? formatNumber(*v, 3) : std::string("-"); };
    for (const auto& c : e.cycles) {
      if (c.cycle == 0) continue;
      o << "| " << c.cycle << " | " << val(c.value("EX_um")) << " | " << optv(c.EX_printed_um) << " | " << val(c.value("EY_um")) << " | "
        << optv(c.EY_printed_um) << " | " << val(c.value("ETTP_um")) << " | " << optv(c.ETTP_7_9_um) << " | " << val(c.value("dT_K"))
        << " |\n";
    }
  }
  // Spans in Table 7.2's layout.
  if (!e.spans.empty()) {
    o << "\n## Spans of the changes (seed 004 Table 7.2)\n\n"
         "Span = max - min of E over cycles 0..n, E(t_0) = 0 included; a span needs E at every cycle of its period, "
         "otherwise it is incomplete (no value; left out of any comparison). U of a span = root-sum-square of the U of the two "
         "extreme values: it ignores that both share the reference cut (which cancels in their difference: conservative) "
         "and that another cycle could be the true extreme.\n\n| period (h) | cycles |";
    std::vector<std::string> qs;
    for (const auto& v : e.spans.front().values) qs.push_back(v.quantity);
    for (const auto& q : qs) o << " " << q << " span +- U |";
    o << "\n|---|---|";
    for (std::size_t i = 0; i < qs.size(); ++i) o << "---|";
    o << "\n";
    for (const auto& s : e.spans) {
      o << "| " << formatNumber(s.period_h, 2) << " | " << s.first << "-" << s.last << " |";
      for (const auto& q : qs) {
        std::string cell = "-";
        for (const auto& v : s.values)
          if (v.quantity == q)
            cell = v.complete() ? formatNumber(v.span, 2) + " +- " + formatNumber(v.U, 2)
                                : "incomplete (cycles " + cycleRanges(v.missing_cycles) + " missing)";
        o << " " << cell << " |";
      }
      o << "\n";
    }
  }
  if (e.comparison) {
    o << "\n## Comparison (Table 7.2 layout): this run (UC) against `" << e.comparison->against
      << "` (C)\n\nRoutes: this run " << e.comparison->this_route << ", the other " << e.comparison->other_route
      << " (the same formulas, checked). Reduction = (UC - C) / UC (parts::spanReductionPercent).\n\n"
         "| period (h) | quantity | UC span | C span | reduction (%) |\n|---|---|---|---|---|\n";
    for (const auto& r : e.comparison->rows)
      o << "| " << formatNumber(r.period_h, 2) << " | " << r.quantity << " | " << formatNumber(r.this_span, 2) << " | "
        << formatNumber(r.other_span, 2) << " | " << (r.reduction_percent ? formatNumber(*r.reduction_percent, 1) : "- (UC span 0)")
        << " |\n";
    if (!e.comparison->left_out.empty()) {
      o << "\nNot compared:\n\n";
      for (const auto& l : e.comparison->left_out) o << "- " << l << "\n";
    }
  }
  // Full budget of the last cycle.
  const TtpCycleResult* last = nullptr;
  for (const auto& c : e.cycles)
    if (c.cycle > 0 && !c.values.empty()) last = &c;
  if (last) {
    o << "\n## Budgets of cycle " << last->cycle << " (the last)\n";
    for (const auto& b : last->values) {
      o << "\n### " << b.quantity << " = " << formatNumber(b.value, 4) << " " << b.unit << ", U = " << formatNumber(b.U, 3) << " "
        << b.unit << " (u_c = " << formatNumber(b.u_c, 3) << ", nu_eff = "
        << (std::isfinite(b.nu_eff) ? formatNumber(b.nu_eff, 3) : std::string("inf")) << ", k = " << formatNumber(b.k, 3)
        << ")\n\n| input | type | distribution | u (" << b.unit << ") | share of u_c^2 | basis |\n|---|---|---|---|---|---|\n";
      for (const auto& c : b.contributions)
        o << "| " << c.input << " | " << c.type << " | " << c.distribution << " | " << formatNumber(c.u, 4) << " | "
          << formatNumber(b.u_c > 0 ? 100 * c.u * c.u / (b.u_c * b.u_c) : 0.0, 3) << " % | " << c.basis << " |\n";
    }
  }
  o << "\n## Formulas\n\n| output | formula | source | features |\n|---|---|---|---|\n";
  for (const auto& f : e.formulas) o << "| " << f.output << " | " << f.formula << " | " << f.source << " | " << f.features << " |\n";
  return o.str();
}

std::string ttpStdout(const TtpEvaluation& e, const std::string& errors_file, const std::string& json_file,
                      const std::string& report_file) {
  std::ostringstream o;
  const auto cols = columns(e);
  o << "Thermal test piece (seed 004 Ch. 7), " << routeWords(e) << ": " << e.input_file << ", ";
  if (e.stated)
    o << e.stated->features.size() << " features matched by " << e.assigned_by << " (no points: the plan's "
      << e.stated->points_placed << " points placed on them)";
  else
    o << e.points << (e.route == TtpRoute::Gauge ? " readings" : " points") << (e.route == TtpRoute::Gauge ? "" : " assigned by " + e.assigned_by);
  o << "\nErrors relative to the reference cut (cycle 0); U for k = " << formatNumber(e.coverage_k) << "\n";
  o << pad("cycle", 6) << " " << pad("phase", 10, true) << pad("time_h", 7);
  for (const auto& q : cols) o << " " << pad(q, 17);
  o << " " << pad("dT_K", 15) << "\n";
  for (const auto& c : e.cycles) {
    o << pad(std::to_string(c.cycle), 6) << " " << pad(c.phase, 10, true) << fixed(c.time_s / 3600, 7, 2);
    for (const auto& q : cols) {
      const auto* b = c.value(q);
      o << " " << (b ? fixed(b->value, 8, 3) + " +- " + fixed(b->U, 5, 3) : pad("-", 17));
    }
    const auto* t = c.value("dT_K");
    o << " " << (t ? fixed(t->value, 7, 3) + " +- " + fixed(t->U, 4, 2) : pad("-", 15)) << "\n";
  }
  {
    // Each reason once, with the cycles it applies to.
    std::vector<std::pair<std::string, std::string>> reasons;
    for (const auto& c : e.cycles)
      for (const auto& m : c.missing) {
        auto it = std::find_if(reasons.begin(), reasons.end(), [&](const auto& r) { return r.first == m; });
        if (it == reasons.end())
          reasons.push_back({m, std::to_string(c.cycle)});
        else
          it->second += ", " + std::to_string(c.cycle);
      }
    for (const auto& [m, cs] : reasons) o << (cs.find(',') == std::string::npos ? "Cycle " : "Cycles ") << cs << ": " << m << "\n";
  }
  for (const auto& n : e.notes) o << "Note: " << n << "\n";
  if (!e.spans.empty()) {
    o << "Spans (seed 004 Table 7.2):";
    for (const auto& s : e.spans) {
      o << " cycles " << s.first << "-" << s.last << " (" << formatNumber(s.period_h, 2) << " h):";
      for (const auto& v : s.values)
        if (v.quantity != "EB_urad")
          o << " " << v.quantity.substr(0, v.quantity.find('_')) << " "
            << (v.complete() ? formatNumber(v.span, 2) : "incomplete (cycles " + cycleRanges(v.missing_cycles) + " missing)");
      o << ";";
    }
    o << "\n";
  }
  if (e.comparison) {
    o << "Reductions against " << e.comparison->against << " (routes " << e.comparison->this_route << " / "
      << e.comparison->other_route << "):";
    for (const auto& r : e.comparison->rows)
      if (r.reduction_percent && r.quantity != "EB_urad")
        o << " " << r.quantity.substr(0, r.quantity.find('_')) << " " << formatNumber(r.period_h, 2) << " h "
          << formatNumber(*r.reduction_percent, 1) << " %;";
    o << "\n";
    for (const auto& l : e.comparison->left_out) o << "Not compared: " << l << "\n";
  }
  o << "Wrote " << errors_file << ", " << json_file << " (budgets) and " << report_file << " (report)\n";
  return o.str();
}

}  // namespace probeloop::evaluate
