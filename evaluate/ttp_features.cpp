// The thermal test piece from the features a CMM states (contract in thermal_test_piece.hpp,
// docs/thermal-test-piece-evaluation.md §10): the rows matched to the plan's features, the plan's
// points placed on them (evaluate/feature_points.hpp), then the CMM route's steps with the
// scatter the file states.
#include <algorithm>
#include <cmath>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/feature_match.hpp"
#include "evaluate/feature_points.hpp"
#include "evaluate/ttp_detail.hpp"

namespace probeloop::evaluate {

namespace ttp {

TtpScatter statedScatter(const parts::PlanManifest& m, const StatedSigmas& s, double type_b_sigma_mm) {
  TtpScatter out;
  out.type_b_sigma_mm = type_b_sigma_mm;
  double v = 0, dof = 0;
  for (const auto& [id, x] : s) {
    const auto* f = m.feature(id);
    if (!f || (f->nominal.role != "z_path" && f->nominal.role != "facet") || !(x.dof > 0) || !std::isfinite(x.form_mm)) continue;
    v += x.dof * x.form_mm * x.form_mm;
    dof += x.dof;
  }
  if (dof > 0) {
    out.type_a_sigma_mm = std::sqrt(v / dof);
    out.type_a_dof = dof;
    out.type_a_used = out.type_a_sigma_mm > type_b_sigma_mm;
  }
  return out;
}

std::pair<double, const char*> statedPointSigma(double spec_mm, const StatedSigma& s, const TtpScatter& pooled) {
  std::pair<double, const char*> r{pooled.type_a_used ? pooled.type_a_sigma_mm : spec_mm, pooled.type_a_used ? "stated forms" : "specification"};
  if (std::isfinite(s.u_mm) && s.u_mm > r.first) r = {s.u_mm, "stated u"};
  return {r.first * s.scale, r.second};
}

std::map<std::string, std::vector<Vector3d>> plannedSurfacePoints(const parts::PlanManifest& m) {
  std::map<std::string, std::vector<Vector3d>> out;
  for (const auto& p : m.points)
    out[p.feature].push_back(machineToPart(m, p.contact_mm + m.tip_radius_mm * p.approach.normalized(), p.c_deg));
  return out;
}

}  // namespace ttp

TtpEvaluation evaluateThermalTestPieceFromFeatures(const parts::PlanManifest& m, const std::vector<FeatureActual>& rows,
                                                   const std::string& file, const std::string& format, const TtpOptions& options) {
  if (m.kind != "thermal_test_piece")
    throw InputError(m.file, 0, "manifest kind '" + m.kind + "': this evaluation is for the thermal test piece");
  const FeatureMatch match = matchFeatureActuals(rows, m);
  for (const char* datum : {"TOP", "FLANK_P", "FLANK_N", "CYL"})
    if (m.feature(datum) && !match.find(datum))
      throw InputError(file, 0, std::string("the datum ") + datum + " is not among the file's features (by id or nominal geometry): "
                                "the datum frame needs TOP, FLANK_P, FLANK_N and CYL (seed 004 L2055)");
  const auto placed = pointsOnStatedFeatures(match, ttp::plannedSurfacePoints(m), file, format);
  ttp::StatedSigmas sigmas;
  for (const auto& mf : match.matched) {
    const auto& s = placed.scatter.at(mf.feature->nominal.id);
    sigmas[s.id] = {s.point_scale, s.sigma_from_form_mm, s.form_dof, s.sigmaFromStatedU_mm()};
  }
  TtpOptions o = options;
  o.form_mz = false;  // the placed points lie on the stated features: their form is the file's
  TtpEvaluation e = ttp::evaluateImpl(m, placed.points, o, false, &sigmas);

  // What was stated, in the manifest's order, with the sigma the budget used.
  auto& st = *e.stated;
  std::map<std::string, TtpStatedFeature> used;
  for (const auto& f : st.features) used[f.id] = f;
  st.features.clear();
  for (const auto& mf : m.features) {
    const auto* x = match.find(mf.nominal.id);
    if (!x || !used.count(mf.nominal.id)) continue;
    TtpStatedFeature f = used.at(mf.nominal.id);
    const auto& s = placed.scatter.at(f.id);
    f.file_id = x->actual.id;
    f.line = x->actual.line;
    f.matched_by = x->by_id ? "id" : "nominal geometry";
    f.n_stated = s.n_stated;
    f.n_planned = s.n_planned;
    if (std::isfinite(s.form_um)) f.form_um = s.form_um;
    st.features.push_back(f);
  }
  for (const auto& u : match.unmatched) st.unmatched.push_back(unmatchedText(u));
  st.other_kinds = match.other_kinds;
  // The forms as stated, NaN (null, "-") where not; no residuals (the placed points have none).
  if (e.alignment)
    for (auto& d : e.alignment->datums) {
      const auto it = placed.scatter.find(d.id);
      d.form_um = it != placed.scatter.end() ? it->second.form_um : NAN;
    }
  for (auto& f : e.features) {
    f.form_mz_um = placed.scatter.at(f.id).form_um;
    f.rms_um = NAN;
  }

  int not_stated = 0;
  for (const auto& f : st.features) not_stated += f.n_stated == 0;
  e.notes.push_back("Evaluated from the " + std::to_string(st.features.size()) + " features the file states, without points: the plan's " +
                    std::to_string(e.points) + " points placed on them (a least-squares fit of them returns each stated feature), "
                    "so every value is the point route's from the same least-squares features.");
  e.notes.push_back(fittingCriterionNote(match));
  e.notes.push_back("Lost against the point route: the type A scatter of the residuals (each feature's scatter is estimated from "
                    "its stated form over d2(n) instead, or the specification where larger), the real point layout (the plan's "
                    "gives the sensitivities), the outlier check, the minimum-zone form (the stated form is reported as it is), "
                    "and the line of each point (messages name the feature's row).");
  if (not_stated)
    e.notes.push_back(std::to_string(not_stated) + " feature" + (not_stated == 1 ? "" : "s") +
                      " without a stated point count: the planned count is taken as the number of points measured.");
  if (!st.unmatched.empty())
    e.notes.push_back(std::to_string(st.unmatched.size()) + " feature" + (st.unmatched.size() == 1 ? "" : "s") +
                      " of the file fit no feature of the plan and are not used (stated_features.unmatched).");
  for (auto& n : statedScatterNotes(placed.scatter)) e.notes.push_back(std::move(n));
  // No point was read: the placed ones are the plan's.
  st.points_placed = e.points;
  e.points = 0;
  return e;
}

}  // namespace probeloop::evaluate
