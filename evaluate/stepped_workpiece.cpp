#include "evaluate/stepped_workpiece.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "evaluate/budget_json.hpp"
#include "evaluate/sw_features.hpp"
#include "geometry/fit.hpp"
#include "uncertainty/gum.hpp"
#include "parts/sw_compensation.hpp"

namespace probeloop::evaluate {

using Eigen::Vector3d;
using uncertainty::Budget;
using uncertainty::Contribution;

namespace {

constexpr double kSqrt3 = 1.7320508075688772;
// On the machine the part's temperature is not measured: within 20 C +- this (our assumption,
// docs/stepped-workpiece.md §6; the thesis's hall is not stated).
constexpr double kMachinePartHalfWidthK = 1.0;

std::string stepId(int k, const char* face) { return "S" + std::to_string(k) + "_" + face; }

const SwPlane& plane(const SwSourceGeometry& g, const std::string& id) {
  for (const auto& p : g.planes)
    if (p.id == id) return p;
  throw InputError(g.file, 0, "feature " + id + ": no points measured (the manifest plans it)");
}

// The plane's coordinate along axis a (0 x, 1 y, 2 z) at the other two coordinates of q.
double onPlane(const SwPlane& p, int a, const Vector3d& q, const std::string& file) {
  if (!(std::fabs(p.normal(a)) > 0.5))
    throw GeometryError(file + ": feature " + p.id + ": its plane is not square to axis " + "xyz"[a] +
                        " (normal " + formatNumber(p.normal.x(), 4) + ", " + formatNumber(p.normal.y(), 4) + ", " +
                        formatNumber(p.normal.z(), 4) + ")");
  double s = 0;
  for (int i = 0; i < 3; ++i)
    if (i != a) s += p.normal(i) * (q(i) - p.point_mm(i));
  return p.point_mm(a) - s / p.normal(a);
}

double slope(const SwPlane& p, int along, int over) { return -p.normal(over) / p.normal(along); }

Contribution contribution(std::string input, char type, std::string dist, std::string basis, double u,
                          double dof = std::numeric_limits<double>::infinity()) {
  Contribution c;
  c.input = std::move(input);
  c.type = type;
  c.distribution = std::move(dist);
  c.basis = std::move(basis);
  c.u = u;
  c.dof = dof;
  return c;
}

// The CMM term of a width or depth from stated planes (evaluate/sw_features.hpp): type A with the
// form's n - 3 dof when a plane's sigma came from its form, else type B (the MPE, a stated u).
Contribution statedPlanes(const SwSourceGeometry& g, const std::string& id1, const std::string& id2, double u) {
  double dof = std::numeric_limits<double>::infinity();
  for (const SwPlane* p : {&plane(g, id1), &plane(g, id2)})
    if (!p->slope_u_from_spec) dof = std::min(dof, p->dof());
  return contribution("CMM planes as stated", std::isfinite(dof) ? 'A' : 'B', "normal", g.stated_basis, u, dof);
}

}  // namespace

std::vector<SwPlane> swPlanes(const parts::PlanManifest& m, const TtpPoints& pts, const std::function<double(double)>& point_u_um) {
  std::vector<SwPlane> planes;
  // Repeated touches of one planned point (step 3's walls, L769) are averaged: the fit takes
  // each place once (points of a feature closer than 0.05 mm are one place; planned points are
  // millimetres apart).
  std::map<std::string, std::vector<std::pair<Vector3d, int>>> sums;
  for (const auto& p : pts.points) {
    auto& v = sums[p.feature];
    bool merged = false;
    for (auto& [s, n] : v)
      if ((s / n - p.p_mm).norm() < 0.05) {
        s += p.p_mm;
        ++n;
        merged = true;
        break;
      }
    if (!merged) v.push_back({p.p_mm, 1});
  }
  std::map<std::string, geometry::Points3> by_feature;
  for (const auto& [f, v] : sums)
    for (const auto& [s, n] : v) by_feature[f].push_back(s / n);
  for (const auto& f : m.features) {
    const auto& nf = f.nominal;
    if (nf.kind != "plane") continue;
    const auto it = by_feature.find(nf.id);
    if (it == by_feature.end()) continue;
    if (it->second.size() < 3)
      throw InputError(pts.file, 0, "feature " + nf.id + ": " + std::to_string(it->second.size()) +
                                        " points, a plane needs at least 3");
    SwPlane p;
    p.id = nf.id;
    p.role = nf.role;
    p.points = static_cast<int>(it->second.size());
    try {
      const auto fit = geometry::fitElement(geometry::ElementKind::Plane, it->second, {});
      p.point_mm = fit.fit.element.position_mm;
      p.normal = fit.fit.element.direction.normalized();
    } catch (const std::exception& e) {
      throw InputError(pts.file, 0, "feature " + nf.id + ": no plane through its points: " + e.what());
    }
    if (p.normal.dot(nf.direction) < 0) p.normal = -p.normal;
    double ss = 0;
    for (const auto& q : it->second) ss += std::pow(p.normal.dot(q - p.point_mm), 2);
    p.rms_um = std::sqrt(ss / std::max(1, p.points - 3)) * 1e3;  // s of the residuals (3 parameters)
    {
      int a = 0;
      nf.direction.cwiseAbs().maxCoeff(&a);
      const int i = (a + 1) % 3, j = (a + 2) % 3;
      double mi = 0, mj = 0;
      for (const auto& q : it->second) mi += q(i), mj += q(j);
      mi /= p.points;
      mj /= p.points;
      Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
      for (const auto& q : it->second) {
        const Eigen::Vector2d d(q(i) - mi, q(j) - mj);
        M += d * d.transpose();
      }
      double u_pt = p.rms_um;
      if (point_u_um) {
        Vector3d c = Vector3d::Zero();
        for (const auto& q : it->second) c += q;
        const double spec = point_u_um((c / p.points).norm());
        if (spec > u_pt) u_pt = spec, p.slope_u_from_spec = true;
      }
      if (std::fabs(M.determinant()) > 1e-12 * std::max(1.0, M.squaredNorm())) {
        const Eigen::Matrix2d C = M.inverse();
        p.slope_lever[i] = std::sqrt(C(0, 0));
        p.slope_lever[j] = std::sqrt(C(1, 1));
        p.u_slope[i] = u_pt * 1e-3 * p.slope_lever[i];
        p.u_slope[j] = u_pt * 1e-3 * p.slope_lever[j];
      }
    }
    planes.push_back(p);
  }
  return planes;
}

SwSourceGeometry swGeometryFromPlanes(const parts::PlanManifest& m, std::vector<SwPlane> planes, const std::string& file,
                                      const std::string& route) {
  SwSourceGeometry g;
  g.file = file;
  g.route = route;
  g.planes = std::move(planes);
  const SwPlane& top = plane(g, "TOP");
  for (std::size_t i = 0; i < m.sw.sizes_mm.size(); ++i) {
    const int k = static_cast<int>(i) + 1;
    SwStepGeometry s;
    s.step = k;
    s.size_mm = m.sw.sizes_mm[i];
    const auto* fxp = m.feature(stepId(k, "XP"));
    const auto* ffl = m.feature(stepId(k, "F"));
    if (!fxp || !ffl) throw InputError(m.file, 0, "features: step " + std::to_string(k) + " has no walls or floor");
    s.depth_nominal_mm = -ffl->nominal.point_mm.z();
    const SwPlane &xp = plane(g, stepId(k, "XP")), &xn = plane(g, stepId(k, "XN")), &yp = plane(g, stepId(k, "YP")),
                  &yn = plane(g, stepId(k, "YN")), &fl = plane(g, stepId(k, "F"));
    // The step's centre line at its walls' mid-height.
    const Vector3d c(0.5 * (xp.point_mm.x() + xn.point_mm.x()), 0.5 * (yp.point_mm.y() + yn.point_mm.y()),
                     fxp->nominal.point_mm.z());
    s.width_x_mm = onPlane(xp, 0, c, g.file) - onPlane(xn, 0, c, g.file);
    s.width_y_mm = onPlane(yp, 1, c, g.file) - onPlane(yn, 1, c, g.file);
    s.u_wall_x_um = std::hypot(xp.rms_um / std::sqrt(xp.points), xn.rms_um / std::sqrt(xn.points));
    s.u_wall_y_um = std::hypot(yp.rms_um / std::sqrt(yp.points), yn.rms_um / std::sqrt(yn.points));
    // Both routes at the same place: the floor's nominal centre (the step's axis).
    const Vector3d fc = ffl->nominal.point_mm;
    s.depth_mm = onPlane(top, 2, fc, g.file) - onPlane(fl, 2, fc, g.file);
    s.u_depth_um = std::hypot(top.rms_um / std::sqrt(top.points), fl.rms_um / std::sqrt(fl.points));
    s.lean_x_urad = 0.5 * (slope(xp, 0, 2) + slope(xn, 0, 2)) * 1e6;
    s.lean_y_urad = 0.5 * (slope(yp, 1, 2) + slope(yn, 1, 2)) * 1e6;
    s.floor_slope_x_urad = slope(fl, 2, 0) * 1e6;
    s.floor_slope_y_urad = slope(fl, 2, 1) * 1e6;
    Vector3d nx = xp.normal - xn.normal, ny = yp.normal - yn.normal;
    nx.z() = 0;
    ny.z() = 0;
    s.oz_urad = -std::asin(nx.normalized().dot(ny.normalized())) * 1e6;
    s.u_lean_x_urad = 0.5 * std::hypot(xp.u_slope[2], xn.u_slope[2]) * 1e6;
    s.u_lean_y_urad = 0.5 * std::hypot(yp.u_slope[2], yn.u_slope[2]) * 1e6;
    s.u_floor_slope_x_urad = fl.u_slope[0] * 1e6;
    s.u_floor_slope_y_urad = fl.u_slope[1] * 1e6;
    s.u_oz_urad = 0.5 * std::hypot(std::hypot(xp.u_slope[1], xn.u_slope[1]), std::hypot(yp.u_slope[0], yn.u_slope[0])) * 1e6;
    const auto k95 = [](std::initializer_list<const SwPlane*> ps) {
      double dof = 1 << 20;
      for (const auto* q : ps)
        if (!q->slope_u_from_spec) dof = std::min(dof, q->dof());
      return uncertainty::coverageFactor(0.95, dof);
    };
    s.U_lean_x_urad = k95({&xp, &xn}) * s.u_lean_x_urad;
    s.U_lean_y_urad = k95({&yp, &yn}) * s.u_lean_y_urad;
    s.U_floor_slope_x_urad = k95({&fl}) * s.u_floor_slope_x_urad;
    s.U_floor_slope_y_urad = k95({&fl}) * s.u_floor_slope_y_urad;
    s.U_oz_urad = k95({&xp, &xn, &yp, &yn}) * s.u_oz_urad;
    g.steps.push_back(s);
  }
  return g;
}

SwSourceGeometry steppedGeometry(const parts::PlanManifest& m, const TtpPoints& pts, const std::string& route,
                                 const std::function<double(double)>& point_u_um) {
  return swGeometryFromPlanes(m, swPlanes(m, pts, point_u_um), pts.file, route);
}

SwRepeatability probeRepeatability(const parts::PlanManifest& m, const TtpPoints& probe) {
  // (feature, point) -> nominal contact and approach
  std::map<std::pair<std::string, int>, const parts::ManifestPoint*> plan;
  for (const auto& p : m.points) plan[{p.feature, p.point}] = &p;
  // Groups of touches of one planned place (same feature, same nominal contact): their
  // positions along the approach; s pooled over the groups with sum (n_i - 1) degrees of freedom.
  struct Group {
    const parts::ManifestPoint* where;
    std::vector<double> along;
  };
  std::map<std::string, std::vector<Group>> groups;
  for (const auto& p : probe.points) {
    const auto it = plan.find({p.feature, p.point});
    if (it == plan.end()) continue;
    const double a = it->second->approach.normalized().dot(p.p_mm);
    auto& v = groups[p.feature];
    auto g = std::find_if(v.begin(), v.end(), [&](const Group& x) { return (x.where->contact_mm - it->second->contact_mm).norm() < 1e-6; });
    if (g == v.end()) v.push_back({it->second, {a}});
    else g->along.push_back(a);
  }
  SwRepeatability r;
  double ss = 0;
  for (const auto& [f, v] : groups)
    for (const auto& g : v) {
      if (g.along.size() < 2) continue;
      double mean = 0;
      for (double x : g.along) mean += x;
      mean /= static_cast<double>(g.along.size());
      for (double x : g.along) ss += (x - mean) * (x - mean);
      r.pairs += static_cast<int>(g.along.size()) - 1;
    }
  if (r.pairs > 0) r.s_um = std::sqrt(ss / r.pairs) * 1e3;
  return r;
}

namespace {
void requireSteppedPlan(const parts::PlanManifest& m) {
  if (parts::parsePieceKind(m.kind) != parts::PieceKind::SteppedWorkpiece)
    throw InputError(m.file, 0, "kind: '" + m.kind + "': the stepped-workpiece evaluation needs a stepped_workpiece plan");
}
}  // namespace

std::function<double(double)> swCmmPointU(const parts::PlanManifest& m) {
  const double mpe0 = m.sw.cmm.mpe_constant_um, mpeK = m.sw.cmm.mpe_length_mm;
  return [mpe0, mpeK](double L) { return (mpe0 + (mpeK > 0 ? L / mpeK : 0.0)) / kSqrt3; };
}

SwEvaluation evaluateSteppedWorkpiece(const parts::PlanManifest& m, const TtpPoints& cmm, const TtpPoints& probe) {
  requireSteppedPlan(m);
  return evaluateSteppedWorkpiece(m, steppedGeometry(m, cmm, "cmm", swCmmPointU(m)), probe);
}

SwEvaluation evaluateSteppedWorkpiece(const parts::PlanManifest& m, SwSourceGeometry cmm, const TtpPoints& probe) {
  requireSteppedPlan(m);
  SwEvaluation e;
  e.experiment = m.sw.experiment;
  e.transition = m.sw.transition;
  e.transition_feed_mm_per_min = m.sw.transition_feed_mm_per_min;
  e.applied = m.sw.compensation;
  const auto rep = probeRepeatability(m, probe);
  e.cmm = std::move(cmm);
  const double s_probe = rep.pairs >= 2 ? rep.s_um : m.probe_repeatability_2sigma_um / 2;
  e.probe = steppedGeometry(m, probe, "on_machine", [&](double) { return s_probe; });
  e.probe_repeat_pairs = rep.pairs;
  const bool type_a = rep.pairs >= 2;
  const double s_pt = type_a ? rep.s_um : m.probe_repeatability_2sigma_um / 2;
  const double dof_pt = type_a ? rep.pairs : std::numeric_limits<double>::infinity();
  e.probe_repeatability_um = s_pt;
  const std::string rep_basis =
      type_a ? std::to_string(rep.pairs) + " repeated points: s = " + formatNumber(s_pt, 3) + " um"
             : "no repeated points: the manifest's probe repeatability 2 sigma " + formatNumber(m.probe_repeatability_2sigma_um) + " um";
  const double alpha = m.material_alpha_um_per_m_K * 1e-3;  // um per mm per K
  const double dT_cmm = m.sw.cmm.temperature_half_width_K;
  auto mpe = [&](double L) { return m.sw.cmm.mpe_constant_um + (m.sw.cmm.mpe_length_mm > 0 ? L / m.sw.cmm.mpe_length_mm : 0.0); };
  const double d_probe = 2 * m.tip_radius_mm, d_tool = m.sw.tool_diameter_mm;
  auto count = [](const SwSourceGeometry& g, const std::string& id) { return plane(g, id).points; };

  if (e.probe.steps.empty() || e.cmm.steps.size() != e.probe.steps.size())
    throw InputError(m.file, 0, "stepped_workpiece.sizes_mm: no steps to evaluate");
  std::vector<std::array<Budget, 3>> pos;  // per step: x, y, z
  std::vector<std::array<double, 3>> u_own;  // per step: the part of u_c that is the step's own (not a common scale)
  std::vector<std::array<double, 3>> u_cmm(e.probe.steps.size());  // per step: the CMM's measurement alone
  for (std::size_t i = 0; i < e.probe.steps.size(); ++i) {
    const auto &c = e.cmm.steps[i], &p = e.probe.steps[i];
    const int k = c.step;
    std::array<Budget, 3> b;
    std::array<double, 3> own{};
    const char* axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      const double value = a == 0 ? c.width_x_error_um() - p.width_x_error_um()
                           : a == 1 ? c.width_y_error_um() - p.width_y_error_um()
                                    : c.depth_error_um() - p.depth_error_um();
      const double L = a < 2 ? c.size_mm : c.depth_nominal_mm;
      const int n1 = a == 0 ? count(e.probe, stepId(k, "XP")) : a == 1 ? count(e.probe, stepId(k, "YP")) : count(e.probe, "TOP");
      const int n2 = a == 0 ? count(e.probe, stepId(k, "XN")) : a == 1 ? count(e.probe, stepId(k, "YN")) : count(e.probe, stepId(k, "F"));
      const double u_fit_cmm = a == 0 ? c.u_wall_x_um : a == 1 ? c.u_wall_y_um : c.u_depth_um;
      const double u_rep = s_pt * std::sqrt(1.0 / n1 + 1.0 / n2);
      std::vector<Contribution> cs{
          contribution("probe repeatability", type_a ? 'A' : 'B', "normal", rep_basis, u_rep, dof_pt),
          contribution("CMM length measurement", 'B', "rectangular", "MPE " + formatNumber(mpe(L), 3) + " um at " + formatNumber(L) + " mm",
                       mpe(L) / kSqrt3),
          e.cmm.stated_basis.empty()
              ? contribution("CMM plane fits", 'A', "normal", "s of the residuals / sqrt(n) of both planes", u_fit_cmm,
                             std::max(1, count(e.cmm, a == 2 ? "TOP" : stepId(k, a == 0 ? "XP" : "YP")) - 3))
              : statedPlanes(e.cmm, a == 2 ? "TOP" : stepId(k, a == 0 ? "XP" : "YP"),
                             a == 2 ? stepId(k, "F") : stepId(k, a == 0 ? "XN" : "YN"), u_fit_cmm),
          contribution("part temperature at the CMM", 'B', "rectangular",
                       "20 C +- " + formatNumber(dT_cmm) + " K, not corrected", alpha * L * dT_cmm / kSqrt3),
          contribution("part temperature on the machine", 'B', "rectangular",
                       "20 C +- " + formatNumber(kMachinePartHalfWidthK) + " K (not measured)", alpha * L * kMachinePartHalfWidthK / kSqrt3)};
      b[a] = uncertainty::combine(std::string("e_pos_") + axes[a] + "_um", "um", value, cs);
      u_cmm[i][static_cast<std::size_t>(a)] = std::hypot(mpe(L) / kSqrt3, u_fit_cmm, alpha * L * dT_cmm / kSqrt3);
      // The step's own part of u_c: repeatability, the CMM's planes and the MPE's constant.
      own[a] = std::sqrt(u_rep * u_rep + u_fit_cmm * u_fit_cmm + std::pow(m.sw.cmm.mpe_constant_um / kSqrt3, 2));
    }
    pos.push_back(b);
    u_own.push_back(own);
  }
  // e_pos(L) = k L per axis over the probe centre's travel (the steps are bosses: the ball
  // touches each wall from outside, so its centre travels size + stylus d; the depth for Z),
  // weighted by the steps' own uncertainties (probe repeatability, the CMM's planes, the MPE's
  // constant); u(k) from the weights, scaled up by the Birge ratio when the steps scatter more
  // than that, plus the lines common to every step, which scale with L and so go into k whole:
  // the part's temperature at the CMM and on the machine and the MPE's length term.
  Budget* kb[3] = {&e.k_pos_x_um_per_mm, &e.k_pos_y_um_per_mm, &e.k_pos_z_um_per_mm};
  for (int a = 0; a < 3; ++a) {
    double swl2 = 0, swle = 0;
    std::vector<std::pair<double, double>> le;
    for (std::size_t i = 0; i < pos.size(); ++i) {
      const double L = a < 2 ? e.probe.steps[i].size_mm + d_probe : e.probe.steps[i].depth_nominal_mm;
      if (!(u_own[i][a] > 0))
        throw GeometryError(m.file + ": step " + std::to_string(i + 1) + ": e_pos has no uncertainty of its own (no probe "
                            "repeatability, no CMM specification): the steps cannot be weighted");
      const double w = 1.0 / std::pow(u_own[i][a], 2);
      swl2 += w * L * L;
      swle += w * L * pos[i][a].value;
      le.push_back({L, pos[i][a].value});
    }
    const double k = swle / swl2;
    double chi2 = 0;
    for (std::size_t i = 0; i < le.size(); ++i) chi2 += std::pow(le[i].second - k * le[i].first, 2) / std::pow(u_own[i][a], 2);
    const int dof = static_cast<int>(le.size()) - 1;
    const double birge = dof > 0 ? std::max(1.0, std::sqrt(chi2 / dof)) : 1.0;
    std::vector<Contribution> cs{
        contribution("e_pos of the steps", 'A', "normal",
                     "weighted line through 0 over " + std::to_string(le.size()) + " steps, Birge ratio " + formatNumber(birge, 3),
                     birge / std::sqrt(swl2), std::max(1, dof)),
        contribution("part temperature at the CMM (every step alike)", 'B', "rectangular",
                     "20 C +- " + formatNumber(dT_cmm) + " K, not corrected", alpha * dT_cmm / kSqrt3),
        contribution("part temperature on the machine (every step alike)", 'B', "rectangular",
                     "20 C +- " + formatNumber(kMachinePartHalfWidthK) + " K (not measured)", alpha * kMachinePartHalfWidthK / kSqrt3)};
    if (m.sw.cmm.mpe_length_mm > 0)
      cs.push_back(contribution("CMM MPE length term (every step alike)", 'B', "rectangular",
                                "L / " + formatNumber(m.sw.cmm.mpe_length_mm) + " um", 1.0 / m.sw.cmm.mpe_length_mm / kSqrt3));
    *kb[a] = uncertainty::combine(std::string("k_pos_") + "xyz"[a] + "_um_per_mm", "um/mm", k, cs);
  }
  for (std::size_t i = 0; i < e.probe.steps.size(); ++i) {
    const auto& p = e.probe.steps[i];
    const int k = p.step;
    SwStepSeparation s;
    s.step = k;
    if (i < m.sw.steps.size()) {
      s.feed_mm_per_min = m.sw.steps[i].feed_xy_mm_per_min;
      s.spindle_rpm = m.sw.steps[i].spindle_speed_rpm;
      s.temp_state_min = m.sw.steps[i].temp_state_min;
      s.cut_start_s = m.sw.steps[i].start_s;
      s.cut_end_s = m.sw.steps[i].end_s;
      s.cut_mid_s = m.sw.steps.front().start_s + 60.0 * s.temp_state_min;
    }
    // A compensated plan cut each wall `wall_um` inside and each floor `floor_um` higher on
    // purpose: the process and spindle errors are against what was commanded, and the
    // prediction (the physical error of the nominal path) adds the offsets back, so that
    // compensation.json always holds the whole offset from nominal.
    double applied[3] = {0, 0, 0};  // width x, width y, depth (um)
    if (i < m.sw.compensation.size()) {
      const auto& c = m.sw.compensation[i];
      applied[0] = c.wall_um[0] + c.wall_um[1];
      applied[1] = c.wall_um[2] + c.wall_um[3];
      applied[2] = c.floor_um;
    }
    s.travel_probe_mm = p.size_mm + d_probe;
    s.travel_tool_mm = p.size_mm + d_tool;
    for (int a = 0; a < 3; ++a) s.u_cmm_um[a] = u_cmm[i][static_cast<std::size_t>(a)];
    s.e_pos_x_um = pos[i][0];
    s.e_pos_y_um = pos[i][1];
    s.e_pos_z_um = pos[i][2];
    for (int a = 0; a < 2; ++a) {
      const double we = a == 0 ? p.width_x_error_um() : p.width_y_error_um();
      const Budget& kk = *kb[a];
      const double lever = d_tool - d_probe;  // e_pos over the tool's travel minus over the probe's
      const int n1 = count(e.probe, stepId(k, a == 0 ? "XP" : "YP")), n2 = count(e.probe, stepId(k, a == 0 ? "XN" : "YN"));
      std::vector<Contribution> cs{
          contribution("probe repeatability", type_a ? 'A' : 'B', "normal", rep_basis, s_pt * std::sqrt(1.0 / n1 + 1.0 / n2), dof_pt),
          contribution("e_pos slope k", 'A', "normal", "u(k) x (tool d - stylus d) = " + formatNumber(lever) + " mm", kk.u_c * lever,
                       kk.contributions.empty() ? 1 : kk.contributions.front().dof),
          contribution("part temperature on the machine", 'B', "rectangular",
                       "20 C +- " + formatNumber(kMachinePartHalfWidthK) + " K (not measured)", alpha * p.size_mm * kMachinePartHalfWidthK / kSqrt3)};
      (a == 0 ? s.e_proc_x_um : s.e_proc_y_um) =
          uncertainty::combine(std::string("e_proc_") + "xy"[a] + "_um", "um", we + applied[a] - kk.value * lever, cs);
    }
    const int nt = count(e.probe, "TOP"), nf = count(e.probe, stepId(k, "F"));
    s.e_splz_um = uncertainty::combine(
        "e_splz_um", "um", -(p.depth_error_um() + applied[2]),
        {contribution("probe repeatability", type_a ? 'A' : 'B', "normal", rep_basis, s_pt * std::sqrt(1.0 / nt + 1.0 / nf), dof_pt),
         contribution("e_pos_z over the depth", 'A', "normal", "u(k_z) x depth", e.k_pos_z_um_per_mm.u_c * p.depth_nominal_mm,
                      e.k_pos_z_um_per_mm.contributions.front().dof),
         contribution("part temperature on the machine", 'B', "rectangular",
                      "20 C +- " + formatNumber(kMachinePartHalfWidthK) + " K (not measured)",
                      alpha * p.depth_nominal_mm * kMachinePartHalfWidthK / kSqrt3)});
    // Prediction: the same quantities by routes whose contributions are independent.
    for (int a = 0; a < 3; ++a) {
      const double L = a < 2 ? p.size_mm + d_probe : p.depth_nominal_mm;
      const double probe_err = a == 0 ? p.width_x_error_um() : a == 1 ? p.width_y_error_um() : p.depth_error_um();
      const Budget& kk = *kb[a];
      const int n1 = count(e.probe, a == 0 ? stepId(k, "XP") : a == 1 ? stepId(k, "YP") : std::string("TOP"));
      const int n2 = count(e.probe, a == 0 ? stepId(k, "XN") : a == 1 ? stepId(k, "YN") : stepId(k, "F"));
      const double size = a < 2 ? p.size_mm : p.depth_nominal_mm;
      std::vector<Contribution> cs{
          contribution("probe repeatability", type_a ? 'A' : 'B', "normal", rep_basis, s_pt * std::sqrt(1.0 / n1 + 1.0 / n2), dof_pt),
          contribution("e_pos slope k", 'A', "normal", "u(k) x " + formatNumber(L) + " mm", kk.u_c * L,
                       kk.contributions.empty() ? 1 : kk.contributions.front().dof),
          contribution("part temperature on the machine", 'B', "rectangular",
                       "20 C +- " + formatNumber(kMachinePartHalfWidthK) + " K (not measured)", alpha * size * kMachinePartHalfWidthK / kSqrt3)};
      const char* q[3] = {"predicted_width_x_um", "predicted_width_y_um", "predicted_depth_um"};
      Budget& out = a == 0 ? s.predicted_width_x_um : a == 1 ? s.predicted_width_y_um : s.predicted_depth_um;
      out = uncertainty::combine(q[a], "um", probe_err + applied[a] + kk.value * L, cs);
    }
    e.steps.push_back(s);
  }
  e.notes.push_back("e_proc: the thermal position error of X and Y (Eq. 3.5/3.6) needs a campaign at constant feed "
                    "(W1, W6, W7); from one workpiece it is taken as 0 and e_proc holds it");
  e.notes.push_back("e_splz: the depth error of each floor below the top, from the probe (+ = the floor shallower: the tool "
                    "tip rose between the top's cut and the floor's); e_pos_z is removed by the probe route itself");
  e.notes.push_back("the part's temperature is not corrected on either route; its range is in every budget");
  return e;
}

