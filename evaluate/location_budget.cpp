#include "evaluate/location_budget.hpp"

#include <cmath>
#include <cstdio>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "geometry/sphere_fit.hpp"

namespace probeloop::evaluate {

using uncertainty::Contribution;

namespace {

std::string num(double v) { return formatSignificant4(v); }

// Standard deviation of W_j . centres when every point has standard deviation sigma.
double throughFit(const Eigen::MatrixXd& W, int j, const CycleBudgetInput& c, double sigma_mm) {
  double v = 0;
  for (std::size_t k = 0; k < c.centre_cov_unscaled.size(); ++k) {
    const Eigen::RowVector3d w = W.block<1, 3>(j, 3 * static_cast<Eigen::Index>(k));
    v += (w * c.centre_cov_unscaled[k] * w.transpose())(0, 0);
  }
  return std::sqrt(std::max(v, 0.0)) * sigma_mm;
}

// Standard deviation of W_j . centres when each centre coordinate has its own u (independent).
double throughStated(const Eigen::MatrixXd& W, int j, const std::vector<Eigen::Vector3d>& u_mm) {
  double v = 0;
  for (std::size_t k = 0; k < u_mm.size(); ++k)
    for (int a = 0; a < 3; ++a) v += std::pow(W(j, 3 * static_cast<Eigen::Index>(k) + a) * u_mm[k](a), 2);
  return std::sqrt(v);
}

// Standard deviation of W_j . (t, t, ..., t) for a translation t with sigma per axis.
double throughTranslation(const Eigen::MatrixXd& W, int j, double sigma_mm) {
  double v = 0;
  for (int axis = 0; axis < 3; ++axis) {
    double s = 0;
    for (Eigen::Index k = 0; k < W.cols() / 3; ++k) s += W(j, 3 * k + axis);
    v += s * s;
  }
  return std::sqrt(v) * sigma_mm;
}

// Bias of error j when the errors drift at `rate` during a cycle whose positions are probed
// at tau_k from the cycle's mean time.
double driftBias(const LocationLeastSquares& ls, int j, const CycleBudgetInput& c) {
  const auto& A = ls.design();
  const auto& W = ls.sensitivity();
  Eigen::Map<const Eigen::Matrix<double, 7, 1>> r(c.rate_per_s.data());
  Eigen::VectorXd d = Eigen::VectorXd::Zero(A.rows());
  for (Eigen::Index k = 0; k < A.rows() / 3; ++k)
    d.segment<3>(3 * k) = A.middleRows(3 * k, 3) * r * c.tau_s[static_cast<std::size_t>(k)];
  return W.row(j).dot(d);
}

const char* kErrorNames[7] = {"EX0C", "EY0C", "EZ0T", "ER0T", "EA0C", "EB0C", "EC0C"};
const char* kUnits[7] = {"um", "um", "um", "um", "urad", "urad", "urad"};

}  // namespace

std::array<uncertainty::Budget, 7> locationErrorBudgets(const LocationLeastSquares& ls, const parts::PlanManifest& m,
                                                        const CycleBudgetInput& c, const CycleBudgetInput& ref,
                                                        const std::array<double, 7>& values, const PointScatter& ps,
                                                        double k, bool predicted) {
  const auto& W = ls.sensitivity();
  std::array<uncertainty::Budget, 7> out;
  const bool use_a = ps.type_a_sigma_mm > ps.type_b_sigma_mm && ps.type_a_dof > 0;
  const double sigma = use_a ? ps.type_a_sigma_mm : ps.type_b_sigma_mm;
  const std::string spec = "probe.repeatability_2sigma = " + num(m.probe_repeatability_2sigma_um) + " um";
  const std::string pooled = ps.type_a_dof > 0 ? "pooled residual of the free-radius sphere fits: s = " +
                                                     num(ps.type_a_sigma_mm * 1e3) + " um, nu = " + num(ps.type_a_dof)
                                               : "";
  const double q = m.coordinate_resolution_mm;
  const double atc = m.probe_tool_change_repeatability_2sigma_um / 2 * 1e-3;
  const bool features = !c.stated_u_mm.empty();
  for (int j = 0; j < 7; ++j) {
    std::vector<Contribution> cs;
    auto add = [&](std::string input, char type, std::string dist, std::string basis, double u,
                   double dof = std::numeric_limits<double>::infinity()) {
      cs.push_back({std::move(input), type, std::move(dist), std::move(basis), u, dof});
    };
    // Point scatter and resolution: the same sigma in this and the reference cycle, so one
    // contribution each (a type A s enters once with its dof, not twice).
    const double v_fit = std::pow(throughFit(W, j, c, 1.0), 2) + std::pow(throughFit(W, j, ref, 1.0), 2);
    const std::string both = ", this and the reference cycle";
    if (features) {
      // No points: each centre's stated u (or the fallback) instead of scatter and resolution.
      for (int which = 0; which < 2; ++which) {
        const auto& cc = which ? ref : c;
        add(std::string("sphere centres as the feature file states them") + (which ? ", reference cycle" : ", this cycle"), 'B',
            "normal", cc.stated_basis, throughStated(W, j, cc.stated_u_mm));
      }
      add("probe point scatter (type A)" + both, 'A', "normal",
          "not available: the feature file holds no points (no free-radius fit, no pooled residual to check the "
          "specification against)",
          0);
    } else if (use_a) {
      add("probe point scatter (type A)" + both, 'A', "normal", pooled, sigma * std::sqrt(v_fit), ps.type_a_dof);
      add("probe repeatability (specification)" + both, 'B', "normal",
          spec + "; not added: the type A estimate of the same scatter is larger", 0);
    } else {
      add("probe repeatability (specification)" + both, 'B', "normal", spec, sigma * std::sqrt(v_fit));
      if (ps.type_a_dof > 0)
        add("probe point scatter (type A)" + both, 'A', "normal", pooled + "; not added: the specification is larger", 0,
            ps.type_a_dof);
    }
    if (!features)
      add("coordinate resolution" + both, 'B', "rectangular", "q = " + num(q * 1e3) + " um per coordinate, q/sqrt(12)",
          q / std::sqrt(12.0) * std::sqrt(v_fit));
    for (int which = 0; which < 2; ++which) {
      const std::string cyc = which ? ", reference cycle" : ", this cycle";
      if (m.tool_change_each_cycle) {
        if (std::isfinite(atc))
          add("tool-change repeatability" + cyc, 'B', "normal",
              "probe.tool_change_repeatability_2sigma = " + num(m.probe_tool_change_repeatability_2sigma_um) +
                  " um per axis: moves all centres of the cycle together",
              throughTranslation(W, j, atc));
        else
          add("tool-change repeatability" + cyc, 'B', "normal",
              "not stated: set probe.tool_change_repeatability_2sigma in the machine file", 0);
      }
    }
    // Drift: E = W (c_i - c_ref), so the biases of the two cycles subtract (a steady drift
    // probed with the same timing cancels).
    if (predicted) {
      add("drift during the cycle", 'B', "rectangular", "needs measured cycles (not predicted)", 0);
    } else if (c.rate_known && ref.rate_known) {
      const double b = driftBias(ls, j, c) - driftBias(ls, j, ref);
      add("drift during the cycle", 'B', "rectangular",
          "error rates from the neighbouring cycles x each position's time in the cycle, this cycle minus the "
          "reference; half-width " + num(std::fabs(b)) + " " + kUnits[j],
          std::fabs(b) / std::sqrt(3.0));
    } else {
      add("drift during the cycle", 'B', "rectangular", "one complete cycle only: no rate to estimate it", 0);
    }
    if (features)
      for (int which = 0; which < 2; ++which) {
        const auto& cc = which ? ref : c;
        std::vector<Eigen::Vector3d> f;
        for (double x : cc.form_u_mm) f.push_back(Eigen::Vector3d::Constant(x));
        add(std::string("sphere form error") + (which ? ", reference cycle" : ", this cycle"), 'B', "rectangular", cc.form_basis,
            throughStated(W, j, f));
      }
    else
      add("sphere form error", 'B', "rectangular",
          "form " + num(m.sphere_form_error_um) + " um; cancels: the same sphere points are probed in every cycle", 0);
    if (j == 2) {
      const double h = m.sphere_centre_height_mm, a = m.artifact_alpha_um_per_m_K,
                   dT = m.artifact_temperature_change_half_width_K;
      if (std::isfinite(h) && std::isfinite(a) && std::isfinite(dT))
        add("artifact temperature and expansion", 'B', "rectangular",
            "alpha (h + R) dT: alpha = " + num(a) + " um/(m K), h + R = " + num(h + m.sphere_radius_mm) +
                " mm, dT within +-" + num(dT) + " K",
            a * 1e-3 * (h + m.sphere_radius_mm) * dT / std::sqrt(3.0));
      else
        add("artifact temperature and expansion", 'B', "rectangular",
            "not stated: set uncertainty.alpha_um_per_m_K and temperature_change_half_width in the artifact file", 0);
    }
    if (j >= 4) {
      const double uR = m.radius_from_axis_u_mm;
      if (predicted)
        add("uncertainty of d/2", 'B', "normal",
            std::isfinite(uR) ? "|E| u(d/2) / (d/2) = |E| x " + num(uR / m.radius_from_axis_mm) +
                                    ": scales with the measured value"
                              : std::string("not stated: set uncertainty.radius_from_c_axis_u in the artifact file"),
            0);
      else if (std::isfinite(uR))
        add("uncertainty of d/2", 'B', "normal",
            "|E| u(d/2) / (d/2), u(d/2) = " + num(uR) + " mm, d/2 = " + num(m.radius_from_axis_mm) + " mm",
            std::fabs(values[static_cast<std::size_t>(j)]) * uR / m.radius_from_axis_mm);
      else
        add("uncertainty of d/2", 'B', "normal", "not stated: set uncertainty.radius_from_c_axis_u in the artifact file", 0);
    }
    out[static_cast<std::size_t>(j)] = uncertainty::combine(kErrorNames[j], kUnits[j], values[static_cast<std::size_t>(j)], cs, k);
  }
  return out;
}

std::array<uncertainty::Budget, 3> sphereCentreBudgets(const parts::PlanManifest& m, const Eigen::Vector3d& centre,
                                                       const Eigen::Matrix3d& cov, const PointScatter& ps, double k) {
  std::array<uncertainty::Budget, 3> out;
  const bool use_a = ps.type_a_sigma_mm > ps.type_b_sigma_mm && ps.type_a_dof > 0;
  const char* axis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    const double s = std::sqrt(std::max(cov(a, a), 0.0)) * 1e3;  // um per mm of point sigma
    std::vector<Contribution> cs;
    if (use_a)
      cs.push_back({"probe point scatter (type A)", 'A', "normal", "pooled free-radius fit residual s = " + num(ps.type_a_sigma_mm * 1e3) + " um",
                    ps.type_a_sigma_mm * s, ps.type_a_dof});
    else
      cs.push_back({"probe repeatability (specification)", 'B', "normal", "probe.repeatability_2sigma = " + num(m.probe_repeatability_2sigma_um) + " um",
                    ps.type_b_sigma_mm * s, std::numeric_limits<double>::infinity()});
    cs.push_back({"coordinate resolution", 'B', "rectangular", "q = " + num(m.coordinate_resolution_mm * 1e3) + " um, q/sqrt(12)",
                  m.coordinate_resolution_mm / std::sqrt(12.0) * s, std::numeric_limits<double>::infinity()});
    cs.push_back({"sphere form error", 'B', "rectangular", "form " + num(m.sphere_form_error_um) + " um: points within +-form/2",
                  m.sphere_form_error_um * 1e-3 / 2 / std::sqrt(3.0) * s, std::numeric_limits<double>::infinity()});
    if (m.tool_change_each_cycle && std::isfinite(m.probe_tool_change_repeatability_2sigma_um))
      cs.push_back({"tool-change repeatability", 'B', "normal", "probe.tool_change_repeatability_2sigma = " + num(m.probe_tool_change_repeatability_2sigma_um) + " um",
                    m.probe_tool_change_repeatability_2sigma_um / 2, std::numeric_limits<double>::infinity()});
    out[static_cast<std::size_t>(a)] = uncertainty::combine(std::string("centre ") + axis[a], "um", centre(a) * 1e3, cs, k);
  }
  return out;
}

