// The thermal test piece's values per cutting cycle (contract in thermal_test_piece.hpp,
// docs/thermal-test-piece-evaluation.md): the manifest's cycles, phases and times, and E_X, E_Y,
// E_Z, E_B, E_TTP and the Eq. 7.10 temperature of each cycle against the reference cut by
// parts::ttpErrors (seed 004 Eqs. 7.1-7.5, 7.9, 7.10), each with its budget (ttp_budget.cpp).
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "evaluate/ttp_detail.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate::ttp {

std::map<int, std::string> phases(const parts::PlanManifest& m) {
  std::map<int, std::string> out;
  for (const auto& c : m.cut_cycles) out[c.cycle] = c.phase;
  return out;
}

// Cycle times: the mean planned cut time of the cycle's features.
std::map<int, double> cycleTimes(const parts::PlanManifest& m) {
  std::map<int, std::pair<double, int>> acc;
  for (const auto& f : m.features)
    if (f.cycle >= 0 && std::isfinite(f.cut_time_s)) acc[f.cycle].first += f.cut_time_s, ++acc[f.cycle].second;
  std::map<int, double> out;
  for (const auto& [c, a] : acc) out[c] = a.first / a.second;
  for (const auto& c : m.cut_cycles)
    if (!out.count(c.cycle)) out[c.cycle] = (c.start_s + c.end_s) / 2;
  return out;
}

std::map<int, CycleFeatures> cycleFeatures(const parts::PlanManifest& m) {
  std::map<int, CycleFeatures> out;
  for (const auto& f : m.features) {
    if (f.cycle < 0) continue;
    const auto& n = f.nominal;
    if (n.role == "z_path" || n.role == "facet") out[f.cycle].by_side[n.group] = &f;
  }
  return out;
}

// One line per cycle: the values left out and the features that are absent.
std::string missingMessage(const std::map<std::string, bool>& ok, const std::vector<std::string>& absent, int cycle,
                           const std::string& why) {
  const bool x = !ok.at("X1") || !ok.at("X2"), y = !ok.at("Y1") || !ok.at("Y2"), z = !ok.at("Z");
  std::string q;
  auto add = [&](const char* name) { q += (q.empty() ? "" : ", ") + std::string(name); };
  if (x) add("EX_um");
  if (y) add("EY_um");
  if (z) add("EZ_um"), add("EB_urad");
  if (x || y) add("ETTP_um"), add("dT_K");
  std::string ids;
  for (const auto& a : absent) ids += (ids.empty() ? "" : ", ") + a;
  return q + " not evaluated: " + ids + " (cycle " + std::to_string(cycle) + ") " + (absent.size() == 1 ? "has " : "have ") + why;
}

// The manifest's rules (parts::thermalTestPieceEvaluation), for the gauge route those of the
// values it gives.
std::vector<parts::EvaluationRule> formulas(const parts::PlanManifest& m, TtpRoute route) {
  if (route != TtpRoute::Gauge) return m.evaluation;
  std::vector<parts::EvaluationRule> out;
  for (const auto& r : m.evaluation)
    if (r.output == "EX_um" || r.output == "EY_um" || r.output == "ETTP_um" || r.output == "dT_K") out.push_back(r);
  return out;
}