void compareWithBefore(SwEvaluation& e, const parts::PlanManifest& m, const std::string& file) {
  if (m.sw.compensation.empty())
    throw InputError(m.file, 0, "--compare: this plan was not compensated (plan --compensate); nothing was promised to compare with");
  nlohmann::json b;
  try {
    b = nlohmann::json::parse(readFile(file, kJsonInput));
  } catch (const nlohmann::json::exception& x) {
    throw InputError(file, 0, std::string("not JSON: ") + x.what());
  }
  if (b.value("kind", "") != "stepped_workpiece" || !b.contains("cmm") || !b.at("cmm").contains("steps"))
    throw InputError(file, 0, "kind: expected the evaluation.json of a stepped workpiece (its CMM route)");
  if (b.value("experiment", "") != e.experiment)
    throw InputError(file, 0, "experiment: '" + b.value("experiment", "") + "', this part is " + e.experiment);
  const auto& bs = b.at("cmm").at("steps");
  if (bs.size() != e.cmm.steps.size() || m.sw.compensation.size() != e.cmm.steps.size())
    throw InputError(file, 0, "cmm.steps: " + std::to_string(bs.size()) + " steps, this part has " + std::to_string(e.cmm.steps.size()));
  // The offsets the earlier part was cut with (0 when it was not compensated).
  std::vector<parts::SwStepCompensation> before_applied(bs.size());
  if (b.contains("compensation_applied") && b.at("compensation_applied").is_array()) {
    const auto& ba = b.at("compensation_applied");
    if (ba.size() != bs.size()) throw InputError(file, 0, "compensation_applied: one entry per step expected");
    try {
      for (std::size_t i = 0; i < ba.size(); ++i) {
        for (int w = 0; w < 4; ++w)
          before_applied[i].wall_um[static_cast<std::size_t>(w)] = ba[i].at("wall_um").at(parts::kSwWalls[w]).get<double>();
        before_applied[i].floor_um = ba[i].at("floor_um").get<double>();
      }
    } catch (const nlohmann::json::exception& x) {
      throw InputError(file, 0, std::string("compensation_applied: expected wall_um {XP, XN, YP, YN} and floor_um per step (") + x.what() + ")");
    }
  }
  e.compared_with = file;
  for (std::size_t i = 0; i < bs.size(); ++i) {
    const auto& after = e.cmm.steps[i];
    parts::SwStepCompensation c = m.sw.compensation[i];
    for (int w = 0; w < 4; ++w) c.wall_um[static_cast<std::size_t>(w)] -= before_applied[i].wall_um[static_cast<std::size_t>(w)];
    c.floor_um -= before_applied[i].floor_um;
    const struct {
      const char* q;
      double after, promised, U;
    } rows[3] = {{"width_x", after.width_x_error_um(), c.wall_um[0] + c.wall_um[1], c.U_wall_um[0] + c.U_wall_um[1]},
                 {"width_y", after.width_y_error_um(), c.wall_um[2] + c.wall_um[3], c.U_wall_um[2] + c.U_wall_um[3]},
                 {"depth", after.depth_error_um(), c.floor_um, c.U_floor_um}};
    for (const auto& r : rows) {
      const std::string key = std::string(r.q) + "_error_um";
      if (!bs[i].contains(key) || !bs[i].at(key).is_number()) throw InputError(file, 0, "cmm.steps[" + std::to_string(i) + "]." + key + ": missing");
      SwBeforeAfter x;
      x.step = after.step;
      x.quantity = r.q;
      x.before_um = bs[i].at(key).get<double>();
      x.after_um = r.after;
      x.fall_um = x.before_um - x.after_um;
      x.promised_um = r.promised;
      x.U_promised_um = r.U;
      e.before_after.push_back(x);
    }
  }
}

