#include "evaluate/sphere_campaign.hpp"

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
    if (s.repeat_of == 0) {
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

// Variance of W_j . centres for one cycle when every point has standard deviation sigma.
double propagated(const Eigen::MatrixXd& W, int j, const CycleEvaluation& c,
                  const std::vector<int>& positions, double sigma_mm) {
  double v = 0;
  for (size_t k = 0; k < positions.size(); ++k) {
    const Eigen::RowVector3d w = W.block<1, 3>(j, 3 * static_cast<Eigen::Index>(k));
    v += (w * c.spheres[positions[k] - 1].centre_cov_unscaled() * w.transpose())(0, 0);
  }
  return std::sqrt(std::max(v, 0.0)) * sigma_mm;
}

}  // namespace

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
  const LocationLeastSquares ls(layout.ls_angles, m.radius_from_axis_mm);
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
      for (const auto* r : pit->second) {
        pts.push_back(r->tip_mm);
        const auto& planned = m.points[(s.position - 1) * m.pointsPerSphere() + (r->point - 1)];
        t_sum += r->time_s ? *r->time_s : m.cycle_start_s[cyc - 1] + planned.time_in_cycle_s;
        ++t_n;
      }
      SphereMeasurement sm;
      sm.position = s.position;
      sm.points = n;
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
  const double sigma_probe_mm = m.probe_repeatability_2sigma_um / 2.0 * 1e-3;
  const double sigma_res_mm = m.coordinate_resolution_mm / std::sqrt(12.0);
  const auto& W = ls.sensitivity();

  for (auto& c : out.cycles) {
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
    const auto values = c.least_squares.values();
    const bool is_ref = c.cycle == out.reference_cycle;
    for (int j = 0; j < 7; ++j) {
      std::string name = LocationErrors::names()[j];
      const std::string unit = name.substr(name.find('_') + 1);
      name = name.substr(0, name.find('_'));
      std::vector<uncertainty::Contribution> contrib;
      if (!is_ref) {  // the reference cycle's errors are zero by definition
        const std::string probe_basis = "machine probe.repeatability_2sigma = " +
                                        formatNumber(m.probe_repeatability_2sigma_um) + " um";
        const std::string res_basis = "coordinate resolution " +
                                      formatNumber(m.coordinate_resolution_mm * 1e3) + " um";
        contrib.push_back({"probe repeatability, this cycle", 'B', "normal", probe_basis,
                           propagated(W, j, c, layout.ls_positions, sigma_probe_mm)});
        contrib.push_back({"probe repeatability, reference cycle", 'B', "normal", probe_basis,
                           propagated(W, j, ref, layout.ls_positions, sigma_probe_mm)});
        contrib.push_back({"coordinate resolution, this cycle", 'B', "rectangular", res_basis,
                           propagated(W, j, c, layout.ls_positions, sigma_res_mm)});
        contrib.push_back({"coordinate resolution, reference cycle", 'B', "rectangular", res_basis,
                           propagated(W, j, ref, layout.ls_positions, sigma_res_mm)});
        contrib.push_back({"sphere form error", 'B', "rectangular",
                           "cancels: the same sphere points are probed in every cycle", 0.0});
      }
      c.budgets[j] = uncertainty::combine(name, unit, values[j], contrib, opt.coverage_k);
    }
  }
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
