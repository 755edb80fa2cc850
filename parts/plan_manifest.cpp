#include "parts/plan_manifest.hpp"

#include <nlohmann/json.hpp>

#include <cmath>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace probeloop::parts {

using nlohmann::ordered_json;

const ManifestSphere* PlanManifest::sphere(int position) const {
  for (const auto& s : spheres)
    if (s.position == position) return &s;
  return nullptr;
}

int PlanManifest::pointsPerSphere() const {
  if (spheres.empty()) return 0;
  return static_cast<int>(points.size() / spheres.size());
}

namespace {
ordered_json vec(const Eigen::Vector3d& v) { return ordered_json::array({v.x(), v.y(), v.z()}); }

Eigen::Vector3d readVec(const ordered_json& j, const std::string& file, const std::string& what) {
  if (!j.is_array() || j.size() != 3)
    throw InputError(file, 0, what + ": expected an array of 3 numbers");
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) throw InputError(file, 0, what + ": expected numbers");
    v(i) = j[i].get<double>();
  }
  return v;
}
}  // namespace

namespace {
ordered_json orNull(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }
double optional(const ordered_json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}
}  // namespace

std::string manifestToJson(const PlanManifest& m) {
  ordered_json j;
  j["format"] = "probeloop-plan-manifest";
  j["version"] = 1;
  j["kind"] = m.kind;
  j["dialect"] = m.dialect;
  for (const auto& p : m.programs)
    j["programs"].push_back({{"file", p.file}, {"dialect", p.dialect}, {"log_file", p.log_file}});
  j["machine"] = {{"name", m.machine_name},
                  {"c_axis_centre_mm", {m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y()}},
                  {"c_positive_is_clockwise", m.c_positive_is_clockwise},
                  {"table_surface_z_mm", m.table_surface_z_mm},
                  {"coordinate_resolution_mm", m.coordinate_resolution_mm}};
  j["probe"] = {{"tool", m.probe_tool},
                {"tip_radius_mm", m.tip_radius_mm},
                {"repeatability_2sigma_um", m.probe_repeatability_2sigma_um},
                {"tool_change_repeatability_2sigma_um", orNull(m.probe_tool_change_repeatability_2sigma_um)}};
  j["artifact"] = {{"sphere_radius_mm", m.sphere_radius_mm},
                   {"sphere_form_error_um", m.sphere_form_error_um},
                   {"radius_from_axis_mm", m.radius_from_axis_mm},
                   {"sphere_centre_height_mm", orNull(m.sphere_centre_height_mm)},
                   {"radius_from_axis_u_mm", orNull(m.radius_from_axis_u_mm)},
                   {"alpha_um_per_m_K", orNull(m.artifact_alpha_um_per_m_K)},
                   {"temperature_change_half_width_K", orNull(m.artifact_temperature_change_half_width_K)}};
  for (const auto& s : m.spheres) {
    j["features"].push_back({{"id", s.id},
                             {"kind", "sphere"},
                             {"position", s.position},
                             {"c_deg", s.c_deg},
                             {"angle_deg", s.angle_deg},
                             {"nominal_centre_mm", vec(s.nominal_centre_mm)},
                             {"radius_mm", m.sphere_radius_mm},
                             {"formula_index", s.formula_index},
                             {"repeat_of", s.repeat_of}});
  }
  for (const auto& p : m.points) {
    j["points"].push_back({{"feature", p.feature},
                           {"position", p.position},
                           {"point", p.point},
                           {"contact_mm", vec(p.contact_mm)},
                           {"approach", vec(p.approach)},
                           {"tip_radius_mm", m.tip_radius_mm},
                           {"time_in_cycle_s", p.time_in_cycle_s}});
  }
  j["schedule"] = {{"cycles", m.cycles},
                   {"gap_s", m.gap_s},
                   {"tool_change_each_cycle", m.tool_change_each_cycle},
                   {"cycle_time_s", m.cycle_time_s},
                   {"cycle_start_s", m.cycle_start_s}};
  return j.dump(1) + "\n";
}