namespace {
std::string num(double v, int d = 4) { return formatNumber(v, d); }
}  // namespace

std::string swErrorsCsv(const SwEvaluation& e) {
  std::ostringstream o;
  o << "# probeloop evaluate: stepped workpiece " << e.experiment << " (seed 000); components in um, U with k = 2\n";
  o << "step,feed_mm_per_min,spindle_rpm,temp_state_min,travel_probe_mm,travel_tool_mm";
  const char* names[] = {"e_pos_x_um", "e_pos_y_um", "e_pos_z_um", "e_proc_x_um", "e_proc_y_um", "e_splz_um"};
  for (const char* n : names) o << "," << n << ",u_" << n << ",U_" << n;
  o << "\n";
  for (const auto& s : e.steps) {
    o << s.step << "," << num(s.feed_mm_per_min, 1) << "," << num(s.spindle_rpm, 0) << "," << num(s.temp_state_min, 3) << ","
      << num(s.travel_probe_mm, 3) << "," << num(s.travel_tool_mm, 3);
    for (const Budget* b : {&s.e_pos_x_um, &s.e_pos_y_um, &s.e_pos_z_um, &s.e_proc_x_um, &s.e_proc_y_um, &s.e_splz_um})
      o << "," << num(b->value, 3) << "," << num(b->u_c, 3) << "," << num(b->U, 3);
    o << "\n";
  }
  return o.str();
}

