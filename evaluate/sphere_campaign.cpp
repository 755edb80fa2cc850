#include "evaluate/sphere_campaign.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/location_errors.hpp"

namespace probeloop::evaluate {

using Eigen::Vector3d;
using geometry::LocationErrors;

namespace {

struct Layout {
  std::vector<int> ls_positions;
  std::vector<double> ls_angles;
  std::array<int, 4> formula_positions{};
  bool formulas = false;
};

Layout layoutOf(const parts::PlanManifest& m) {
  Layout l;
  for (const auto& s : m.spheres) {
    if (s.usedForCAxis()) {
      l.ls_positions.push_back(s.position);
      l.ls_angles.push_back(s.angle_deg);
    }
    if (s.formula_index > 0) l.formula_positions[s.formula_index - 1] = s.position;
  }
  l.formulas = l.formula_positions[0] && l.formula_positions[1] && l.formula_positions[2] &&
               l.formula_positions[3];
  return l;
}

std::vector<Vector3d> centresOf(const CycleEvaluation& c, const std::vector<int>& positions) {
  std::vector<Vector3d> out;
  for (int p : positions) out.push_back(c.spheres[p - 1].centre_mm());
  return out;
}

void evaluateLocationErrors(const parts::PlanManifest& m, const Layout& layout, CampaignEvaluation& out,
                            const EvaluateOptions& opt);

}  // namespace

std::vector<ScatterTerm> scatterTerms(const CycleEvaluation& c) {
  std::vector<ScatterTerm> out;
  for (const auto& s : c.spheres)
    if (s.free_radius && s.free_radius->dof > 0)
      out.push_back({c.cycle, s.position, s.free_radius->rms_mm * s.free_radius->rms_mm * s.points, double(s.free_radius->dof)});
  return out;
}

CampaignEvaluation evaluateSphereCampaign(const parts::PlanManifest& m,
                                          const std::vector<ProbeRecord>& records,
                                          const EvaluateOptions& opt) {
  CampaignEvaluation out;
  out.manifest_file = m.file;
  if (!records.empty()) out.points_file = records.front().file;
  const Layout layout = layoutOf(m);
  out.ls_positions = layout.ls_positions;
  out.formula_positions = layout.formula_positions;
  out.formulas_applicable = layout.formulas;
  const double known_radius = m.sphere_radius_mm + m.tip_radius_mm;

  // Group by cycle and position.
  std::map<int, std::map<int, std::vector<const ProbeRecord*>>> by;
  for (const auto& r : records) by[r.cycle][r.position].push_back(&r);

  for (int cyc = 1; cyc <= m.cycles; ++cyc) {
    auto it = by.find(cyc);
    if (it == by.end()) {
      out.incomplete.push_back({cyc, "no points logged"});
      continue;
    }
    CycleEvaluation ce;
    ce.cycle = cyc;
    std::string missing;
    double t_sum = 0;
    int t_n = 0;
    for (const auto& s : m.spheres) {
      const auto pit = it->second.find(s.position);
      const int n = pit == it->second.end() ? 0 : static_cast<int>(pit->second.size());
      if (n < 4) {
        missing += (missing.empty() ? "" : ", ") + std::string("position ") +
                   std::to_string(s.position) + " has " + std::to_string(n) + " of " +
                   std::to_string(m.pointsPerSphere()) + " points (a sphere needs >= 4)";
        continue;
      }
      std::vector<Vector3d> pts;
      double tp = 0;
      for (const auto* r : pit->second) {
        pts.push_back(r->tip_mm);
        const auto& planned = m.points[(s.position - 1) * m.pointsPerSphere() + (r->point - 1)];
        if (!r->time_s && std::isnan(m.cycle_start_s[cyc - 1]))
          throw InputError(r->file, r->line, "cycle " + std::to_string(cyc) +
                                                 ": no start time (the --cycle-starts file ends before it) and no time of its own");
        const double t = r->time_s ? *r->time_s : m.cycle_start_s[cyc - 1] + planned.time_in_cycle_s;
        t_sum += t;
        tp += t;
        ++t_n;
      }
      SphereMeasurement sm;
      sm.position = s.position;
      sm.points = n;
      sm.time_s = tp / n;
      try {
        geometry::SphereFitOptions fo;
        fo.fixed_radius_mm = known_radius;
        sm.known_radius = geometry::fitSphere(pts, fo);
      } catch (const GeometryError& e) {
        throw InputError(pit->second.front()->file, pit->second.front()->line,
                         "cycle " + std::to_string(cyc) + " position " +
                             std::to_string(s.position) + ": " + e.what());
      }
      try {
        sm.free_radius = geometry::fitSphere(pts);
      } catch (const GeometryError& e) {
        sm.free_radius_note = e.what();
      }
      ce.spheres.push_back(std::move(sm));
    }
    if (!missing.empty()) {
      out.incomplete.push_back({cyc, missing});
      continue;
    }
    ce.time_s = t_n ? t_sum / t_n : m.cycle_start_s[cyc - 1];
    out.cycles.push_back(std::move(ce));
  }
  evaluateLocationErrors(m, layout, out, opt);
  return out;
}

namespace {

// The location-error part both centre sources share: the reference cycle, the pooled scatter,
// the estimators and every budget, from the cycles' centres.
void evaluateLocationErrors(const parts::PlanManifest& m, const Layout& layout, CampaignEvaluation& out,
                            const EvaluateOptions& opt) {
  const LocationLeastSquares ls(layout.ls_angles, m.radius_from_axis_mm);
  if (out.cycles.empty())
    throw InputError(out.points_file, 0, "no complete cycle: nothing to evaluate");
  out.reference_cycle = out.cycles.front().cycle;
  if (!opt.known_radius)
    for (auto& c : out.cycles)
      for (auto& s : c.spheres) {
        if (!s.free_radius)
          throw InputError(out.points_file, 0, "--free-radius: cycle " + std::to_string(c.cycle) +
                                                   " position " + std::to_string(s.position) +
                                                   ": " + s.free_radius_note);
        s.use_free_radius = true;
      }

  const CycleEvaluation& ref = out.cycles.front();
  const auto ref_centres = centresOf(ref, layout.ls_positions);

  // Type A scatter of the points: pooled residuals of every free-radius fit. (Not the
  // known-radius fits: the probe's mean pre-travel shrinks the apparent radius, a systematic
  // misfit that cancels between cycles but would read as scatter there.)
  std::vector<ScatterTerm> terms = opt.prior_scatter;
  for (const auto& c : out.cycles) {
    const auto t = scatterTerms(c);
    terms.insert(terms.end(), t.begin(), t.end());
  }
  std::stable_sort(terms.begin(), terms.end(), [](const ScatterTerm& a, const ScatterTerm& b) { return a.cycle < b.cycle; });
  double ssr = 0, dof = 0;
  for (const auto& t : terms) {
    ssr += t.ssr_mm2;
    dof += t.dof;
  }
  out.point_scatter.type_b_sigma_mm = m.probe_repeatability_2sigma_um / 2.0 * 1e-3;
  if (dof > 0) {
    out.point_scatter.type_a_sigma_mm = std::sqrt(ssr / dof);
    out.point_scatter.type_a_dof = dof;
  }

  for (auto& c : out.cycles) {
    for (auto& s : c.spheres)
      s.centre_budgets = s.stated ? featureCentreBudgets(m, s.centre_mm(), s.stated_u, opt.coverage_k)
                                  : sphereCentreBudgets(m, s.centre_mm(), s.centre_cov_unscaled(), out.point_scatter, opt.coverage_k);
    const auto centres = centresOf(c, layout.ls_positions);
    c.least_squares = ls.solve(centres, ref_centres);
    const auto res = ls.residual(centres, ref_centres);
    c.model_residual_xy_um = res.xy_um;
    c.model_residual_z_um = res.z_um;
    if (layout.formulas) {
      std::array<Vector3d, 4> a, b;
      for (int f = 0; f < 4; ++f) {
        a[f] = c.spheres[layout.formula_positions[f] - 1].centre_mm();
        b[f] = ref.spheres[layout.formula_positions[f] - 1].centre_mm();
      }
      c.formulas = gebhardtFormulas(a, b, 2.0 * m.radius_from_axis_mm * 1e-3);
    }
    for (const auto& s : m.spheres)
      if (s.repeat_of)
        c.repeats.push_back({s.position, s.repeat_of,
                             (c.spheres[s.position - 1].centre_mm() -
                              c.spheres[s.repeat_of - 1].centre_mm()) * 1e3});
  }

  // Budget inputs per cycle: fit covariances, each position's time in the cycle, and the
  // error rates from the neighbouring cycles (central differences; one-sided at the ends).
  const auto n_cycles = out.cycles.size();
  std::vector<CycleBudgetInput> inputs(n_cycles);
  for (std::size_t i = 0; i < n_cycles; ++i) {
    const auto& c = out.cycles[i];
    auto& in = inputs[i];
    std::size_t n_stated = 0, n_form = 0;
    for (int p : layout.ls_positions) {
      const auto& s = c.spheres[static_cast<std::size_t>(p - 1)];
      in.centre_cov_unscaled.push_back(s.centre_cov_unscaled());
      in.tau_s.push_back(s.time_s - c.time_s);
      if (s.stated) {
        in.stated_u_mm.push_back(s.stated_u.u_mm);
        in.form_u_mm.push_back(s.stated_u.form_u_mm);
        n_stated += s.stated_u.stated;
        n_form += s.stated_u.form_stated;
      }
    }
    if (!in.stated_u_mm.empty()) {
      const auto n = std::to_string(in.stated_u_mm.size());
      in.stated_basis = "u_x/u_y/u_z_um of the file for " + std::to_string(n_stated) + " of the " + n + " centres" +
                        (n_stated < in.stated_u_mm.size()
                             ? "; the others not stated: probe.repeatability_2sigma = " + formatSignificant4(m.probe_repeatability_2sigma_um) +
                                   " um through the planned points' fit, scaled to n_points"
                             : std::string());
      in.form_basis = "form_um of the file for " + std::to_string(n_form) + " of the " + n + " centres" +
                      (n_form < in.stated_u_mm.size() ? "; the others the artifact's " + formatSignificant4(m.sphere_form_error_um) + " um" : std::string()) +
                      ", +-form/2 on each coordinate; does not cancel: the file does not say that the same points were probed";
    }
    if (n_cycles >= 2) {
      const std::size_t lo = i == 0 ? 0 : i - 1, hi = i + 1 == n_cycles ? i : i + 1;
      const double dt = out.cycles[hi].time_s - out.cycles[lo].time_s;
      if (dt > 0) {
        const auto a = out.cycles[lo].least_squares.values(), b = out.cycles[hi].least_squares.values();
        for (int j = 0; j < 7; ++j) in.rate_per_s[static_cast<std::size_t>(j)] = (b[j] - a[j]) / dt;
        in.rate_known = true;
      }
    }
  }
  for (std::size_t i = 0; i < n_cycles; ++i) {
    auto& c = out.cycles[i];
    const auto values = c.least_squares.values();
    if (c.cycle == out.reference_cycle) {  // its errors are zero by definition
      for (int j = 0; j < 7; ++j) {
        std::string name = LocationErrors::names()[j];
        const std::string unit = name.substr(name.find('_') + 1);
        c.budgets[j] = uncertainty::combine(name.substr(0, name.find('_')), unit, values[j], {}, opt.coverage_k);
      }
      continue;
    }
    c.budgets = locationErrorBudgets(ls, m, inputs[i], inputs[0], values, out.point_scatter, opt.coverage_k);
  }

  if (out.cycles.size() >= 2)
    for (const auto& s : m.spheres) {
      std::vector<Vector3d> cs;
      for (const auto& c : out.cycles) cs.push_back(c.spheres[static_cast<std::size_t>(s.position - 1)].centre_mm());
      out.centre_repeatability.push_back({s.position, centreRepeatability(cs)});
    }
}

}  // namespace

CampaignEvaluation evaluateSphereCampaignFromFeatures(const parts::PlanManifest& m, const SphereCentresFromFeatures& centres,
                                                      const std::string& file, const EvaluateOptions& opt) {
  // --free-radius chooses how a centre is fitted: only a sphere of points only is fitted here
  // (featureActualsFromCmm); a stated centre comes from no fit of ours.
  if (!opt.known_radius)
    for (const auto& [cycle, by_position] : centres.by_cycle)
      for (const auto& [position, c] : by_position)
        if (!c.feature.fitted_here)
          throw InputError(c.feature.file, c.feature.line, "--free-radius: sphere '" + c.feature.id +
                                                               "' states its centre, which comes from no fit of ours");
  CampaignEvaluation out;
  out.manifest_file = m.file;
  out.points_file = file;
  out.from_features = true;
  out.other_features = centres.other_kinds;
  const Layout layout = layoutOf(m);
  out.ls_positions = layout.ls_positions;
  out.formula_positions = layout.formula_positions;
  out.formulas_applicable = layout.formulas;
  const int per = m.pointsPerSphere();
  for (int cyc = 1; cyc <= m.cycles; ++cyc) {
    const auto it = centres.by_cycle.find(cyc);
    if (it == centres.by_cycle.end()) {
      out.incomplete.push_back({cyc, "no sphere centres in the feature file"});
      continue;
    }
    CycleEvaluation ce;
    ce.cycle = cyc;
    std::string missing;
    double t_sum = 0, n_sum = 0;
    for (const auto& s : m.spheres) {
      const auto pit = it->second.find(s.position);
      if (pit == it->second.end()) {
        missing += (missing.empty() ? "" : ", ") + std::string("position ") + std::to_string(s.position) +
                   " has no sphere centre in the feature file";
        continue;
      }
      const FeatureActual& f = pit->second.feature;
      SphereMeasurement sm;
      sm.position = s.position;
      const int n_points = f.n_points > 0 ? f.n_points : per;  // not stated: as planned
      sm.points = n_points;
      if (f.time_s) {
        sm.time_s = *f.time_s;
      } else {
        if (std::isnan(m.cycle_start_s[cyc - 1]))
          throw InputError(f.file, f.line, "cycle " + std::to_string(cyc) +
                                               ": no start time (the --cycle-starts file ends before it) and no time_s of its own");
        double t = 0;
        for (int i = 0; i < per; ++i) t += m.points[static_cast<std::size_t>((s.position - 1) * per + i)].time_in_cycle_s;
        sm.time_s = m.cycle_start_s[cyc - 1] + t / per;
      }
      t_sum += sm.time_s * n_points;
      n_sum += n_points;
      sm.stated = pit->second;
      sm.stated_u = featureCentreU(m, f, s.position);
      ce.spheres.push_back(std::move(sm));
    }
    if (!missing.empty()) {
      out.incomplete.push_back({cyc, missing});
      continue;
    }
    ce.time_s = t_sum / n_sum;
    out.cycles.push_back(std::move(ce));
  }
  // The centres are the file's or fitted here as --free-radius chose: no free-radius fit to switch to.
  EvaluateOptions stated = opt;
  stated.known_radius = true;
  evaluateLocationErrors(m, layout, out, stated);
  return out;
}

Resolution locationErrorResolution(const parts::PlanManifest& m, double step) {
  const Layout layout = layoutOf(m);
  Resolution r;
  const LocationLeastSquares ls(layout.ls_angles, m.radius_from_axis_mm);
  const auto& W = ls.sensitivity();
  for (int j = 0; j < 7; ++j) r.least_squares[j] = W.row(j).cwiseAbs().maxCoeff() * step;
  if (layout.formulas) {
    // The formulas are linear: perturb each coordinate of the cycle by one step.
    std::array<Vector3d, 4> base;
    for (int f = 0; f < 4; ++f) base[f] = m.sphere(layout.formula_positions[f])->nominal_centre_mm;
    std::array<double, 7> best{};
    for (int f = 0; f < 4; ++f)
      for (int axis = 0; axis < 3; ++axis) {
        auto moved = base;
        moved[f](axis) += step;
        const auto e = gebhardtFormulas(moved, base, 2.0 * m.radius_from_axis_mm * 1e-3).values();
        for (int j = 0; j < 7; ++j) best[j] = std::max(best[j], std::fabs(e[j]));
      }
    r.formulas = best;
  }
  return r;
}

}  // namespace probeloop::evaluate
