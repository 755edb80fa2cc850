#include "planner/cmm_plan.hpp"

#include <map>
#include <stdexcept>

#include "core/csv.hpp"
#include "interop/dmis.hpp"
#include "interop/qif.hpp"
#include "parts/cmm_feature.hpp"

namespace probeloop::planner {

using Eigen::Vector3d;

namespace {

interop::CmmDocument cmmPlanDocument(const parts::PlanManifest& m, const std::string& cmm_points_csv) {
  const CsvTable t = parseCsv(cmm_points_csv, "cmm_points.csv");
  const int cf = t.column("feature"), cx = t.column("x_mm"), cy = t.column("y_mm"), cz = t.column("z_mm"), nx = t.column("nx"),
            ny = t.column("ny"), nz = t.column("nz");
  interop::CmmDocument d;
  d.part_name = m.part_name;
  std::map<std::string, std::size_t> index;
  for (const auto& r : t.rows) {
    const std::string& id = r.fields[static_cast<std::size_t>(cf)];
    auto it = index.find(id);
    if (it == index.end()) {
      const auto* mf = m.feature(id);
      if (!mf) throw std::logic_error("CMM plan: feature " + id + " is not in the manifest");
      it = index.emplace(id, d.features.size()).first;
      d.features.push_back(parts::cmmFeatureOf(mf->nominal));
    }
    interop::CmmPoint p;
    p.p_mm = Vector3d(t.number(r, cx), t.number(r, cy), t.number(r, cz));
    p.normal = Vector3d(t.number(r, nx), t.number(r, ny), t.number(r, nz));
    d.features[it->second].points.push_back(p);
  }
  for (auto& f : d.features) parts::setInternalFromPoints(f);
  return d;
}

}  // namespace

std::string qifCmmPlan(const parts::PlanManifest& m, const std::string& cmm_points_csv) {
  return interop::qifPlan(cmmPlanDocument(m, cmm_points_csv));
}

std::string dmisCmmPlan(const parts::PlanManifest& m, const std::string& cmm_points_csv) {
  return interop::dmisProgram(cmmPlanDocument(m, cmm_points_csv), m.part_name.substr(0, 60));
}

std::string qifSphereProbePlan(const parts::PlanManifest& m) {
  interop::CmmDocument d;
  d.part_name = "sphere artifact";
  for (const auto& s : m.spheres) {
    interop::CmmFeature f;
    f.name = s.id;
    f.kind = interop::CmmFeatureKind::Sphere;
    f.nominal.given = true;
    f.nominal.location_mm = s.nominal_centre_mm;
    f.nominal.diameter_mm = 2 * m.sphere_radius_mm;
    for (const auto& p : m.points) {
      if (p.position != s.position) continue;
      interop::CmmPoint q;
      q.p_mm = p.contact_mm + m.tip_radius_mm * p.approach;
      q.normal = -p.approach;
      f.points.push_back(q);
    }
    d.features.push_back(f);
  }
  return interop::qifPlan(d);
}

}  // namespace probeloop::planner