std::string swEvaluationJson(const SwEvaluation& e) {
  nlohmann::ordered_json j;
  j["format"] = "probeloop-evaluation";
  j["kind"] = "stepped_workpiece";
  j["experiment"] = e.experiment;
  j["transition"] = e.transition;
  if (e.transition != "continuous") j["transition_feed_mm_per_min"] = e.transition_feed_mm_per_min;
  auto geom = [](const SwSourceGeometry& g) {
    nlohmann::ordered_json s{{"file", g.file}, {"route", g.route}};
    for (const auto& p : g.planes)
      s["planes"].push_back({{"id", p.id}, {"role", p.role}, {"points", p.points},
                             {"point_mm", {p.point_mm.x(), p.point_mm.y(), p.point_mm.z()}},
                             {"normal", {p.normal.x(), p.normal.y(), p.normal.z()}},
                             {"residual_s_um", p.stated ? nlohmann::ordered_json() : nlohmann::ordered_json(p.rms_um)}});
    for (const auto& t : g.steps)
      s["steps"].push_back({{"step", t.step}, {"size_mm", t.size_mm}, {"width_x_mm", t.width_x_mm}, {"width_y_mm", t.width_y_mm},
                            {"depth_nominal_mm", t.depth_nominal_mm}, {"depth_mm", t.depth_mm},
                            {"width_x_error_um", t.width_x_error_um()}, {"width_y_error_um", t.width_y_error_um()},
                            {"depth_error_um", t.depth_error_um()}, {"wall_tilt_x_urad", t.lean_x_urad},
                            {"wall_tilt_y_urad", t.lean_y_urad}, {"floor_slope_x_urad", t.floor_slope_x_urad},
                            {"floor_slope_y_urad", t.floor_slope_y_urad}, {"oz_urad", t.oz_urad},
                            {"u_wall_tilt_x_urad", t.u_lean_x_urad}, {"u_wall_tilt_y_urad", t.u_lean_y_urad},
                            {"u_floor_slope_x_urad", t.u_floor_slope_x_urad}, {"u_floor_slope_y_urad", t.u_floor_slope_y_urad},
                            {"u_oz_urad", t.u_oz_urad}, {"U_wall_tilt_x_urad", t.U_lean_x_urad},
                            {"U_wall_tilt_y_urad", t.U_lean_y_urad}, {"U_floor_slope_x_urad", t.U_floor_slope_x_urad},
                            {"U_floor_slope_y_urad", t.U_floor_slope_y_urad}, {"U_oz_urad", t.U_oz_urad}});
    return s;
  };
  j["cmm"] = geom(e.cmm);
  if (e.from_features) {  // the CMM planes as a file stated them (evaluate/sw_features.hpp)
    const auto& f = *e.from_features;
    nlohmann::ordered_json x{{"file", f.file}, {"format", f.format}, {"assigned_by", f.assigned_by}, {"basis", e.cmm.stated_basis}};
    for (const auto& p : f.planes)
      x["planes"].push_back({{"id", p.id}, {"row", p.row}, {"matched_by", p.matched_by}, {"n_stated", p.n_stated},
                             {"n_planned", p.n_planned}, {"form_um", std::isfinite(p.form_um) ? nlohmann::ordered_json(p.form_um) : nullptr},
                             {"sigma_um", p.sigma_um}, {"sigma_from", p.sigma_from}});
    x["unmatched"] = f.unmatched;
    x["rows_of_other_kinds_not_used"] = f.other_kinds;
    j["cmm"]["from_features"] = x;
  }
  j["on_machine"] = geom(e.probe);
  j["probe_repeatability_um"] = e.probe_repeatability_um;
  j["probe_repeat_pairs"] = e.probe_repeat_pairs;
  j["k_pos_x_um_per_mm"] = budgetJson(e.k_pos_x_um_per_mm);
  j["k_pos_y_um_per_mm"] = budgetJson(e.k_pos_y_um_per_mm);
  j["k_pos_z_um_per_mm"] = budgetJson(e.k_pos_z_um_per_mm);
  for (const auto& s : e.steps)
    j["separation"].push_back({{"step", s.step}, {"feed_mm_per_min", s.feed_mm_per_min}, {"spindle_rpm", s.spindle_rpm},
                               {"temp_state_min", s.temp_state_min}, {"cut_start_s", s.cut_start_s},
                               {"cut_end_s", s.cut_end_s}, {"cut_mid_s", s.cut_mid_s}, {"u_cmm_width_x_um", s.u_cmm_um[0]},
                               {"u_cmm_width_y_um", s.u_cmm_um[1]}, {"u_cmm_depth_um", s.u_cmm_um[2]}, {"travel_probe_mm", s.travel_probe_mm},
                               {"travel_tool_mm", s.travel_tool_mm}, {"e_pos_x_um", budgetJson(s.e_pos_x_um)},
                               {"e_pos_y_um", budgetJson(s.e_pos_y_um)}, {"e_pos_z_um", budgetJson(s.e_pos_z_um)},
                               {"e_proc_x_um", budgetJson(s.e_proc_x_um)}, {"e_proc_y_um", budgetJson(s.e_proc_y_um)},
                               {"e_splz_um", budgetJson(s.e_splz_um)},
                               {"predicted_width_x_um", budgetJson(s.predicted_width_x_um)},
                               {"predicted_width_y_um", budgetJson(s.predicted_width_y_um)},
                               {"predicted_depth_um", budgetJson(s.predicted_depth_um)}});
  if (!e.applied.empty()) {
    j["compensation_applied"] = nlohmann::ordered_json::array();
    for (const auto& c : e.applied) {
      nlohmann::ordered_json w;
      for (int i = 0; i < 4; ++i) w[parts::kSwWalls[i]] = c.wall_um[static_cast<std::size_t>(i)];
      j["compensation_applied"].push_back({{"step", c.step}, {"wall_um", w}, {"floor_um", c.floor_um}});
    }
  }
  if (!e.compared_with.empty()) {
    j["compared_with"] = e.compared_with;
    for (const auto& x : e.before_after)
      j["before_after"].push_back({{"step", x.step}, {"quantity", x.quantity}, {"before_um", x.before_um}, {"after_um", x.after_um},
                                   {"fall_um", x.fall_um}, {"promised_um", x.promised_um}, {"U_promised_um", x.U_promised_um}});
  }
  j["notes"] = e.notes;
  return j.dump(1) + "\n";
}