FeatureCentreU featureCentreU(const parts::PlanManifest& m, const FeatureActual& f, int position) {
  FeatureCentreU u;
  if (f.u_um) {
    u.u_mm = *f.u_um * 1e-3;
    u.stated = true;
  } else {
    const int per = m.pointsPerSphere();
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < per; ++i) pts.push_back(m.points[static_cast<std::size_t>((position - 1) * per + i)].contact_mm);
    geometry::SphereFitOptions fo;
    fo.fixed_radius_mm = m.sphere_radius_mm + m.tip_radius_mm;
    const Eigen::Matrix3d cov = geometry::fitSphere(pts, fo).covariance_unscaled.topLeftCorner<3, 3>();
    const double sigma = m.probe_repeatability_2sigma_um / 2 * 1e-3;
    const int n = f.n_points > 0 ? f.n_points : per;  // not stated: the planned points
    for (int a = 0; a < 3; ++a) u.u_mm(a) = sigma * std::sqrt(std::max(cov(a, a), 0.0) * per / n);
  }
  u.form_stated = std::isfinite(f.form_um);
  u.form_u_mm = (u.form_stated ? f.form_um : m.sphere_form_error_um) * 1e-3 / 2 / std::sqrt(3.0);
  return u;
}

std::array<uncertainty::Budget, 3> featureCentreBudgets(const parts::PlanManifest& m, const Eigen::Vector3d& centre,
                                                        const FeatureCentreU& u, double k) {
  std::array<uncertainty::Budget, 3> out;
  const char* axis[3] = {"x", "y", "z"};
  const double inf = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    std::vector<Contribution> cs;
    cs.push_back({"sphere centre as the feature file states it", 'B', "normal",
                  u.stated ? std::string("u_") + axis[a] + "_um of the file"
                           : "not stated: probe.repeatability_2sigma = " + num(m.probe_repeatability_2sigma_um) +
                                 " um through the planned points' fit, scaled to the file's n_points",
                  u.u_mm(a) * 1e3, inf});
    cs.push_back({"probe point scatter (type A)", 'A', "normal", "not available: the feature file holds no points", 0, inf});
    cs.push_back({"sphere form error", 'B', "rectangular",
                  (u.form_stated ? "form_um of the file" : "not stated in the file: the artifact's " + num(m.sphere_form_error_um) + " um") +
                      std::string(", +-form/2 on the centre"),
                  u.form_u_mm * 1e3, inf});
    if (m.tool_change_each_cycle && std::isfinite(m.probe_tool_change_repeatability_2sigma_um))
      cs.push_back({"tool-change repeatability", 'B', "normal", "probe.tool_change_repeatability_2sigma = " + num(m.probe_tool_change_repeatability_2sigma_um) + " um",
                    m.probe_tool_change_repeatability_2sigma_um / 2, inf});
    out[static_cast<std::size_t>(a)] = uncertainty::combine(std::string("centre ") + axis[a], "um", centre(a) * 1e3, cs, k);
  }
  return out;
}

