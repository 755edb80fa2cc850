#include "evaluate/feature_fit.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "uncertainty/gum.hpp"

namespace probeloop::evaluate {
namespace {

using geometry::ElementKind;

std::vector<std::string> parameterNames(ElementKind k) {
  switch (k) {
    case ElementKind::Line2D: return {"x_mm", "y_mm", "dx", "dy"};
    case ElementKind::Line3D:
    case ElementKind::Plane: return {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz"};
    case ElementKind::Circle2D: return {"x_mm", "y_mm", "r_mm"};
    case ElementKind::Sphere: return {"x_mm", "y_mm", "z_mm", "r_mm"};
    case ElementKind::Circle3D:
    case ElementKind::Cylinder: return {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz", "r_mm"};
    case ElementKind::Cone: return {"x_mm", "y_mm", "z_mm", "nx", "ny", "nz", "r_mm", "half_angle_rad"};
  }
  return {};
}

double valueOf(const geometry::Element& e, const std::string& name) {
  if (name == "x_mm") return e.position_mm.x();
  if (name == "y_mm") return e.position_mm.y();
  if (name == "z_mm") return e.position_mm.z();
  if (name == "nx" || name == "dx") return e.direction.x();
  if (name == "ny" || name == "dy") return e.direction.y();
  if (name == "nz") return e.direction.z();
  if (name == "r_mm") return e.radius_mm;
  if (name == "half_angle_rad") return e.half_angle_rad;
  throw GeometryError("internal: unknown parameter name '" + name + "'");
}

std::string sideName(geometry::MaterialSide s) {
  return s == geometry::MaterialSide::Inside ? "inside" : "outside";
}

double um(double mm) { return mm * 1000.0; }

}  // namespace

FeatureFitReport fitFeature(const PointCloud& cloud, const FeatureFitRequest& req) {
  FeatureFitReport rep;
  rep.kind = req.kind;
  geometry::FitOptions opt = req.options;
  opt.tip.reset();  // applied below, once the material side is known
  rep.fit = geometry::fitElement(req.kind, cloud.points_mm, opt);
  const geometry::FitResult& f = rep.fit.fit;

  if (req.tip_radius_mm < 0.0 || !std::isfinite(req.tip_radius_mm))
    throw GeometryError("--tip-radius must be a finite number >= 0 mm");
  if (req.tip_radius_mm > 0.0) {
    const auto& e = rep.fit.tip_centre_element;
    if (!cloud.approach.empty()) {
      geometry::Points3 p, a;
      for (int i : rep.fit.kept) {
        p.push_back(cloud.points_mm[static_cast<size_t>(i)]);
        a.push_back(cloud.approach[static_cast<size_t>(i)]);
      }
      rep.side_used = geometry::materialSideFromApproach(e, p, a);
      rep.side_source = "approach directions nx,ny,nz in the file";
      if (req.side && *req.side != *rep.side_used)
        throw GeometryError("--material " + sideName(*req.side) +
                            " contradicts the approach directions in the file, which put the "
                            "material " + sideName(*rep.side_used));
    } else if (req.approach) {
      rep.side_used = geometry::materialSideFromApproach(e, *req.approach);
      rep.side_source = "--approach";
    } else if (req.side) {
      rep.side_used = *req.side;
      rep.side_source = "--material";
    } else {
      throw GeometryError(
          "tip compensation needs the material side: the file has no approach directions "
          "(nx,ny,nz); give --material inside (ball, shaft, boss) or outside (bore, hole), or "
          "--approach nx,ny,nz for a plane or line");
    }
    rep.fit.fit.element = geometry::compensateTipRadius(e, req.tip_radius_mm, *rep.side_used);
    rep.tip_radius_mm = req.tip_radius_mm;
  }

  // Residual statistics of the kept points.
  const auto& r = f.residuals_mm;
  if (!r.empty()) {
    const auto [mn, mx] = std::minmax_element(r.begin(), r.end());
    rep.residual_min_mm = *mn;
    rep.residual_max_mm = *mx;
  }
  rep.residual_s_mm = std::sqrt(f.residual_variance_mm2);

  // Parameters and their standard uncertainties.
  const geometry::Element& e = rep.fit.fit.element;
  const bool ls = f.method == geometry::FitMethod::LeastSquares;
  const bool has_cov = ls && !f.parameter_names.empty() &&
                       f.covariance_unscaled.rows() == static_cast<int>(f.parameter_names.size());
  double scale2 = 0.0;
  if (!ls) {
    rep.uncertainty_basis =
        "none: a " + std::string(geometry::methodName(f.method)) +
        " fit is not a linearisable estimator; use --method ls for parameter uncertainties";
  } else if (req.point_u_mm) {
    if (!(*req.point_u_mm > 0.0)) throw GeometryError("--point-u must be > 0 um");
    scale2 = *req.point_u_mm * *req.point_u_mm;
    rep.uncertainty_basis = "type B: point standard uncertainty " +
                            formatNumber(um(*req.point_u_mm), 4) +
                            " um propagated through (J^T J)^-1";
  } else if (f.dof > 0) {
    scale2 = f.residual_variance_mm2;
    rep.uncertainty_basis = "type A: residual standard deviation s = " +
                            formatNumber(um(rep.residual_s_mm), 4) + " um, nu = " +
                            std::to_string(f.dof) + ", propagated through (J^T J)^-1";
    // A type A u from a handful of residuals is itself barely known (its relative u is about
    // 1/sqrt(2 nu), GUM G.4.2 / E.4.3), and residuals at rounding level say nothing of the points.
    if (rep.residual_s_mm < kRoundingLevelMm)
      rep.warnings.push_back("the residuals are at rounding level (s = " + [&] {
        char b[32];
        std::snprintf(b, sizeof b, "%.2g", um(rep.residual_s_mm));
        return std::string(b);
      }() + " um): the points lie exactly on the element, so u from them means nothing; "
                             "give --point-u (the probing's standard uncertainty)");
    else if (f.dof < kMinDofForTypeA)
      rep.warnings.push_back("nu = " + std::to_string(f.dof) + ": the type A u rests on " + std::to_string(f.dof) +
                             " degree(s) of freedom (its own relative u is about " +
                             std::to_string(static_cast<int>(std::lround(100.0 / std::sqrt(2.0 * f.dof)))) + " %; the 95 % coverage factor is t = " +
                             formatNumber(uncertainty::coverageFactor(0.95, f.dof), 3) +
                             ", not 2); measure more points or give --point-u");
  } else {
    rep.uncertainty_basis =
        "none: exact fit (n = number of parameters) has no residual scatter; give --point-u";
  }
  const auto names = parameterNames(req.kind);
  std::optional<double> u_r;
  for (const auto& name : names) {
    ReportedParameter p{name, valueOf(e, name), std::nullopt};
    if (has_cov && scale2 > 0.0) {
      const auto it = std::find(f.parameter_names.begin(), f.parameter_names.end(), name);
      if (it != f.parameter_names.end()) {
        const int j = static_cast<int>(it - f.parameter_names.begin());
        p.u = std::sqrt(std::max(f.covariance_unscaled(j, j), 0.0) * scale2);
      }
    }
    if (name == "r_mm") u_r = p.u;
    if (name == "half_angle_rad") {
      ReportedParameter deg{"apex_angle_deg", 2.0 * p.value * 180.0 / M_PI, std::nullopt};
      if (p.u) deg.u = 2.0 * *p.u * 180.0 / M_PI;
      rep.parameters.push_back(p);
      rep.parameters.push_back(deg);
      continue;
    }
    rep.parameters.push_back(p);
    if (name == "r_mm")
      rep.parameters.push_back({"d_mm", 2.0 * e.radius_mm,
                                u_r ? std::optional<double>(2.0 * *u_r) : std::nullopt});
  }
  return rep;
}

std::string featureFitJson(const PointCloud& cloud, const FeatureFitReport& rep) {
  const auto& f = rep.fit.fit;
  nlohmann::ordered_json j;
  j["probeloop_fit"] = 1;
  j["element"] = std::string(geometry::elementName(rep.kind));
  j["method"] = std::string(geometry::methodName(f.method));
  j["input"] = {{"file", cloud.file},
                {"format", cloud.format},
                {"points", cloud.points_mm.size()},
                {"used", rep.fit.kept.size()}};
  nlohmann::ordered_json params = nlohmann::ordered_json::array();
  for (const auto& p : rep.parameters) {
    nlohmann::ordered_json q;
    q["name"] = p.name;
    q["value"] = p.value;
    q["u"] = p.u ? nlohmann::ordered_json(*p.u) : nlohmann::ordered_json(nullptr);
    params.push_back(q);
  }
  j["parameters"] = params;
  j["uncertainty_basis"] = rep.uncertainty_basis;
  j["dof"] = f.dof;
  j["form_um"] = um(f.form_mm);
  j["residuals_um"] = {{"rms", um(f.rms_mm)},
                       {"s", um(rep.residual_s_mm)},
                       {"min", um(rep.residual_min_mm)},
                       {"max", um(rep.residual_max_mm)}};
  if (rep.side_used) {
    j["tip_compensation"] = {{"tip_radius_mm", rep.tip_radius_mm},
                             {"material", sideName(*rep.side_used)},
                             {"side_from", rep.side_source}};
  } else {
    j["tip_compensation"] = nullptr;
  }
  nlohmann::ordered_json dropped = nlohmann::ordered_json::array();
  for (const auto& d : rep.fit.dropped)
    dropped.push_back({{"point", d.index + 1},
                       {"line", cloud.source_lines[static_cast<size_t>(d.index)]},
                       {"round", d.round},
                       {"residual_um", um(d.residual_mm)}});
  j["outliers"] = {{"rounds", rep.fit.outlier_rounds},
                   {"threshold_um", um(rep.fit.outlier_threshold_mm)},
                   {"dropped", dropped}};
  nlohmann::ordered_json support = nlohmann::ordered_json::array();
  for (int s : f.support_points) support.push_back(rep.fit.kept[static_cast<size_t>(s)] + 1);
  j["support_points"] = support;
  j["warnings"] = rep.warnings;
  return j.dump(2) + "\n";
}

std::string featureFitText(const PointCloud& cloud, const FeatureFitReport& rep) {
  const auto& f = rep.fit.fit;
  std::ostringstream o;
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s %s fit of %zu points from %s (%s)", 
                std::string(geometry::methodName(f.method)).c_str(),
                std::string(geometry::elementName(rep.kind)).c_str(), rep.fit.kept.size(),
                cloud.file.c_str(), cloud.format.c_str());
  o << buf << "\n";
  for (const auto& p : rep.parameters) {
    const bool angle = p.name.find("_deg") != std::string::npos || p.name.find("_rad") != std::string::npos;
    const bool unitless = p.name.size() == 2;  // nx, ny, nz, dx, dy
    if (p.u)
      std::snprintf(buf, sizeof buf, "  %-15s %16.6f  u = %.3g %s\n", p.name.c_str(), p.value,
                    unitless || angle ? *p.u : um(*p.u), unitless || angle ? "" : "um");
    else
      std::snprintf(buf, sizeof buf, "  %-15s %16.6f\n", p.name.c_str(), p.value);
    o << buf;
  }
  o << "  uncertainty: " << rep.uncertainty_basis << "\n";
  std::snprintf(buf, sizeof buf,
                "  form %.3f um; residuals rms %.3f um, s %.3f um, min %.3f um, max %.3f um (dof %d)\n",
                um(f.form_mm), um(f.rms_mm), um(rep.residual_s_mm), um(rep.residual_min_mm),
                um(rep.residual_max_mm), f.dof);
  o << buf;
  if (rep.side_used)
    o << "  tip compensation: material " << sideName(*rep.side_used) << " (from "
      << rep.side_source << ")\n";
  if (!rep.fit.dropped.empty() || rep.fit.outlier_rounds > 0) {
    std::snprintf(buf, sizeof buf, "  outliers: %zu dropped in %d round(s), last threshold %.3f um\n",
                  rep.fit.dropped.size(), rep.fit.outlier_rounds, um(rep.fit.outlier_threshold_mm));
    o << buf;
    for (const auto& d : rep.fit.dropped) {
      std::snprintf(buf, sizeof buf, "    point %d (line %d): residual %.3f um, round %d\n",
                    d.index + 1, cloud.source_lines[static_cast<size_t>(d.index)],
                    um(d.residual_mm), d.round);
      o << buf;
    }
  }
  if (!f.support_points.empty()) o << "  support points: " << f.support_points.size() << "\n";
  for (const auto& w : rep.warnings) o << "  warning: " << w << "\n";
  return o.str();
}

}  // namespace probeloop::evaluate