std::string swReport(const SwEvaluation& e) {
  std::ostringstream o;
  o << "# Stepped workpiece " << e.experiment << ": geometry and separated errors\n\n";
  o << "Seed 000 (Yaqoob 2017) Ch. 5 from one workpiece; docs/stepped-workpiece.md §6. U with k = 2.\n\n";
  o << "## Geometry\n\n| step | route | width X err um | width Y err um | depth err um | wall tilt X urad | wall tilt Y urad | "
       "floor slope X urad | floor slope Y urad | Oz urad |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto* g : {&e.cmm, &e.probe})
    for (const auto& s : g->steps)
      o << "| " << s.step << " | " << g->route << " | " << num(s.width_x_error_um(), 2) << " | " << num(s.width_y_error_um(), 2) << " | "
        << num(s.depth_error_um(), 2) << " | " << num(s.lean_x_urad, 1) << " | " << num(s.lean_y_urad, 1) << " | "
        << num(s.floor_slope_x_urad, 1) << " | " << num(s.floor_slope_y_urad, 1) << " | " << num(s.oz_urad, 1) << " |\n";
  o << "\n## Separated components (um)\n\n| step | feed mm/min | T min | e_pos_x | e_pos_y | e_pos_z | e_proc_x (2 walls) | "
       "e_proc_y (2 walls) | e_splz |\n|---|---|---|---|---|---|---|---|---|\n";
  auto bu = [](const Budget& b) { return num(b.value, 2) + " ± " + num(b.U, 2); };
  for (const auto& s : e.steps)
    o << "| " << s.step << " | " << num(s.feed_mm_per_min, 0) << " | " << num(s.temp_state_min, 1) << " | " << bu(s.e_pos_x_um) << " | "
      << bu(s.e_pos_y_um) << " | " << bu(s.e_pos_z_um) << " | " << bu(s.e_proc_x_um) << " | " << bu(s.e_proc_y_um) << " | "
      << bu(s.e_splz_um) << " |\n";
  o << "\nPosition error per mm of travel: k_x = " << bu(e.k_pos_x_um_per_mm) << ", k_y = " << bu(e.k_pos_y_um_per_mm)
    << ", k_z = " << bu(e.k_pos_z_um_per_mm) << " um/mm. Probe repeatability (1 sigma, one point): "
    << num(e.probe_repeatability_um, 3) << " um from " << e.probe_repeat_pairs << " repeated points.\n\n";
  for (const auto& n : e.notes) o << "- " << n << "\n";
  if (e.from_features) o << swFromFeaturesReport(*e.from_features);
  if (!e.compared_with.empty()) {
    o << "\n## Before and after the compensation (CMM, um)\n\nBefore: " << e.compared_with
      << ". The promised fall is the compensation the plan applied (U of the prediction, k = 2).\n\n"
         "| step | feature | before | after | fall | promised |\n|---|---|---|---|---|---|\n";
    for (const auto& x : e.before_after)
      o << "| " << x.step << " | " << x.quantity << " | " << num(x.before_um, 2) << " | " << num(x.after_um, 2) << " | "
        << num(x.fall_um, 2) << " | " << num(x.promised_um, 2) << " ± " << num(x.U_promised_um, 2) << " |\n";
  }
  return o.str();
}

