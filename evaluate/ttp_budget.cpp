// The thermal test piece's budgets (GUM; contract in thermal_test_piece.hpp, every term with its
// derivation in docs/thermal-test-piece-evaluation.md): the scatter per point and the pooled type
// A scatter, the budget of each value (point scatter, resolution, machine repeatability,
// temperature, datum alignment) and that of the Eq. 7.10 temperature.
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "evaluate/ttp_detail.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::evaluate::ttp {

// Scatter per point.
void setPointScatter(std::vector<Pt>& pts, const parts::PlanManifest& m, TtpRoute route, double sigma_spec_om) {
  for (auto& p : pts) {
    if (route == TtpRoute::Cmm) {
      const double L = p.part_mm.norm();
      const double mpe = m.ttp.cmm.mpe_constant_um + (m.ttp.cmm.mpe_length_mm > 0 ? L / m.ttp.cmm.mpe_length_mm : 0.0);
      p.sigma_b_mm = mpe / 2 * 1e-3;
    } else {
      p.sigma_b_mm = sigma_spec_om;
      p.sigma_res_mm = m.coordinate_resolution_mm / std::sqrt(12.0);
    }
  }
}

// Type A: pooled residual of the measurement-feature fits.
TtpScatter pooledScatter(const std::map<std::string, PlaneModel>& planes, const std::vector<Pt>& pts, double sigma_spec_om,
                         bool predicted) {
  TtpScatter scatter;
  double ssr = 0, dof = 0, sb2 = 0;
  int nb = 0;
  for (const auto& [id, p] : planes) {
    ssr += p.ssr_mm2;
    dof += p.dof;
    for (int i : p.pts) sb2 += std::pow(pts[static_cast<std::size_t>(i)].sigma_b_mm, 2), ++nb;
  }
  scatter.type_b_sigma_mm = nb ? std::sqrt(sb2 / nb) : sigma_spec_om;
  if (dof > 0 && !predicted) {
    scatter.type_a_sigma_mm = std::sqrt(ssr / dof);
    scatter.type_a_dof = dof;
  }
  scatter.type_a_used = scatter.type_a_dof > 0 && scatter.type_a_sigma_mm > scatter.type_b_sigma_mm;
  return scatter;
}

std::string alphaBasis(const parts::PlanManifest& m) {
  return "alpha = " + num(m.material_alpha_um_per_m_K) + " um/(m K) (part.alpha_um_per_m_K, the blank's material)";
}

