// Writers of the evaluation outputs (formats: docs/formats.md).
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/csv.hpp"
#include "evaluate/budget_json.hpp"
#include "evaluate/sphere_campaign.hpp"

namespace probeloop::evaluate {

using nlohmann::ordered_json;
using geometry::LocationErrors;

namespace {
ordered_json errorsJson(const LocationErrors& e) {
  ordered_json j;
  const auto v = e.values();
  for (int i = 0; i < 7; ++i) j[LocationErrors::names()[i]] = v[i];
  return j;
}
ordered_json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

std::string errorSeriesCsv(const CampaignEvaluation& e) {
  std::ostringstream o;
  o << "# probeloop location errors of the C axis, relative to cycle " << e.reference_cycle
    << "; least squares over positions";
  for (int p : e.ls_positions) o << " " << p;
  o << "; U = expanded uncertainty (k = 2)\n";
  o << "time_s,cycle";
  for (const auto* n : LocationErrors::names()) o << "," << n;
  for (const auto* n : LocationErrors::names()) o << ",U_" << n;
  o << "\n";
  for (const auto& c : e.cycles) {
    o << formatNumber(c.time_s, 3) << "," << c.cycle;
    for (double v : c.least_squares.values()) o << "," << formatNumber(v, 4);
    for (const auto& b : c.budgets) o << "," << formatNumber(b.U, 4);
    o << "\n";
  }
  return o.str();
}

std::string evaluationJson(const CampaignEvaluation& e, const parts::PlanManifest& m) {
  ordered_json j;
  j["format"] = "probeloop-evaluation";
  j["version"] = 1;
  j["kind"] = "sphere_artifact";
  j["manifest"] = e.manifest_file;
  j["points_file"] = e.points_file;
  if (e.from_features)
    j["centres_from"] = {{"source", "feature actuals (docs/formats.md#feature-actuals-csv): no points, no fits"},
                         {"rows_of_other_kinds_not_used", e.other_features}};
  j["reference_cycle"] = e.reference_cycle;
  j["d_m"] = 2.0 * m.radius_from_axis_mm * 1e-3;
  j["least_squares_positions"] = e.ls_positions;
  j["formula_positions"] = e.formulas_applicable ? ordered_json(e.formula_positions) : ordered_json();
  j["sign_conventions"] = "docs/conventions.md";
  j["incomplete_cycles"] = ordered_json::array();
  for (const auto& [c, why] : e.incomplete) j["incomplete_cycles"].push_back({{"cycle", c}, {"reason", why}});
  j["point_scatter"] = {{"type_b_sigma_um", e.point_scatter.type_b_sigma_mm * 1e3},
                        {"type_a_sigma_um", e.point_scatter.type_a_sigma_mm * 1e3},
                        {"type_a_dof", e.point_scatter.type_a_dof},
                        {"used", e.point_scatter.type_a_sigma_mm > e.point_scatter.type_b_sigma_mm ? "type A" : "type B"}};
  j["centre_repeatability"] = ordered_json::array();
  for (const auto& [pos, r] : e.centre_repeatability)
    j["centre_repeatability"].push_back({{"position", pos},
                                         {"cycles", r.n},
                                         {"s_um", vec(r.s_um)},
                                         {"U_single_um", vec(r.U_single_um)},
                                         {"U_single_3d_um", r.U_single_3d_um},
                                         {"U_mean_um", vec(r.U_mean_um)},
                                         {"U_mean_3d_um", r.U_mean_3d_um},
                                         {"note", "over the complete cycles, drift included (seed 004 Table 5.3 statistics)"}});
  for (const auto& c : e.cycles) {
    ordered_json jc;
    jc["cycle"] = c.cycle;
    jc["time_s"] = c.time_s;
    jc["least_squares"] = errorsJson(c.least_squares);
    jc["formulas_eq_5_4_to_5_10"] = c.formulas ? errorsJson(*c.formulas) : ordered_json();
    jc["model_residual_xy_um"] = c.model_residual_xy_um;
    jc["model_residual_z_um"] = c.model_residual_z_um;
    for (const auto& b : c.budgets) jc["budgets"].push_back(budgetJson(b));
    for (const auto& s : c.spheres) {
      ordered_json js;
      js["position"] = s.position;
      js["points"] = s.points;
      js["centre_used"] = s.stated ? "feature_file" : s.use_free_radius ? "free_radius" : "known_radius";
      js["centre_mm"] = vec(s.centre_mm());
      js["centre_U_um"] = {s.centre_budgets[0].U, s.centre_budgets[1].U, s.centre_budgets[2].U};
      for (const auto& b : s.centre_budgets) {
        ordered_json jb = {{"quantity", b.quantity}, {"unit", b.unit}, {"u_c", b.u_c}, {"nu_eff", finiteOrNull(b.nu_eff)}, {"k", b.k}, {"U", b.U}};
        for (const auto& ct : b.contributions)
          jb["contributions"].push_back({{"input", ct.input}, {"type", std::string(1, ct.type)}, {"distribution", ct.distribution},
                                         {"basis", ct.basis}, {"u", ct.u}});
        js["centre_budgets"].push_back(jb);
      }
      if (s.stated) {
        const auto& f = s.stated->feature;
        js["feature"] = {{"id", f.id},
                         {"line", f.line},
                         {"matched_by", s.stated->by_id ? "id" : "nearest nominal centre"},
                         {"centre", !f.fitted_here ? "as the file states it"
                                    : std::isfinite(f.fitted_known_radius_mm)
                                        ? "least-squares sphere of the file's points (known radius " + formatNumber(f.fitted_known_radius_mm) +
                                              " mm, the plan's; --free-radius frees it), fitted here"
                                        : std::string("least-squares sphere of the file's points (free radius, --free-radius), fitted here")},
                         {"diameter_mm", finiteOrNull(f.size_mm)},
                         {"form_um", finiteOrNull(f.form_um)},
                         {"n_points", f.n_points}};
        jc["spheres"].push_back(js);
        continue;
      }
      js["known_radius_mm"] = s.known_radius.radius_mm;
      js["known_radius_rms_um"] = s.known_radius.rms_mm * 1e3;
      if (s.free_radius) {
        js["free_radius"] = {{"centre_mm", vec(s.free_radius->centre_mm)},
                             {"radius_mm", s.free_radius->radius_mm},
                             {"rms_um", s.free_radius->rms_mm * 1e3},
                             {"form_um", s.free_radius->form_mm * 1e3}};
      } else {
        js["free_radius"] = {{"note", s.free_radius_note}};
      }
      jc["spheres"].push_back(js);
    }
    for (const auto& r : c.repeats)
      jc["repeatability"].push_back(
          {{"position", r.position}, {"repeat_of", r.repeat_of}, {"difference_um", vec(r.difference_um)}});
    j["cycles"].push_back(jc);
  }
  return j.dump(1) + "\n";
}

std::string evaluationReport(const CampaignEvaluation& e, const parts::PlanManifest& m) {
  std::ostringstream o;
  o << "# Location errors of the C axis: results and uncertainty budgets\n\n";
  o << "Manifest `" << e.manifest_file << "`, points `" << e.points_file << "`; errors relative to cycle "
    << e.reference_cycle << " (least squares over positions";
  for (int p : e.ls_positions) o << " " << p;
  o << "; d/2 = " << formatNumber(m.radius_from_axis_mm) << " mm). U is the expanded uncertainty (k = "
    << formatNumber(e.cycles.empty() ? 2.0 : e.cycles.front().budgets[0].k) << ").\n\n";
  if (e.from_features)
    o << "Sphere centres as the feature file states them (no points): each centre's budget is the file's stated u per "
         "coordinate (or the probe's specification through the planned points, scaled to n_points) and its form; the "
         "point route's pooled type A scatter and free-radius fits are not available (docs/uncertainty.md#sphere-centres-from-feature-actuals).\n\n";
  o << "Probe point scatter: specification sigma = " << formatNumber(e.point_scatter.type_b_sigma_mm * 1e3, 4)
    << " um, pooled fit residual s = " << formatNumber(e.point_scatter.type_a_sigma_mm * 1e3, 4) << " um (nu = "
    << formatNumber(e.point_scatter.type_a_dof) << "); the budgets use the larger.\n\n";
  o << "## Range of U over the cycles\n\n| error | unit | smallest U | largest U | largest contribution (at the largest U) |\n|---|---|---|---|---|\n";
  for (int j = 0; j < 7; ++j) {
    const uncertainty::Budget* lo = nullptr;
    const uncertainty::Budget* hi = nullptr;
    for (const auto& c : e.cycles) {
      if (c.cycle == e.reference_cycle) continue;
      const auto& b = c.budgets[j];
      if (!lo || b.U < lo->U) lo = &b;
      if (!hi || b.U > hi->U) hi = &b;
    }
    if (!hi) continue;
    o << "| " << hi->quantity << " | " << hi->unit << " | " << formatNumber(lo->U, 3) << " | " << formatNumber(hi->U, 3)
      << " | " << (hi->contributions.empty() ? "" : hi->contributions.front().input) << " |\n";
  }
  const CycleEvaluation* last = e.cycles.empty() ? nullptr : &e.cycles.back();
  if (last && last->cycle != e.reference_cycle) {
    o << "\n## Budgets of cycle " << last->cycle << " (the last)\n";
    for (const auto& b : last->budgets) {
      o << "\n### " << b.quantity << " = " << formatNumber(b.value, 4) << " " << b.unit << ", U = " << formatNumber(b.U, 3)
        << " " << b.unit << " (u_c = " << formatNumber(b.u_c, 3) << ", nu_eff = "
        << (std::isfinite(b.nu_eff) ? formatNumber(b.nu_eff, 3) : std::string("inf")) << ", k = " << formatNumber(b.k, 3)
        << ")\n\n| input | type | distribution | u (" << b.unit << ") | share of u_c^2 | basis |\n|---|---|---|---|---|---|\n";
      for (const auto& c : b.contributions)
        o << "| " << c.input << " | " << c.type << " | " << c.distribution << " | " << formatNumber(c.u, 3) << " | "
          << formatNumber(b.u_c > 0 ? 100 * c.u * c.u / (b.u_c * b.u_c) : 0.0, 3) << " % | " << c.basis << " |\n";
    }
  }
  if (!e.centre_repeatability.empty()) {
    o << "\n## Sphere-centre repeatability over the cycles (seed 004 Table 5.3 statistics)\n\n"
         "Drift between cycles is included (Table 5.3 measured one position continuously). U = 2 s for one "
         "measurement, 2 s / sqrt(n) for the mean; 3D = root-sum-square of X, Y, Z.\n\n"
         "| position | cycles | U X (um) | U Y (um) | U Z (um) | U 3D (um) | U 3D of the mean (um) |\n|---|---|---|---|---|---|---|\n";
    for (const auto& [pos, r] : e.centre_repeatability)
      o << "| " << pos << " | " << r.n << " | " << formatNumber(r.U_single_um.x(), 3) << " | "
        << formatNumber(r.U_single_um.y(), 3) << " | " << formatNumber(r.U_single_um.z(), 3) << " | "
        << formatNumber(r.U_single_3d_um, 3) << " | " << formatNumber(r.U_mean_3d_um, 3) << " |\n";
  }
  for (const auto& [c, why] : e.incomplete) o << "\nCycle " << c << " not evaluated: " << why << "\n";
  return o.str();
}

}  // namespace probeloop::evaluate