std::string swCompensationFile(const SwEvaluation& e) {
  parts::SwCompensation c;
  c.experiment = e.experiment;
  c.basis = "probeloop evaluate: the CMM errors predicted for " + e.experiment +
            " cut again from the components separated here (docs/stepped-workpiece.md §7); each wall half its width's";
  for (const auto& s : e.steps) {
    parts::SwStepCompensation x;
    x.step = s.step;
    x.wall_um = {s.predicted_width_x_um.value / 2, s.predicted_width_x_um.value / 2, s.predicted_width_y_um.value / 2,
                 s.predicted_width_y_um.value / 2};
    x.U_wall_um = {s.predicted_width_x_um.U / 2, s.predicted_width_x_um.U / 2, s.predicted_width_y_um.U / 2,
                   s.predicted_width_y_um.U / 2};
    x.floor_um = s.predicted_depth_um.value;
    x.U_floor_um = s.predicted_depth_um.U;
    c.steps.push_back(x);
  }
  return parts::swCompensationJson(c);
}

std::string swStdout(const SwEvaluation& e, const std::string& out_dir) {
  std::ostringstream o;
  o << "Stepped workpiece " << e.experiment << ": " << e.cmm.planes.size() << " planes from the CMM, " << e.probe.planes.size()
    << " from the probe; probe repeatability " << num(e.probe_repeatability_um, 2) << " um (" << e.probe_repeat_pairs
    << " repeats)\n";
  o << "  e_pos per mm: X " << num(e.k_pos_x_um_per_mm.value, 4) << " +- " << num(e.k_pos_x_um_per_mm.U, 4) << ", Y "
    << num(e.k_pos_y_um_per_mm.value, 4) << " +- " << num(e.k_pos_y_um_per_mm.U, 4) << " um/mm (U, k = 2)\n";
  for (const auto& s : e.steps)
    o << "  step " << s.step << " (F " << num(s.feed_mm_per_min, 0) << ", T " << num(s.temp_state_min, 1) << " min): e_pos_x "
      << num(s.e_pos_x_um.value, 2) << ", e_proc_x " << num(s.e_proc_x_um.value, 2) << " +- " << num(s.e_proc_x_um.U, 2)
      << ", e_splz " << num(s.e_splz_um.value, 2) << " +- " << num(s.e_splz_um.U, 2) << " um\n";
  if (!e.compared_with.empty()) {
    double before = 0, after = 0;
    for (const auto& x : e.before_after) before += x.before_um * x.before_um, after += x.after_um * x.after_um;
    const double n = static_cast<double>(e.before_after.size());
    o << "  against " << e.compared_with << " (CMM): rms error of the widths and depths " << num(std::sqrt(before / n), 2)
      << " um before, " << num(std::sqrt(after / n), 2) << " um after the compensation\n";
    for (const auto& x : e.before_after)
      o << "    step " << x.step << " " << x.quantity << ": " << num(x.before_um, 2) << " -> " << num(x.after_um, 2) << " um, fell "
        << num(x.fall_um, 2) << ", promised " << num(x.promised_um, 2) << " +- " << num(x.U_promised_um, 2) << "\n";
  }
  o << "  wrote errors.csv, evaluation.json, report.md, compensation.json in " << out_dir << "\n";
  return o.str();
}

}  // namespace probeloop::evaluate