uncertainty::Budget valueBudget(const ValueSpec& v, const BudgetContext& ctx) {
  const auto& m = *ctx.m;
  const auto& pts = *ctx.pts;
  std::vector<Contribution> cs;
  auto add = [&](std::string input, char type, std::string dist, std::string basis, double u, double dof = kInf) {
    cs.push_back({std::move(input), type, std::move(dist), std::move(basis), u, dof});
  };
  // Per-point gradient (value unit per mm of normal displacement), per-feature shift gradient.
  std::map<int, double> g;
  std::map<const TtpFeatureResult*, double> shift;
  Vector6d G = Vector6d::Zero();
  for (const auto& pr : v.pairs)
    for (int side = 0; side < 2; ++side) {
      const FQ& q = side == 0 ? *pr.at_i : *pr.at_0;
      const double w = (side == 0 ? pr.w : -pr.w) * v.unit_factor;
      for (std::size_t j = 0; j < q.pts.size(); ++j) g[q.pts[j]] += w * q.s[j];
      shift[q.feature] += w * q.shift;
      G += w * q.frame;
    }
  double sb2 = 0, sum_g2 = 0, sres2 = 0;
  for (const auto& [i, gi] : g) {
    const auto& p = pts[static_cast<std::size_t>(i)];
    sb2 += std::pow(p.sigma_b_mm * gi, 2);
    sres2 += std::pow(p.sigma_res_mm * gi, 2);
    sum_g2 += gi * gi;
  }
  const auto& sc = ctx.scatter;
  const bool cmm = ctx.route == TtpRoute::Cmm;
  const std::string both = ", this and the reference cycle";
  const std::string spec_name = ctx.stated ? "CMM point scatter from the stated features"
                                : cmm       ? "CMM probing error (specification)"
                                            : "probe repeatability (specification)";
  const std::string spec_basis =
      ctx.stated
          ? std::string(sc.type_a_used ? "the stated forms of the Z paths and facets pooled (form / (d2(n) sqrt((n - 3)/n)) per "
                                         "feature): s = " + num(sc.type_a_sigma_mm * 1e3) + " um, nu = " + num(sc.type_a_dof) +
                                         ", larger than the specification MPE(L)/2"
                                       : "MPE(L)/2 per point (thermal_test_piece.cmm, MPE = " + num(m.ttp.cmm.mpe_constant_um) + " um" +
                                         (m.ttp.cmm.mpe_length_mm > 0 ? " + L/" + num(m.ttp.cmm.mpe_length_mm) : std::string()) + ")" +
                                         (sc.type_a_dof > 0 ? "; the stated forms pooled give s = " + num(sc.type_a_sigma_mm * 1e3) +
                                                                  " um (nu = " + num(sc.type_a_dof) + "), not larger"
                                                            : "; no form stated")) +
                "; times sqrt(n_planned / n_stated) per feature, or the sigma a stated u of the location implies where larger "
                "(evaluation.json stated_features); the plan's points placed on the stated features, through each plane fit's "
                "(J^T J)^-1"
      : cmm ? "MPE = " + num(m.ttp.cmm.mpe_constant_um) + " um" +
                (m.ttp.cmm.mpe_length_mm > 0 ? " + L/" + num(m.ttp.cmm.mpe_length_mm) : std::string()) +
                " (thermal_test_piece.cmm; seed 004 L2145), sigma = MPE(L)/2 per point, L = distance from the origin; "
                "through each plane fit's (J^T J)^-1"
          : "probe.repeatability_2sigma = " + num(m.probe_repeatability_2sigma_um) +
                " um: sigma = " + num(m.probe_repeatability_2sigma_um / 2) + " um per point; through each plane fit's (J^T J)^-1";
  const std::string pooled = "pooled residual of the Z-path and facet plane fits: s = " + num(sc.type_a_sigma_mm * 1e3) +
                             " um, nu = " + num(sc.type_a_dof);
  if (ctx.stated) {
    add(spec_name + both, sc.type_a_used ? 'A' : 'B', "normal", spec_basis, std::sqrt(sb2), sc.type_a_used ? sc.type_a_dof : kInf);
    add("point scatter (type A)" + both, 'A', "normal", "needs the points: the file states the features only (their forms enter the line above)", 0);
  } else if (sc.type_a_used) {
    add("point scatter (type A)" + both, 'A', "normal", pooled, sc.type_a_sigma_mm * std::sqrt(sum_g2), sc.type_a_dof);
    add(spec_name + both, 'B', "normal", spec_basis + "; not added: the type A estimate of the same scatter is larger", 0);
  } else {
    add(spec_name + both, 'B', "normal", spec_basis, std::sqrt(sb2));
    if (ctx.predicted)
      add("point scatter (type A)" + both, 'A', "normal", "needs measured points (not predicted)", 0);
    else if (sc.type_a_dof > 0)
      add("point scatter (type A)" + both, 'A', "normal", pooled + "; not added: the specification is larger", 0, sc.type_a_dof);
  }
  if (ctx.route == TtpRoute::OnMachine) {
    const double q = m.coordinate_resolution_mm;
    add("coordinate resolution" + both, 'B', "rectangular",
        "q = " + num(q * 1e3) + " um per coordinate (machine.coordinate_resolution), q/sqrt(12) along each point's normal",
        std::sqrt(sres2));
    const double rep = m.ttp.on_machine_repeatability_um / 2 * 1e-3;
    double v2 = 0;
    for (const auto& [f, s] : shift) v2 += s * s;
    add("machine repeatability" + both, 'B', "normal",
        "thermal_test_piece.on_machine.repeatability = " + num(m.ttp.on_machine_repeatability_um) +
            " um (seed 004 L2145: added to the probe's), read as 2 sigma; one rigid shift along the normal per feature "
            "measurement",
        rep * std::sqrt(v2));
  } else {
    add("coordinate resolution" + both, 'B', "rectangular", "part of the CMM's MPE (not added again)", 0);
  }
  // Temperature of the part.
  const double alpha = m.material_alpha_um_per_m_K;
  if (v.angle) {
    add("part temperature", 'B', "rectangular", "a uniform temperature changes no angle", 0);
  } else if (!std::isfinite(alpha)) {
    add("part temperature", 'B', "rectangular", "not stated: set blank.material.alpha_um_per_m_K in the part file", 0);
  } else if (cmm) {
    const double dT = m.ttp.cmm.temperature_half_width_K;
    if (ctx.predicted)
      add("part temperature in the CMM room (Eq. 7.6)", 'B', "rectangular",
          "U_dT = alpha dT |E| (seed 004 Eq. 7.6) read as a rectangular half-width, " + alphaBasis(m) + ", dT within +-" +
              num(dT) + " K: scales with the measured value",
          0);
    else
      add("part temperature in the CMM room (Eq. 7.6)", 'B', "rectangular",
          "U_dT = alpha dT |E| (seed 004 Eq. 7.6, a 'measurement deviation assessment'), read as the half-width of a "
          "rectangular distribution (our interpretation): u = U_dT / sqrt(3); " + alphaBasis(m) + ", dT within +-" + num(dT) +
              " K (thermal_test_piece.cmm.temperature_half_width; seed 004 L2145)",
          std::fabs(parts::measurementDeviationEq76_um(alpha, dT, v.value)) / std::sqrt(3.0));
  } else {
    const double dT = m.ttp.on_machine_temperature_change_K;
    double v2 = 0;
    for (const auto& pr : v.pairs) {
      const double L = (pr.at_i->length_mm + pr.at_0->length_mm) / 2;
      v2 += std::pow(pr.w * v.unit_factor * alpha * 1e-6 * dT * L, 2) / 3.0;
    }
    add("part temperature change between compared features", 'B', "rectangular",
        "alpha dT d per compared pair (feature of cycle i against its reference), " + alphaBasis(m) +
            ", dT within +-" + num(dT) + " K (thermal_test_piece.on_machine.temperature_change), independent pairs",
        std::sqrt(v2));
  }
  // Datum frame.
  double a2 = 0;
  for (const auto& [i, dxi] : ctx.datum_sens) {
    const auto& p = pts[static_cast<std::size_t>(i)];
    const double sigma = sc.type_a_used && !ctx.stated ? sc.type_a_sigma_mm : p.sigma_b_mm;
    const double gi = G.dot(dxi);
    a2 += (sigma * sigma + p.sigma_res_mm * p.sigma_res_mm) * gi * gi;
  }
  add("datum alignment (TOP, FLANK_P, FLANK_N, CYL)", sc.type_a_used ? 'A' : 'B', "normal",
      std::string("the datum points' scatter") + (ctx.route == TtpRoute::OnMachine ? " and resolution" : "") +
          " through the datum frame (origin, axes) and the sensitivities of the value to it; facets of different cycles "
          "have different normals, Z paths at different y see the tilt",
      std::sqrt(a2), sc.type_a_used ? sc.type_a_dof : kInf);
  return uncertainty::combine(v.quantity, v.unit, v.value, cs, ctx.k);
}

