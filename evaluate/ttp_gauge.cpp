// The thermal test piece by the dial gauge on the machine (seed 004 Eqs. 7.7-7.9, L2121; contract
// in thermal_test_piece.hpp, docs/thermal-test-piece-evaluation.md): E_X, E_Y, E_TTP and the
// Eq. 7.10 temperature per cycle from one reading per facet, with their budgets.
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "evaluate/ttp_detail.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate {

using ttp::alphaBasis;
using ttp::Contribution;
using ttp::cycleFeatures;
using ttp::cycleResult;
using ttp::cycleTimes;
using ttp::formulas;
using ttp::kInf;
using ttp::kQuantities;
using ttp::kSides;
using ttp::kUnits;
using ttp::missingMessage;
using ttp::num;
using ttp::phases;
using ttp::temperatureBudget;
using ttp::zeroBudget;

// --- dial gauge (seed 004 Eqs. 7.7-7.9) -------------------------------------------------------

TtpEvaluation evaluateThermalTestPieceGauge(const parts::PlanManifest& m, const TtpGaugeReadings& r, const TtpOptions& opt) {
  if (m.kind != "thermal_test_piece")
    throw InputError(m.file, 0, "manifest kind '" + m.kind + "': this evaluation is for the thermal test piece");
  TtpEvaluation e;
  e.manifest_file = m.file;
  e.input_file = r.file;
  e.format = "gauge";
  e.assigned_by = "labels";
  e.route = TtpRoute::Gauge;
  e.points = static_cast<int>(r.readings.size());
  e.coverage_k = opt.coverage_k;
  e.formulas = formulas(m, TtpRoute::Gauge);
  e.gauge_resolution_um = opt.gauge_resolution_um;
  const double u_read = opt.gauge_resolution_um / std::sqrt(12.0);
  e.scatter.type_b_sigma_mm = u_read * 1e-3;
  e.notes.push_back("E_Z and E_B are not available from the dial gauge on the facets (seed 004 L2121 measures the Z paths with a "
                    "separate depth gauge set-up)");
  e.notes.push_back("the readings are g = d(t_i) - d(t_0) per facet, so Eqs. 7.7-7.9 are the formulas below with g for the "
                    "changes of d; E_TTP is Eq. 7.3 (diametral) as on the other routes: (g_X1 + g_X2 + g_Y1 + g_Y2) / 2, twice "
                    "Eq. 7.9's radial mean, which is reported as ETTP_7_9_um and gives dT (Eq. 7.10)");
  e.notes.push_back("gauge uncertainty: the thesis states none; the budget reads the gauge resolution (" +
                    num(opt.gauge_resolution_um) + " um, --gauge-resolution-um) as rectangular per reading and per zero setting");
  std::map<std::string, double> g;
  for (const auto& x : r.readings) g[x.facet] = x.g_um;
  const auto cf = cycleFeatures(m);
  const auto ph = phases(m);
  const auto times = cycleTimes(m);
  if (!cf.count(0)) throw InputError(m.file, 0, "the manifest lists no reference features (cycle 0)");
  const auto& ref = cf.at(0);
  for (const char* s : kSides)
    if (!ref.by_side.count(s))
      throw InputError(m.file, 0, std::string("the manifest has no reference ") + s +
                                      " facet (cycle 0): the dial-gauge readings of that side are relative to it (seed 004 L2121)");
  auto reading = [&](const parts::ManifestFeature* f, const parts::ManifestFeature* f0) -> std::optional<double> {
    if (!f || !g.count(f->nominal.id)) return std::nullopt;
    return g.at(f->nominal.id) - (g.count(f0->nominal.id) ? g.at(f0->nominal.id) : 0.0);  // relative to the reference facet
  };
  const double alpha = m.material_alpha_um_per_m_K;
  const double dT = m.ttp.on_machine_temperature_change_K;
  // Not a structured binding: lambdas below use feats, which clang before 16 cannot capture
  // (C++20 P1091; scripts/fuzz.sh builds with clang 14).
  for (const auto& entry : cf) {
    const auto& c = entry.first;
    const auto& feats = entry.second;
    TtpCycleResult cr = cycleResult(c, ph, times);
    if (c == 0) {
      for (int j : {0, 1, 4, 5}) cr.values.push_back(zeroBudget(kQuantities[j], kUnits[j], opt.coverage_k));
      cr.ETTP_7_9_um = 0;
      e.cycles.push_back(cr);
      continue;
    }
    cr.missing.push_back("EZ_um, EB_urad: not measured by the dial gauge on the facets (seed 004 Eqs. 7.7-7.9)");
    std::map<std::string, std::optional<double>> v;
    std::map<std::string, bool> ok{{"Z", true}};
    std::vector<std::string> absent;
    for (const char* s : kSides) {
      const auto it = feats.by_side.find(s);
      v[s] = it == feats.by_side.end() ? std::nullopt : reading(it->second, ref.by_side.at(s));
      ok[s] = v[s].has_value();
      if (!ok[s]) absent.push_back(it == feats.by_side.end() ? std::string(s) + " (not in the manifest)" : it->second->nominal.id);
    }
    if (!absent.empty()) cr.missing.push_back(missingMessage(ok, absent, c, "no reading in " + r.file));
    const auto ge = parts::gaugeErrors(v["X1"].value_or(0), v["X2"].value_or(0), v["Y1"].value_or(0), v["Y2"].value_or(0));
    auto budget = [&](const std::string& q, double value, const std::vector<std::pair<const char*, double>>& w) {
      std::vector<Contribution> cs;
      double w2 = 0, t2 = 0;
      for (const auto& [s, wi] : w) {
        w2 += wi * wi;
        const double L = m.feature(feats.by_side.at(s)->nominal.id)->nominal.point_mm.head<2>().norm();
        if (std::isfinite(alpha)) t2 += std::pow(wi * alpha * 1e-6 * dT * L * 1e3, 2) / 3.0;
      }
      const std::string basis = "resolution " + num(opt.gauge_resolution_um) +
                                " um (--gauge-resolution-um; not stated in the thesis), rectangular, res/sqrt(12)";
      cs.push_back({"dial gauge readings", 'B', "rectangular", basis + " per reading", u_read * std::sqrt(w2), kInf});
      cs.push_back({"dial gauge zero on the reference facets", 'B', "rectangular", basis + " per side's zero setting",
                    u_read * std::sqrt(w2), kInf});
      if (std::isfinite(alpha))
        cs.push_back({"part temperature change between compared facets", 'B', "rectangular",
                      "alpha dT d per facet against its reference, " + alphaBasis(m) + ", dT within +-" + num(dT) +
                          " K (thermal_test_piece.on_machine.temperature_change)",
                      std::sqrt(t2), kInf});
      else
        cs.push_back({"part temperature change between compared facets", 'B', "rectangular",
                      "not stated: set blank.material.alpha_um_per_m_K in the part file", 0, kInf});
      return uncertainty::combine(q, "um", value, cs, opt.coverage_k);
    };
    if (v["X1"] && v["X2"]) cr.values.push_back(budget("EX_um", ge.EX_um, {{"X2", 0.5}, {"X1", -0.5}}));  // seed 004 Eq. 7.7
    if (v["Y1"] && v["Y2"]) cr.values.push_back(budget("EY_um", ge.EY_um, {{"Y2", 0.5}, {"Y1", -0.5}}));  // seed 004 Eq. 7.8
    if (v["X1"] && v["X2"] && v["Y1"] && v["Y2"]) {
      // Eq. 7.3 with g = d(t_i) - d(t_0): [(g_X1 + g_X2) + (g_Y1 + g_Y2)] / 2, exactly twice Eq. 7.9.
      cr.values.push_back(budget("ETTP_um", 2 * ge.ETTP_um, {{"X1", 0.5}, {"X2", 0.5}, {"Y1", 0.5}, {"Y2", 0.5}}));
      const auto radial = budget("ETTP_7_9_um", ge.ETTP_um, {{"X1", 0.25}, {"X2", 0.25}, {"Y1", 0.25}, {"Y2", 0.25}});  // seed 004 Eq. 7.9
      cr.ETTP_7_9_um = ge.ETTP_um;
      cr.values.push_back(temperatureBudget(m, radial, opt.coverage_k, false));
    }
    e.cycles.push_back(cr);
  }
  e.spans = ttpSpans(e.cycles);
  return e;
}

}  // namespace probeloop::evaluate
