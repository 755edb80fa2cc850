// Writers of the evaluation outputs (formats: docs/formats.md).
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/csv.hpp"
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
ordered_json finiteOrNull(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }
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
  j["reference_cycle"] = e.reference_cycle;
  j["d_m"] = 2.0 * m.radius_from_axis_mm * 1e-3;
  j["least_squares_positions"] = e.ls_positions;
  j["formula_positions"] = e.formulas_applicable ? ordered_json(e.formula_positions) : ordered_json();
  j["sign_conventions"] = "docs/conventions.md";
  j["incomplete_cycles"] = ordered_json::array();
  for (const auto& [c, why] : e.incomplete) j["incomplete_cycles"].push_back({{"cycle", c}, {"reason", why}});
  for (const auto& c : e.cycles) {
    ordered_json jc;
    jc["cycle"] = c.cycle;
    jc["time_s"] = c.time_s;
    jc["least_squares"] = errorsJson(c.least_squares);
    jc["formulas_eq_5_4_to_5_10"] = c.formulas ? errorsJson(*c.formulas) : ordered_json();
    jc["model_residual_xy_um"] = c.model_residual_xy_um;
    jc["model_residual_z_um"] = c.model_residual_z_um;
    for (const auto& b : c.budgets) {
      ordered_json jb;
      jb["quantity"] = b.quantity;
      jb["unit"] = b.unit;
      jb["value"] = b.value;
      jb["u_c"] = b.u_c;
      jb["nu_eff"] = finiteOrNull(b.nu_eff);
      jb["k"] = b.k;
      jb["U"] = b.U;
      for (const auto& ct : b.contributions)
        jb["contributions"].push_back({{"input", ct.input},
                                       {"type", std::string(1, ct.type)},
                                       {"distribution", ct.distribution},
                                       {"basis", ct.basis},
                                       {"u", ct.u}});
      jc["budgets"].push_back(jb);
    }
    for (const auto& s : c.spheres) {
      ordered_json js;
      js["position"] = s.position;
      js["points"] = s.points;
      js["centre_used"] = s.use_free_radius ? "free_radius" : "known_radius";
      js["centre_mm"] = vec(s.centre_mm());
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

}  // namespace probeloop::evaluate