// Eq. 7.10 with its budget from the budget of E_TTP in the radial form (Eq. 7.9).
uncertainty::Budget temperatureBudget(const parts::PlanManifest& m, const uncertainty::Budget& ettp_7_9, double k,
                                      bool predicted) {
  const double alpha = m.ttp.eq_7_10_alpha_um_per_m_K, R = m.ttp.eq_7_10_radius_mm;
  const double aR = alpha * R * 1e-3;  // um per K
  const double dT = -parts::temperatureEquivalentEq710_K(ettp_7_9.value, alpha, R);  // seed 004 Eq. 7.10, docs §4 signs
  std::vector<Contribution> cs;
  for (const auto& c : ettp_7_9.contributions) {
    Contribution x = c;
    x.u = c.u / aR;
    x.basis = c.basis + " (through E_TTP,7.9 / (alpha R))";
    cs.push_back(x);
  }
  const double ua = m.ttp.alpha_u_um_per_m_K;
  cs.push_back({"alpha of Eq. 7.10", 'B', "normal",
                "u(alpha) = " + num(ua) + " um/(m K) (thermal_test_piece.evaluation.alpha_u_um_per_m_K), alpha = " +
                    num(alpha) + " um/(m K) (seed 004 L2177): |dT| u(alpha) / alpha" +
                    (predicted ? ": scales with the measured value" : ""),
                predicted ? 0.0 : std::fabs(dT) * ua / alpha, kInf});
  cs.push_back({"R of Eq. 7.10", 'B', "normal",
                "not stated: R = " + num(R) + " mm is the nominal facet apothem (seed 004 L2177); no uncertainty given", 0, kInf});
  return uncertainty::combine("dT_K", "K", dT, cs, k);
}

uncertainty::Budget zeroBudget(const std::string& q, const std::string& unit, double k) {
  return uncertainty::combine(q, unit, 0.0, {}, k);
}

}  // namespace probeloop::evaluate::ttp