std::vector<TtpCycleResult> cycleValues(const parts::PlanManifest& m, const std::string& file, const TtpOptions& opt,
                                        bool predicted, const std::map<int, double>& times,
                                        const std::map<std::string, PlaneModel>& planes, FeatureQuantities& fq,
                                        const BudgetContext& ctx) {
  std::vector<TtpCycleResult> cycles;
  auto& dq = fq.dq;
  auto& zq = fq.zq;
  auto& bq = fq.bq;
  const auto cf = cycleFeatures(m);
  const auto ph = phases(m);
  if (!cf.count(0)) throw InputError(m.file, 0, "the manifest lists no reference features (cycle 0)");
  const auto& ref = cf.at(0);
  auto have = [&](const parts::ManifestFeature* f) { return f && planes.count(f->nominal.id); };
  for (const auto& [side, f] : ref.by_side)
    if (!have(f))
      throw InputError(file, 0, "the reference feature " + f->nominal.id + " (cycle 0) has no points: a missing reference cut; every "
                                "value of its side is measured against it (manifest " + m.file + ")");
  for (const char* s : {"Z", "X1", "X2", "Y1", "Y2"})
    if (!ref.by_side.count(s)) throw InputError(m.file, 0, std::string("the manifest has no reference ") + s + " feature (cycle 0)");

  // Not a structured binding: lambdas below use feats, which clang before 16 cannot capture
  // (C++20 P1091; scripts/fuzz.sh builds with clang 14).
  for (const auto& entry : cf) {
    const auto& c = entry.first;
    const auto& feats = entry.second;
    TtpCycleResult cr = cycleResult(c, ph, times);
    if (c == 0) {
      for (int j = 0; j < 6; ++j) cr.values.push_back(zeroBudget(kQuantities[j], kUnits[j], opt.coverage_k));
      cr.ETTP_7_9_um = 0;  // the printed forms of Eqs. 7.1/7.2 are defined for i >= 1 only
      cycles.push_back(cr);
      continue;
    }
    std::map<std::string, bool> ok;
    std::vector<std::string> absent;
    for (const char* s : {"Z", "X1", "X2", "Y1", "Y2"}) {
      const auto it = feats.by_side.find(s);
      ok[s] = it != feats.by_side.end() && have(it->second);
      if (!ok[s]) absent.push_back(it != feats.by_side.end() ? it->second->nominal.id : std::string(s) + " (not in the manifest)");
    }
    if (!absent.empty()) cr.missing.push_back(missingMessage(ok, absent, c, "no points in " + file));
    auto id = [&](const std::map<std::string, const parts::ManifestFeature*>& b, const char* s) { return b.at(s)->nominal.id; };
    parts::TtpMeasures mi, m0;
    auto fill = [&](parts::TtpMeasures& mm, const CycleFeatures& cfs, bool all) {
      auto val = [&](std::map<std::string, FQ>& mq, const char* s) {
        return (all || ok[s]) ? mq[id(cfs.by_side, s)].value : 0.0;
      };
      mm.d_X1_mm = val(dq, "X1");
      mm.d_X2_mm = val(dq, "X2");
      mm.d_Y1_mm = val(dq, "Y1");
      mm.d_Y2_mm = val(dq, "Y2");
      mm.d_Z_mm = val(zq, "Z");
      mm.beta_urad = val(bq, "Z");
    };
    fill(mi, feats, false);
    fill(m0, ref, true);
    const auto te = parts::ttpErrors(mi, m0);
    auto pair = [&](std::map<std::string, FQ>& mq, const char* s, double w) {
      return Pair{&mq[id(feats.by_side, s)], &mq[id(ref.by_side, s)], w};
    };
    std::vector<ValueSpec> specs;
    if (ok["X1"] && ok["X2"]) {
      specs.push_back({"EX_um", "um", te.EX_um, {pair(dq, "X2", 0.5), pair(dq, "X1", -0.5)}, 1e3, false});  // seed 004 Eq. 7.1
      cr.EX_printed_um = te.EX_printed_um;
    }
    if (ok["Y1"] && ok["Y2"]) {
      specs.push_back({"EY_um", "um", te.EY_um, {pair(dq, "Y2", 0.5), pair(dq, "Y1", -0.5)}, 1e3, false});  // seed 004 Eq. 7.2
      cr.EY_printed_um = te.EY_printed_um;
    }
    if (ok["Z"]) {
      specs.push_back({"EZ_um", "um", te.EZ_um, {pair(zq, "Z", 1.0)}, 1e3, false});        // seed 004 Eq. 7.4
      specs.push_back({"EB_urad", "urad", te.EB_urad, {pair(bq, "Z", 1.0)}, 1.0, true});   // seed 004 Eq. 7.5
    }
    const bool facets = ok["X1"] && ok["X2"] && ok["Y1"] && ok["Y2"];
    ValueSpec radial;
    if (facets) {
      specs.push_back({"ETTP_um", "um", te.ETTP_7_3_um,  // seed 004 Eq. 7.3
                       {pair(dq, "X1", 0.5), pair(dq, "X2", 0.5), pair(dq, "Y1", 0.5), pair(dq, "Y2", 0.5)}, 1e3, false});
      radial = {"ETTP_7_9_um", "um", te.ETTP_7_9_um,  // seed 004 Eq. 7.9
                {pair(dq, "X1", 0.25), pair(dq, "X2", 0.25), pair(dq, "Y1", 0.25), pair(dq, "Y2", 0.25)}, 1e3, false};
      cr.ETTP_7_9_um = te.ETTP_7_9_um;
    }
    for (const auto& s : specs)
      cr.values.push_back(opt.budgets ? valueBudget(s, ctx) : uncertainty::combine(s.quantity, s.unit, s.value, {}, opt.coverage_k));
    if (facets) {
      const auto rb = opt.budgets ? valueBudget(radial, ctx) : uncertainty::combine(radial.quantity, "um", radial.value, {}, opt.coverage_k);
      cr.values.push_back(temperatureBudget(m, rb, opt.coverage_k, predicted));
    }
    cycles.push_back(cr);
  }
  return cycles;
}

}  // namespace probeloop::evaluate::ttp