std::array<uncertainty::Budget, 7> predictLocationErrorBudgets(const parts::PlanManifest& m, double k) {
  std::vector<double> angles;
  std::vector<int> positions;
  for (const auto& s : m.spheres)
    if (s.usedForCAxis()) angles.push_back(s.angle_deg), positions.push_back(s.position);
  const LocationLeastSquares ls(angles, m.radius_from_axis_mm);
  CycleBudgetInput planned;
  const int per = m.pointsPerSphere();
  double t_all = 0;
  int n_all = 0;
  for (const auto& p : m.points) t_all += p.time_in_cycle_s, ++n_all;
  const double t_mean = n_all ? t_all / n_all : 0;
  for (int pos : positions) {
    std::vector<Eigen::Vector3d> pts;
    double t = 0;
    for (int i = 0; i < per; ++i) {
      const auto& p = m.points[static_cast<std::size_t>((pos - 1) * per + i)];
      pts.push_back(p.contact_mm);
      t += p.time_in_cycle_s;
    }
    geometry::SphereFitOptions fo;
    fo.fixed_radius_mm = m.sphere_radius_mm + m.tip_radius_mm;
    const auto fit = geometry::fitSphere(pts, fo);
    planned.centre_cov_unscaled.push_back(fit.covariance_unscaled.topLeftCorner<3, 3>());
    planned.tau_s.push_back(t / per - t_mean);
  }
  PointScatter ps;
  ps.type_b_sigma_mm = m.probe_repeatability_2sigma_um / 2 * 1e-3;
  return locationErrorBudgets(ls, m, planned, planned, {}, ps, k, true);
}

double rootSumSquare(const Eigen::Vector3d& v) { return v.norm(); }

CentreRepeatability centreRepeatability(const std::vector<Eigen::Vector3d>& c) {
  if (c.size() < 2) throw GeometryError("centre repeatability needs >= 2 repeated measurements");
  CentreRepeatability r;
  r.n = static_cast<int>(c.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& x : c) mean += x;
  mean /= r.n;
  Eigen::Vector3d ss = Eigen::Vector3d::Zero();
  for (const auto& x : c) ss += (x - mean).cwiseAbs2();
  r.s_um = (ss / (r.n - 1)).cwiseSqrt() * 1e3;
  r.U_single_um = 2 * r.s_um;
  r.U_mean_um = r.U_single_um / std::sqrt(static_cast<double>(r.n));
  r.U_single_3d_um = rootSumSquare(r.U_single_um);
  r.U_mean_3d_um = rootSumSquare(r.U_mean_um);
  return r;
}

}  // namespace probeloop::evaluate
