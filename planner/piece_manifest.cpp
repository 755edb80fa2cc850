#include "planner/piece_manifest.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/csv.hpp"

namespace probeloop::planner {

void setManifestPrograms(parts::PlanManifest& m, const std::vector<NotedProgram>& programs,
                         const std::vector<double>& start_s, const std::vector<double>& duration_s) {
  for (std::size_t i = 0; i < programs.size(); ++i) {
    parts::ManifestProgram p;
    p.file = programs[i].file;
    p.dialect = m.dialect;
    p.log_file = programs[i].program.log_file;
    p.role = programs[i].role;
    p.start_s = start_s[i];
    p.duration_s = duration_s[i];
    m.programs.push_back(p);
  }
}

void setManifestMachine(parts::PlanManifest& m, const parts::Machine& machine) {
  m.machine_name = machine.name;
  m.c_axis_centre_mm = machine.c_axis_centre_mm;
  m.c_positive_is_clockwise = machine.c.positive_is_clockwise;
  m.table_surface_z_mm = machine.table_surface_z_mm;
  m.coordinate_resolution_mm = std::max({machine.x.resolution_mm, machine.y.resolution_mm, machine.z.resolution_mm});
  m.probe_tool = machine.probe.tool;
  m.probe_tool_change_repeatability_2sigma_um = machine.probe.tool_change_repeatability_2sigma_um;
}

void setManifestPiece(parts::PlanManifest& m, const std::string& kind, parts::Dialect dialect,
                      const std::vector<NotedProgram>& programs, const std::vector<double>& start_s,
                      const std::vector<double>& duration_s, const parts::Machine& machine, double tip_radius_mm,
                      double probe_repeatability_2sigma_um, const std::string& part_name,
                      const Eigen::Vector3d& part_origin_mm, const parts::WorkpieceMaterial& material) {
  m.kind = kind;
  m.dialect = parts::dialectName(dialect);
  setManifestPrograms(m, programs, start_s, duration_s);
  setManifestMachine(m, machine);
  m.tip_radius_mm = tip_radius_mm;
  m.probe_repeatability_2sigma_um = probe_repeatability_2sigma_um;
  m.part_name = part_name;
  m.part_origin_mm = part_origin_mm;
  m.material_name = material.name;
  m.material_alpha_um_per_m_K = material.alpha_um_per_m_K;
}

void setManifestProbingCycle(parts::PlanManifest& m, const std::vector<double>& start_s,
                             const std::vector<double>& duration_s) {
  setFeatureCutTimes(m);  // the cycle and the mid time of the cut(s) that finish each feature
  const std::size_t last = start_s.size() - 1;
  m.cycles = 1;
  m.gap_s = 0;
  m.cycle_time_s = duration_s[last];
  m.cycle_start_s = {start_s[last]};
}

void setFeatureCutTimes(parts::PlanManifest& m) {
  for (auto& f : m.features) {
    double first = INFINITY, last = -INFINITY;
    for (const auto& k : m.cuts)
      if (k.feature == f.nominal.id) {
        first = std::min(first, k.start_s);
        last = std::max(last, k.end_s);
        f.cycle = k.cycle;
      }
    if (std::isfinite(first)) f.cut_time_s = (first + last) / 2;
  }
}

std::string cmmPointsCsv(const std::vector<std::string>& comments, const std::vector<CmmRow>& rows) {
  std::ostringstream o;
  for (const auto& c : comments) o << "# " << c << "\n";
  o << "feature,point,x_mm,y_mm,z_mm,nx,ny,nz\n";
  for (const auto& r : rows)
    o << r.feature << "," << r.point << "," << formatNumber(r.p.x(), 6) << "," << formatNumber(r.p.y(), 6) << ","
      << formatNumber(r.p.z(), 6) << "," << formatNumber(r.n.x(), 6) << "," << formatNumber(r.n.y(), 6) << ","
      << formatNumber(r.n.z(), 6) << "\n";
  return o.str();
}

WalkTimes operator-(const WalkTimes& a, const WalkTimes& b) {
  WalkTimes d;
  d.tool_change_s = a.tool_change_s - b.tool_change_s;
  d.rapid_s = a.rapid_s - b.rapid_s;
  d.rotary_index_s = a.rotary_index_s - b.rotary_index_s;
  d.feed_s = a.feed_s - b.feed_s;
  d.rotary_feed_s = a.rotary_feed_s - b.rotary_feed_s;
  d.protected_s = a.protected_s - b.protected_s;
  d.probing_s = a.probing_s - b.probing_s;
  d.dwell_s = a.dwell_s - b.dwell_s;
  return d;
}

}  // namespace probeloop::planner
