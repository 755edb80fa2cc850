// Evaluation of the thermal test piece (contract in thermal_test_piece.hpp; the definitions and
// every budget term with its derivation in docs/thermal-test-piece-evaluation.md).
// This file: the steps of the CMM and on-machine routes in order (evaluateImpl); the steps
// themselves are in ttp_frame.cpp, ttp_fits.cpp, ttp_budget.cpp, ttp_values.cpp and
// ttp_spans.cpp (ttp_detail.hpp lists them).
#include "evaluate/thermal_test_piece.hpp"

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "evaluate/ttp_detail.hpp"

namespace probeloop::evaluate {

const uncertainty::Budget* TtpCycleResult::value(const std::string& q) const {
  for (const auto& b : values)
    if (b.quantity == q) return &b;
  return nullptr;
}

namespace ttp {

namespace {

std::string lineList(const std::vector<int>& lines) {
  std::string s;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i == 12) return s + ", ...";
    s += (i ? ", " : "") + std::to_string(lines[i]);
  }
  return s;
}

}  // namespace

[[noreturn]] void featureError(const std::string& file, const std::vector<Pt>& all, const std::vector<int>& idx,
                               const std::string& id, const std::string& what) {
  std::vector<int> lines;
  for (int i : idx) lines.push_back(all[static_cast<std::size_t>(i)].line);
  throw InputError(file, lines.empty() ? 0 : lines.front(),
                   "feature " + id + " has " + std::to_string(idx.size()) + " point" + (idx.size() == 1 ? "" : "s") +
                       (lines.empty() ? "" : " (lines " + lineList(lines) + ")") + ": " + what);
}

TtpEvaluation evaluateImpl(const parts::PlanManifest& m, const TtpPoints& in, const TtpOptions& opt, bool predicted,
                           const StatedSigmas* stated) {
  if (m.kind != "thermal_test_piece")
    throw InputError(m.file, 0, "manifest kind '" + m.kind + "': this evaluation is for the thermal test piece");
  TtpEvaluation e;
  e.manifest_file = m.file;
  e.input_file = in.file;
  e.format = in.format;
  e.assigned_by = in.assigned_by;
  e.route = in.route;
  e.points = static_cast<int>(in.points.size());
  e.coverage_k = opt.coverage_k;
  e.formulas = formulas(m, in.route);
  const std::string& file = in.file;

  // Points grouped by feature, in file order.
  std::vector<Pt> pts;
  std::map<std::string, std::vector<int>> by;
  for (const auto& p : in.points) {
    if (!m.feature(p.feature))
      throw InputError(file, p.line, "feature '" + p.feature + "' is not in the manifest " + m.file);
    Pt q;
    q.feature = p.feature;
    q.line = p.line;
    q.file_mm = p.p_mm;
    by[p.feature].push_back(static_cast<int>(pts.size()));
    pts.push_back(q);
  }

  // Datum frame.
  const DatumFits datums = fitDatums(file, pts, by);
  const TtpFrame& frame = datums.fits.frame;
  for (auto& p : pts) p.part_mm = frame.toPart(p.file_mm);

  // Scatter per point.
  const double sigma_spec_om = m.probe_repeatability_2sigma_um / 2 * 1e-3;
  setPointScatter(pts, m, in.route, sigma_spec_om);
  TtpScatter stated_scatter;
  if (stated) {
    // The features route: each placed point's scatter as the file states it (docs/formats.md).
    double sb2 = 0;
    int nb = 0;
    for (const auto& p : pts) {
      const auto* f = m.feature(p.feature);
      if (f->nominal.role == "z_path" || f->nominal.role == "facet") sb2 += p.sigma_b_mm * p.sigma_b_mm, ++nb;
    }
    stated_scatter = statedScatter(m, *stated, nb ? std::sqrt(sb2 / nb) : sigma_spec_om);
    e.stated.emplace();
    std::map<std::string, std::pair<double, int>> sum;
    std::map<std::string, const char*> from;
    for (auto& p : pts) {
      const auto [sigma, why] = statedPointSigma(p.sigma_b_mm, stated->at(p.feature), stated_scatter);
      p.sigma_b_mm = sigma;
      sum[p.feature].first += sigma * sigma, ++sum[p.feature].second;
      if (!from.count(p.feature) || std::string(why) == "stated u") from[p.feature] = why;
    }
    for (const auto& [id, a] : sum) {
      TtpStatedFeature f;
      f.id = id;
      f.sigma_um = std::sqrt(a.first / a.second) * 1e3;
      f.sigma_from = from[id];
      e.stated->features.push_back(f);
    }
  }

  // Alignment report.
  e.alignment = alignmentReport(datums.sets, datums.fits, opt.form_mz);

  // Measurement features: one LS plane each (part frame).
  const auto times = cycleTimes(m);
  const auto planes = fitFeatures(m, file, pts, by, times, opt.form_mz, e.features);

  // Type A: pooled residual of the measurement-feature fits.
  // (The features route: the stated forms pooled instead; the budgets take each point's sigma.)
  e.scatter = stated ? stated_scatter : pooledScatter(planes, pts, sigma_spec_om, predicted);

  // Quantities per feature.
  TtpScatter per_point = e.scatter;
  if (stated) per_point.type_a_used = false;  // the features route: already in each point's sigma
  FeatureQuantities fq = featureQuantities(m, planes, pts, per_point, e.features);

  // Frame sensitivities to every datum point (central differences of the construction).
  BudgetContext ctx;
  ctx.m = &m;
  ctx.route = in.route;
  ctx.pts = &pts;
  ctx.scatter = e.scatter;
  ctx.predicted = predicted;
  ctx.stated = stated != nullptr;
  ctx.k = opt.coverage_k;
  if (opt.budgets) ctx.datum_sens = datumSensitivities(datums.sets, datums.fits, by);

  // Cycles.
  e.cycles = cycleValues(m, file, opt, predicted, times, planes, fq, ctx);
  e.spans = ttpSpans(e.cycles);
  return e;
}

}  // namespace ttp

TtpEvaluation evaluateThermalTestPiece(const parts::PlanManifest& m, const TtpPoints& points, const TtpOptions& options) {
  return ttp::evaluateImpl(m, points, options, false);
}

}  // namespace probeloop::evaluate