PlanManifest readManifest(const std::string& path) {
  ordered_json j;
  try {
    j = ordered_json::parse(readFile(path));
  } catch (const ordered_json::parse_error& e) {
    throw InputError(path, 0, std::string("not valid JSON: ") + e.what());
  }
  PlanManifest m;
  m.file = path;
  try {
    if (j.value("format", "") != "probeloop-plan-manifest")
      throw InputError(path, 0, "not a probeloop plan manifest (format field)");
    if (j.at("version").get<int>() != 1)
      throw InputError(path, 0, "manifest version " + j.at("version").dump() + " is not supported");
    m.kind = j.at("kind").get<std::string>();
    m.dialect = j.at("dialect").get<std::string>();
    for (const auto& p : j.at("programs"))
      m.programs.push_back({p.at("file").get<std::string>(), p.at("dialect").get<std::string>(),
                            p.at("log_file").get<std::string>()});
    const auto& mc = j.at("machine");
    m.machine_name = mc.at("name");
    m.c_axis_centre_mm = Eigen::Vector2d(mc.at("c_axis_centre_mm").at(0).get<double>(),
                                         mc.at("c_axis_centre_mm").at(1).get<double>());
    m.c_positive_is_clockwise = mc.at("c_positive_is_clockwise");
    m.table_surface_z_mm = mc.at("table_surface_z_mm");
    m.coordinate_resolution_mm = mc.at("coordinate_resolution_mm");
    const auto& pr = j.at("probe");
    m.probe_tool = pr.at("tool");
    m.tip_radius_mm = pr.at("tip_radius_mm");
    m.probe_repeatability_2sigma_um = pr.at("repeatability_2sigma_um");
    m.probe_tool_change_repeatability_2sigma_um = optional(pr, "tool_change_repeatability_2sigma_um");
    const auto& a = j.at("artifact");
    m.sphere_radius_mm = a.at("sphere_radius_mm");
    m.sphere_form_error_um = a.at("sphere_form_error_um");
    m.radius_from_axis_mm = a.at("radius_from_axis_mm");
    m.sphere_centre_height_mm = optional(a, "sphere_centre_height_mm");
    m.radius_from_axis_u_mm = optional(a, "radius_from_axis_u_mm");
    m.artifact_alpha_um_per_m_K = optional(a, "alpha_um_per_m_K");
    m.artifact_temperature_change_half_width_K = optional(a, "temperature_change_half_width_K");
    for (const auto& f : j.at("features")) {
      ManifestSphere s;
      s.id = f.at("id");
      s.position = f.at("position");
      s.c_deg = f.at("c_deg");
      s.angle_deg = f.at("angle_deg");
      s.nominal_centre_mm = readVec(f.at("nominal_centre_mm"), path, "features[].nominal_centre_mm");
      s.formula_index = f.at("formula_index");
      s.repeat_of = f.at("repeat_of");
      m.spheres.push_back(s);
    }
    for (const auto& p : j.at("points")) {
      ManifestPoint q;
      q.feature = p.at("feature");
      q.position = p.at("position");
      q.point = p.at("point");
      q.contact_mm = readVec(p.at("contact_mm"), path, "points[].contact_mm");
      q.approach = readVec(p.at("approach"), path, "points[].approach");
      q.time_in_cycle_s = p.at("time_in_cycle_s");
      m.points.push_back(q);
    }
    const auto& s = j.at("schedule");
    m.cycles = s.at("cycles");
    m.tool_change_each_cycle = s.value("tool_change_each_cycle", false);
    m.gap_s = s.at("gap_s");
    m.cycle_time_s = s.at("cycle_time_s");
    m.cycle_start_s = s.at("cycle_start_s").get<std::vector<double>>();
  } catch (const ordered_json::exception& e) {
    throw InputError(path, 0, std::string("manifest field missing or of the wrong type: ") + e.what());
  }
  if (m.spheres.size() < 3) throw InputError(path, 0, "manifest has fewer than 3 sphere positions");
  if (m.points.size() % m.spheres.size() != 0)
    throw InputError(path, 0, "manifest points are not the same number per sphere");
  if (static_cast<int>(m.cycle_start_s.size()) != m.cycles)
    throw InputError(path, 0, "schedule.cycle_start_s does not have one entry per cycle");
  for (const auto& p : m.points)
    if (!m.sphere(p.position))
      throw InputError(path, 0, "point of feature " + p.feature + " names a missing position");
  return m;
}

}  // namespace probeloop::parts
