// Table 7.2 of seed 004 (contract in thermal_test_piece.hpp, docs/thermal-test-piece-evaluation.md):
// the spans of E_X ... E_TTP per period (first hour, half, all) and their comparison with another
// evaluation.json of the same kind (this run = UC, the other = C).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "evaluate/thermal_test_piece.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate {

// --- spans (Table 7.2) -------------------------------------------------------------------

std::vector<TtpSpan> ttpSpans(const std::vector<TtpCycleResult>& cycles) {
  std::vector<TtpSpan> out;
  if (cycles.empty()) return out;
  int last = 0;
  for (const auto& c : cycles) last = std::max(last, c.cycle);
  std::vector<int> ends;
  for (int l : {1, last / 2, last})
    if (l >= 1 && (ends.empty() || l > ends.back())) ends.push_back(l);
  const TtpCycleResult* c0 = nullptr;
  for (const auto& c : cycles)
    if (c.cycle == 0) c0 = &c;
  for (int l : ends) {
    TtpSpan s;
    s.first = 0;
    s.last = l;
    double t_last = 0;
    for (const auto& c : cycles)
      if (c.cycle == l) t_last = c.time_s;
    s.period_h = c0 ? (t_last - c0->time_s) / 3600 : 0;
    for (const char* q : {"EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"}) {
      // Every cycle 0..l must have the value: a span over the cycles that happen to be there
      // would read as the period's span.
      std::map<int, const uncertainty::Budget*> at;
      for (const auto& c : cycles)
        if (c.cycle <= l && c.value(q)) at[c.cycle] = c.value(q);
      bool measured = false;  // a quantity this route gives at all in the period
      for (const auto& [c, b] : at) measured = measured || c > 0;
      if (!measured) continue;
      TtpSpanValue v;
      v.quantity = q;
      for (int c = 0; c <= l; ++c)
        if (!at.count(c)) v.missing_cycles.push_back(c);
      if (v.complete()) {
        const uncertainty::Budget* hi = nullptr;
        const uncertainty::Budget* lo = nullptr;
        for (const auto& [c, b] : at) {
          if (!hi || b->value > hi->value) hi = b;
          if (!lo || b->value < lo->value) lo = b;
        }
        // The two extremes' U combined as if independent: conservative (both share the reference
        // cut, which cancels in their difference) and blind to another cycle being the true extreme.
        v.span = hi->value - lo->value;
        v.U = std::sqrt(hi->U * hi->U + lo->U * lo->U);
      }
      s.values.push_back(v);
    }
    out.push_back(s);
  }
  return out;
}

std::string cycleRanges(const std::vector<int>& c) {
  std::string out;
  for (std::size_t i = 0; i < c.size();) {
    std::size_t j = i;
    while (j + 1 < c.size() && c[j + 1] == c[j] + 1) ++j;
    out += (out.empty() ? "" : ", ") + std::to_string(c[i]) + (j > i ? "-" + std::to_string(c[j]) : "");
    i = j + 1;
  }
  return out;
}

TtpComparison compareSpans(const TtpEvaluation& e, const std::string& other) {
  using nlohmann::json;
  json j;
  try {
    j = json::parse(readFile(other));
  } catch (const json::parse_error& x) {
    throw InputError(other, 0, std::string("not valid JSON: ") + x.what());
  }
  TtpComparison c;
  c.against = other;
  c.this_route = ttpRouteName(e.route);
  try {
    if (j.value("format", "") != "probeloop-evaluation" || j.value("kind", "") != "thermal_test_piece")
      throw InputError(other, 0,
                       "not a thermal-test-piece evaluation.json (format probeloop-evaluation, kind thermal_test_piece; found kind '" +
                           j.value("kind", "") + "')");
    c.other_route = j.at("input").at("route").get<std::string>();
    // The same quantity on both sides: the formula of each compared output must be this run's.
    auto formulaOf = [](const std::vector<parts::EvaluationRule>& rules, const std::string& q) -> const parts::EvaluationRule* {
      for (const auto& r : rules)
        if (r.output == q) return &r;
      return nullptr;
    };
    auto otherFormula = [&](const std::string& q) -> std::string {
      for (const auto& f : j.at("formulas"))
        if (f.at("output").get<std::string>() == q) return f.at("formula").get<std::string>();
      return "";
    };
    auto sameQuantity = [&](const std::string& q) {
      const auto* mine = formulaOf(e.formulas, q);
      const std::string theirs = otherFormula(q);
      if (!mine || theirs != mine->formula)
        throw InputError(other, 0,
                         q + " is not the same quantity in both evaluations: this run (route " + c.this_route + ") computes '" +
                             (mine ? mine->formula : std::string("(no formula)")) + "', " + other + " (route " + c.other_route +
                             ") '" + (theirs.empty() ? std::string("(no formula)") : theirs) +
                             "'; re-evaluate it with this probeloop so that both use the same formulas");
    };
    for (const auto& s : e.spans) {
      const json* match = nullptr;
      for (const auto& o : j.at("spans"))
        if (o.at("cycles").at(0).get<int>() == s.first && o.at("cycles").at(1).get<int>() == s.last) match = &o;
      if (!match) continue;
      const std::string period = "cycles " + std::to_string(s.first) + "-" + std::to_string(s.last);
      for (const auto& v : s.values)
        for (const auto& ov : match->at("values")) {
          if (ov.at("quantity").get<std::string>() != v.quantity) continue;
          sameQuantity(v.quantity);
          const auto other_missing = ov.at("missing_cycles").get<std::vector<int>>();
          if (!v.complete() || !other_missing.empty()) {
            c.left_out.push_back(period + " " + v.quantity + ": incomplete in " +
                                 (!v.complete() ? "this run (cycles " + cycleRanges(v.missing_cycles) + " missing)" : std::string()) +
                                 (!v.complete() && !other_missing.empty() ? " and in " : "") +
                                 (!other_missing.empty() ? other + " (cycles " + cycleRanges(other_missing) + " missing)" : std::string()));
            continue;
          }
          TtpComparisonRow r;
          r.period_h = s.period_h;
          r.quantity = v.quantity;
          r.this_span = v.span;
          r.other_span = ov.at("span").get<double>();
          if (std::fabs(v.span) > 0) r.reduction_percent = parts::spanReductionPercent(v.span, r.other_span);  // Table 7.2
          c.rows.push_back(r);
        }
    }
  } catch (const json::exception& x) {
    throw InputError(other, 0, std::string("input.route, spans or formulas missing or of the wrong type: ") + x.what());
  }
  if (c.rows.empty()) {
    std::string why;
    for (const auto& l : c.left_out) why += "; " + l;
    throw InputError(other, 0,
                     "no complete span of this evaluation (cycles 0-1, 0-half, 0-last) has a complete span of the same cycles in the "
                     "other: nothing to compare" + why);
  }
  return c;
}

}  // namespace probeloop::evaluate
