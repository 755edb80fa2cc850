// The thermal test piece's feature fits (contract in thermal_test_piece.hpp,
// docs/thermal-test-piece-evaluation.md): one least-squares plane per Z path and facet in the
// part frame, checked against its nominal one, and the measured quantities of each (d of a
// facet, d_Z and beta of a Z path) with their sensitivities to the points and the frame.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "evaluate/ttp_detail.hpp"
#include "geometry/fit.hpp"
#include "geometry/minimum_zone.hpp"

namespace probeloop::evaluate::ttp {

namespace {

PlaneModel fitPlaneModel(const std::vector<Vector3d>& pts, const std::vector<int>& idx, const Vector3d& nominal_dir,
                         bool mz) {
  geometry::FitOptions fo;  // least squares
  const auto ef = geometry::fitElement(geometry::ElementKind::Plane, pts, fo);
  const auto& fr = ef.fit;
  PlaneModel p;
  p.c = fr.element.position_mm;
  p.n = fr.element.direction.normalized();
  p.C = fr.covariance_unscaled;
  if (p.n.dot(nominal_dir) < 0) {
    p.n = -p.n;
    Vector6d s;
    s << 1, 1, 1, -1, -1, -1;
    p.C = s.asDiagonal() * p.C * s.asDiagonal();
  }
  p.pts = idx;
  for (const auto& q : pts) {
    // Residual r = n.(q - c): dr/dc = -n, dr/dn = q - c. A displacement eps of the point along
    // n changes its residual by eps; least squares moves the parameters by -C J^T eps.
    Vector6d J;
    J << -p.n, q - p.c;
    p.infl.push_back(-p.C * J);
  }
  p.rms_mm = fr.rms_mm;
  p.ssr_mm2 = fr.ssr_mm2;
  p.dof = fr.dof;
  p.form_ls_mm = fr.form_mm;
  if (mz) {
    try {
      p.form_mz_mm = geometry::fitMinimumZone(geometry::ElementKind::Plane, pts).form_mm;
    } catch (const GeometryError&) {
      p.form_mz_mm = fr.form_mm;  // degenerate for the zone search: the LS peak to valley
    }
  }
  return p;
}

// --- measured quantities and their sensitivities ------------------------------------------

enum class Q { D, DZ, Beta };

FQ quantity(const TtpFeatureResult& f, const PlaneModel& p, Q q, double y_path) {
  FQ r;
  r.feature = &f;
  r.pts = p.pts;
  const Vector3d& c = p.c;
  const Vector3d& n = p.n;
  Vector6d J = Vector6d::Zero();
  if (q == Q::D) {
    r.value = n.dot(c);  // d = n.(c - O), O = 0 in the part frame
    J << n, c;
    r.frame << -n, Vector3d::Zero();
    r.length_mm = std::fabs(r.value);
  } else if (q == Q::DZ) {
    const double x0 = 0.0;
    const double a = n.x() * (x0 - c.x()) + n.y() * (y_path - c.y());
    const double z_at = c.z() - a / n.z();
    r.value = -z_at;  // depth below the datum plane z = 0
    J << -n.x() / n.z(), -n.y() / n.z(), -1.0, (x0 - c.x()) / n.z(), (y_path - c.y()) / n.z(), -a / (n.z() * n.z());
    const Vector3d P(x0, y_path, z_at);
    r.frame << n / n.z(), P.cross(n) / n.z();
    r.length_mm = std::fabs(r.value);
  } else {
    const double h = n.x() * n.x() + n.z() * n.z();
    r.value = std::atan2(n.x(), n.z()) * 1e6;
    const Vector3d b = Vector3d(n.z(), 0.0, -n.x()) / h * 1e6;
    J << Vector3d::Zero(), b;
    r.frame << Vector3d::Zero(), b.cross(n);
  }
  for (const auto& k : p.infl) r.s.push_back(J.dot(k));
  r.shift = J.head<3>().dot(n);
  return r;
}

}  // namespace

std::map<std::string, PlaneModel> fitFeatures(const parts::PlanManifest& m, const std::string& file, const std::vector<Pt>& pts,
                                              const PointsByFeature& by, const std::map<int, double>& times, bool form_mz,
                                              std::vector<TtpFeatureResult>& features) {
  std::map<std::string, PlaneModel> planes;
  features.reserve(m.features.size());
  for (const auto& mf : m.features) {
    const auto& n = mf.nominal;
    if (n.role != "z_path" && n.role != "facet") continue;
    const auto it = by.find(n.id);
    if (it == by.end()) continue;
    const auto& idx = it->second;
    if (idx.size() < 3) featureError(file, pts, idx, n.id, "a plane needs >= 3 non-collinear points");
    std::vector<Vector3d> v;
    for (int i : idx) v.push_back(pts[static_cast<std::size_t>(i)].part_mm);
    PlaneModel pm;
    try {
      pm = fitPlaneModel(v, idx, n.direction, form_mz);
    } catch (const GeometryError& x) {
      featureError(file, pts, idx, n.id, x.what());
    }
    // The fitted plane against its nominal one: mislabelled points (X1_3's labelled X1_4) would
    // otherwise give errors off by tenths of a mm silently, and a Z path's depth divides by n_z.
    {
      const Vector3d nn = n.direction.normalized();
      const double angle_deg = radToDeg(std::acos(std::clamp(pm.n.dot(nn), -1.0, 1.0)));
      const double off_mm = (pm.c - n.point_mm).dot(nn);
      if (angle_deg > kNominalAngleDeg || std::fabs(off_mm) > kNominalDistanceMm)
        throw InputError(file, pts[static_cast<std::size_t>(idx.front())].line,
                         "feature " + n.id + " (" + std::to_string(idx.size()) + " points, the first on this line): after the datum "
                         "alignment its fitted plane's normal is " + num(angle_deg) + " deg from the nominal one and its centre " +
                             num(off_mm) + " mm from the nominal surface (at most " + num(kNominalAngleDeg) + " deg and " +
                             num(kNominalDistanceMm) + " mm): mislabelled points? (manifest " + m.file + ")");
    }
    TtpFeatureResult f;
    f.id = n.id;
    f.group = n.group;
    f.index = n.index;
    f.cycle = mf.cycle;
    f.time_s = std::isfinite(mf.cut_time_s) ? mf.cut_time_s : (times.count(mf.cycle) ? times.at(mf.cycle) : 0.0);
    f.points = static_cast<int>(idx.size());
    f.rms_um = pm.rms_mm * 1e3;
    f.form_mz_um = (pm.form_mz_mm >= 0 ? pm.form_mz_mm : pm.form_ls_mm) * 1e3;
    f.centre_mm = pm.c;
    f.normal = pm.n;
    planes[n.id] = pm;
    features.push_back(f);
  }
  return planes;
}

FeatureQuantities featureQuantities(const parts::PlanManifest& m, const std::map<std::string, PlaneModel>& planes,
                                    const std::vector<Pt>& pts, const TtpScatter& scatter,
                                    std::vector<TtpFeatureResult>& features) {
  FeatureQuantities out;
  auto& dq = out.dq;
  auto& zq = out.zq;
  auto& bq = out.bq;
  for (auto& f : features) {
    const auto& pm = planes.at(f.id);
    const auto& nom = m.feature(f.id)->nominal;
    if (nom.role == "facet") {
      dq[f.id] = quantity(f, pm, Q::D, 0);
      f.d_mm = dq[f.id].value;
    } else {
      zq[f.id] = quantity(f, pm, Q::DZ, nom.point_mm.y());
      bq[f.id] = quantity(f, pm, Q::Beta, nom.point_mm.y());
      f.depth_mm = zq[f.id].value;
      f.beta_urad = bq[f.id].value;
    }
    const FQ& main = nom.role == "facet" ? dq[f.id] : zq[f.id];
    double v = 0;
    for (std::size_t j = 0; j < main.pts.size(); ++j) {
      const auto& p = pts[static_cast<std::size_t>(main.pts[j])];
      const double s = scatter.type_a_used ? scatter.type_a_sigma_mm : p.sigma_b_mm;
      v += std::pow(s * main.s[j], 2);
    }
    f.u_d_um = std::sqrt(v) * 1e3;
  }
  return out;
}

}  // namespace probeloop::evaluate::ttp
