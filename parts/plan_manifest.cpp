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

const ManifestFeature* PlanManifest::feature(const std::string& id) const {
  for (const auto& f : features)
    if (f.nominal.id == id) return &f;
  return nullptr;
}

const ManifestFeature* PlanManifest::featureAtPosition(int position) const {
  for (const auto& f : features)
    if (f.position == position && position > 0) return &f;
  return nullptr;
}

const ManifestProgram* PlanManifest::program(const std::string& role) const {
  for (const auto& p : programs)
    if (p.role == role) return &p;
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

Eigen::Vector2d readVec2(const ordered_json& j, const std::string& file, const std::string& what) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number())
    throw InputError(file, 0, what + ": expected an array of 2 numbers");
  return {j[0].get<double>(), j[1].get<double>()};
}
}  // namespace

namespace {
ordered_json orNull(double v) { return std::isfinite(v) ? ordered_json(v) : ordered_json(); }
double optional(const ordered_json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}
}  // namespace

namespace {

ordered_json machineJson(const PlanManifest& m) {
  ordered_json j = {{"name", m.machine_name},
                  {"c_axis_centre_mm", {m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y()}},
                  {"c_positive_is_clockwise", m.c_positive_is_clockwise},
                  {"table_surface_z_mm", m.table_surface_z_mm},
                  {"coordinate_resolution_mm", m.coordinate_resolution_mm}};
  if (m.tilt_axis)
    j["tilt_axis"] = {{"name", m.tilt_axis->name},
                      {"centre_mm", {m.tilt_axis->centre_mm.x(), m.tilt_axis->centre_mm.y()}},
                      {"positive_is_clockwise", m.tilt_axis->positive_is_clockwise}};
  return j;
}

ordered_json probeJson(const PlanManifest& m) {
  return {{"tool", m.probe_tool},
          {"tip_radius_mm", m.tip_radius_mm},
          {"repeatability_2sigma_um", m.probe_repeatability_2sigma_um},
          {"tool_change_repeatability_2sigma_um", orNull(m.probe_tool_change_repeatability_2sigma_um)}};
}

ordered_json scheduleJson(const PlanManifest& m) {
  return {{"cycles", m.cycles},
          {"gap_s", m.gap_s},
          {"tool_change_each_cycle", m.tool_change_each_cycle},
          {"cycle_time_s", m.cycle_time_s},
          {"cycle_start_s", m.cycle_start_s}};
}

// Kinds other than the sphere artifact: features, cycles, cuts and points of any geometry.
std::string genericManifestJson(const PlanManifest& m) {
  ordered_json j;
  j["format"] = "probeloop-plan-manifest";
  j["version"] = 1;
  j["kind"] = m.kind;
  j["dialect"] = m.dialect;
  j["programs"] = ordered_json::array();
  for (const auto& p : m.programs)
    j["programs"].push_back({{"file", p.file}, {"dialect", p.dialect}, {"log_file", p.log_file}, {"role", p.role},
                             {"start_s", p.start_s}, {"duration_s", p.duration_s}});
  j["machine"] = machineJson(m);
  j["probe"] = probeJson(m);
  j["part"] = {{"name", m.part_name},
               {"origin_mm", vec(m.part_origin_mm)},
               {"material", m.material_name},
               {"alpha_um_per_m_K", orNull(m.material_alpha_um_per_m_K)}};
  if (m.kind == "thermal_test_piece") {
    const auto& t = m.ttp;
    j["thermal_test_piece"] = {{"z_paths", t.z_paths},
                               {"facets_per_segment", t.facets_per_segment},
                               {"eq_7_10", {{"alpha_um_per_m_K", t.eq_7_10_alpha_um_per_m_K},
                                            {"alpha_u_um_per_m_K", t.alpha_u_um_per_m_K},
                                            {"radius_mm", t.eq_7_10_radius_mm}}},
                               {"cmm", {{"mpe_constant_um", t.cmm.mpe_constant_um},
                                        {"mpe_length_mm", t.cmm.mpe_length_mm},
                                        {"temperature_half_width_K", t.cmm.temperature_half_width_K}}},
                               {"on_machine", {{"repeatability_um", t.on_machine_repeatability_um},
                                               {"temperature_change_K", t.on_machine_temperature_change_K}}},
                               {"cmm_plan", t.cmm_plan}};
  }
  if (m.kind == "stepped_workpiece") {
    const auto& t = m.sw;
    ordered_json steps = ordered_json::array();
    for (const auto& s : t.steps)
      steps.push_back({{"step", s.step}, {"feed_xy_mm_per_min", s.feed_xy_mm_per_min}, {"feed_z_mm_per_min", s.feed_z_mm_per_min},
                       {"spindle_speed_rpm", s.spindle_speed_rpm}, {"start_s", s.start_s}, {"end_s", s.end_s},
                       {"temp_state_min", s.temp_state_min}});
    j["stepped_workpiece"] = {{"experiment", t.experiment},
                              {"transition", t.transition},
                              {"transition_feed_mm_per_min", t.transition_feed_mm_per_min},
                              {"tool_runout_mm", t.tool_runout_mm},
                              {"tool_diameter_mm", t.tool_diameter_mm},
                              {"sizes_mm", t.sizes_mm},
                              {"steps", steps},
                              {"cmm", {{"mpe_constant_um", t.cmm.mpe_constant_um},
                                       {"mpe_length_mm", t.cmm.mpe_length_mm},
                                       {"temperature_half_width_K", t.cmm.temperature_half_width_K}}},
                              {"cmm_plan", t.cmm_plan}};
    if (!t.compensation.empty()) {
      ordered_json cs = ordered_json::array();
      for (const auto& c : t.compensation) {
        ordered_json w, uw;
        for (int i = 0; i < 4; ++i) {
          w[kSwWalls[i]] = c.wall_um[static_cast<std::size_t>(i)];
          uw[kSwWalls[i]] = c.U_wall_um[static_cast<std::size_t>(i)];
        }
        cs.push_back({{"step", c.step}, {"wall_um", w}, {"floor_um", c.floor_um}, {"U_wall_um", uw}, {"U_floor_um", c.U_floor_um}});
      }
      j["stepped_workpiece"]["compensation"] = {{"file", t.compensation_file}, {"steps", cs}};
    }
  }
  j["features"] = ordered_json::array();
  for (const auto& f : m.features) {
    const auto& n = f.nominal;
    j["features"].push_back({{"id", n.id}, {"kind", n.kind}, {"role", n.role}, {"group", n.group}, {"index", n.index},
                             {"point_mm", vec(n.point_mm)}, {"direction", vec(n.direction)}, {"u", vec(n.u)},
                             {"half_u_mm", n.half_u_mm}, {"half_v_mm", n.half_v_mm}, {"radius_mm", n.radius_mm},
                             {"angle_deg", n.angle_deg}, {"cycle", f.cycle}, {"cut_time_s", orNull(f.cut_time_s)},
                             {"position", f.position}, {"probe_c_deg", orNull(f.probe_c_deg)}});
  }
  j["cycles"] = ordered_json::array();
  for (const auto& c : m.cut_cycles)
    j["cycles"].push_back({{"cycle", c.cycle}, {"phase", c.phase}, {"c_axis_rpm_before", c.c_axis_rpm_before},
                           {"start_s", c.start_s}, {"end_s", c.end_s}, {"z_path", c.z_path}, {"facet", c.facet},
                           {"c_x_deg", c.c_x_deg}, {"c_y_deg", c.c_y_deg}});
  j["cuts"] = ordered_json::array();
  for (const auto& c : m.cuts)
    j["cuts"].push_back({{"id", c.id}, {"program", c.program}, {"feature", c.feature}, {"cycle", c.cycle}, {"tool", c.tool},
                         {"c_deg", c.c_deg}, {"start_s", c.start_s}, {"end_s", c.end_s}, {"from_mm", vec(c.from_mm)},
                         {"to_mm", vec(c.to_mm)}});
  j["points"] = ordered_json::array();
  for (const auto& p : m.points)
    j["points"].push_back({{"feature", p.feature}, {"position", p.position}, {"point", p.point},
                           {"contact_mm", vec(p.contact_mm)}, {"approach", vec(p.approach)},
                           {"tip_radius_mm", m.tip_radius_mm}, {"c_deg", p.c_deg},
                           {"time_in_cycle_s", p.time_in_cycle_s}});
  j["evaluation"] = ordered_json::array();
  for (const auto& e : m.evaluation)
    j["evaluation"].push_back({{"output", e.output}, {"formula", e.formula}, {"source", e.source}, {"features", e.features}});
  j["schedule"] = scheduleJson(m);
  return j.dump(1) + "\n";
}

}  // namespace

std::string manifestToJson(const PlanManifest& m) {
  if (m.kind != "sphere_artifact") return genericManifestJson(m);
  ordered_json j;
  j["format"] = "probeloop-plan-manifest";
  j["version"] = 1;
  j["kind"] = m.kind;
  j["dialect"] = m.dialect;
  for (const auto& p : m.programs)
    j["programs"].push_back({{"file", p.file}, {"dialect", p.dialect}, {"log_file", p.log_file}});
  j["machine"] = machineJson(m);
  j["probe"] = probeJson(m);
  j["artifact"] = {{"sphere_radius_mm", m.sphere_radius_mm},
                   {"sphere_form_error_um", m.sphere_form_error_um},
                   {"radius_from_axis_mm", m.radius_from_axis_mm},
                   {"sphere_centre_height_mm", orNull(m.sphere_centre_height_mm)},
                   {"radius_from_axis_u_mm", orNull(m.radius_from_axis_u_mm)},
                   {"alpha_um_per_m_K", orNull(m.artifact_alpha_um_per_m_K)},
                   {"temperature_change_half_width_K", orNull(m.artifact_temperature_change_half_width_K)}};
  for (const auto& s : m.spheres) {
    ordered_json f = {{"id", s.id},
                             {"kind", "sphere"},
                             {"position", s.position},
                             {"c_deg", s.c_deg},
                             {"angle_deg", s.angle_deg},
                             {"nominal_centre_mm", vec(s.nominal_centre_mm)},
                             {"radius_mm", m.sphere_radius_mm},
                             {"formula_index", s.formula_index},
                             {"repeat_of", s.repeat_of}};
    if (m.tilt_axis) f["tilt_deg"] = s.tilt_deg;
    j["features"].push_back(f);
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
  j["schedule"] = scheduleJson(m);
  return j.dump(1) + "\n";
}

namespace {

void readSchedule(const ordered_json& s, PlanManifest& m) {
  m.cycles = s.at("cycles");
  m.tool_change_each_cycle = s.value("tool_change_each_cycle", false);
  m.gap_s = s.at("gap_s");
  m.cycle_time_s = s.at("cycle_time_s");
  m.cycle_start_s = s.at("cycle_start_s").get<std::vector<double>>();
  if (static_cast<int>(m.cycle_start_s.size()) != m.cycles)
    throw InputError(m.file, 0, "schedule.cycle_start_s does not have one entry per cycle");
}

// Kinds other than the sphere artifact (the caller catches json exceptions).
void readGeneric(const ordered_json& j, PlanManifest& m) {
  const std::string& path = m.file;
  const auto& part = j.at("part");
  m.part_name = part.at("name");
  m.part_origin_mm = readVec(part.at("origin_mm"), path, "part.origin_mm");
  m.material_name = part.at("material");
  m.material_alpha_um_per_m_K = optional(part, "alpha_um_per_m_K");
  if (m.kind == "thermal_test_piece") {
    const auto& t = j.at("thermal_test_piece");
    auto& c = m.ttp;
    c.z_paths = t.at("z_paths");
    c.facets_per_segment = t.at("facets_per_segment");
    c.eq_7_10_alpha_um_per_m_K = t.at("eq_7_10").at("alpha_um_per_m_K");
    c.alpha_u_um_per_m_K = t.at("eq_7_10").at("alpha_u_um_per_m_K");
    c.eq_7_10_radius_mm = t.at("eq_7_10").at("radius_mm");
    c.cmm.mpe_constant_um = t.at("cmm").at("mpe_constant_um");
    c.cmm.mpe_length_mm = t.at("cmm").at("mpe_length_mm");
    c.cmm.temperature_half_width_K = t.at("cmm").at("temperature_half_width_K");
    c.on_machine_repeatability_um = t.at("on_machine").at("repeatability_um");
    c.on_machine_temperature_change_K = t.at("on_machine").at("temperature_change_K");
    c.cmm_plan = t.at("cmm_plan");
    // Divisors and half-widths of the evaluation: refused here rather than a NaN later.
    auto need = [&](bool ok, const std::string& what) {
      if (!ok) throw InputError(path, 0, "thermal_test_piece." + what);
    };
    need(c.z_paths >= 2 && c.facets_per_segment >= 2, "z_paths, facets_per_segment: expected at least 2 each");
    need(c.eq_7_10_alpha_um_per_m_K > 0 && c.eq_7_10_radius_mm > 0, "eq_7_10: alpha and radius must be positive");
    need(c.alpha_u_um_per_m_K >= 0, "eq_7_10.alpha_u_um_per_m_K: must not be negative");
    need(c.cmm.mpe_constant_um >= 0 && c.cmm.mpe_length_mm >= 0 && c.cmm.temperature_half_width_K >= 0,
         "cmm: MPE terms and the temperature half-width must not be negative");
    need(c.on_machine_repeatability_um >= 0 && c.on_machine_temperature_change_K >= 0,
         "on_machine: repeatability and temperature change must not be negative");
  }
  if (m.kind == "stepped_workpiece") {
    const auto& t = j.at("stepped_workpiece");
    auto& c = m.sw;
    c.experiment = t.at("experiment");
    c.transition = t.at("transition");
    c.transition_feed_mm_per_min = t.at("transition_feed_mm_per_min");
    c.tool_runout_mm = t.at("tool_runout_mm");
    c.tool_diameter_mm = t.at("tool_diameter_mm");
    if (t.contains("compensation")) {
      c.compensation_file = t.at("compensation").at("file");
      for (const auto& s : t.at("compensation").at("steps")) {
        SwStepCompensation x;
        x.step = s.at("step");
        for (int i = 0; i < 4; ++i) {
          x.wall_um[static_cast<std::size_t>(i)] = s.at("wall_um").at(kSwWalls[i]);
          x.U_wall_um[static_cast<std::size_t>(i)] = s.at("U_wall_um").at(kSwWalls[i]);
        }
        x.floor_um = s.at("floor_um");
        x.U_floor_um = s.at("U_floor_um");
        c.compensation.push_back(x);
      }
    }
    c.sizes_mm = t.at("sizes_mm").get<std::vector<double>>();
    for (const auto& s : t.at("steps")) {
      ManifestStep x;
      x.step = s.at("step");
      x.feed_xy_mm_per_min = s.at("feed_xy_mm_per_min");
      x.feed_z_mm_per_min = s.at("feed_z_mm_per_min");
      x.spindle_speed_rpm = s.at("spindle_speed_rpm");
      x.start_s = s.at("start_s");
      x.end_s = s.at("end_s");
      x.temp_state_min = s.at("temp_state_min");
      c.steps.push_back(x);
    }
    c.cmm.mpe_constant_um = t.at("cmm").at("mpe_constant_um");
    c.cmm.mpe_length_mm = t.at("cmm").at("mpe_length_mm");
    c.cmm.temperature_half_width_K = t.at("cmm").at("temperature_half_width_K");
    c.cmm_plan = t.at("cmm_plan");
    if (c.steps.size() != c.sizes_mm.size() || c.steps.size() < 2)
      throw InputError(path, 0, "stepped_workpiece.steps: expected one entry per size in sizes_mm (at least 2)");
    for (double v : c.sizes_mm)
      if (!(v > 0)) throw InputError(path, 0, "stepped_workpiece.sizes_mm: every size must be positive");
  }
  for (const auto& f : j.at("features")) {
    ManifestFeature x;
    auto& n = x.nominal;
    n.id = f.at("id");
    n.kind = f.at("kind");
    n.role = f.at("role");
    n.group = f.at("group");
    n.index = f.at("index");
    n.point_mm = readVec(f.at("point_mm"), path, "features[].point_mm");
    n.direction = readVec(f.at("direction"), path, "features[].direction");
    n.u = readVec(f.at("u"), path, "features[].u");
    n.half_u_mm = f.at("half_u_mm");
    n.half_v_mm = f.at("half_v_mm");
    n.radius_mm = f.at("radius_mm");
    n.angle_deg = f.at("angle_deg");
    x.cycle = f.at("cycle");
    x.cut_time_s = optional(f, "cut_time_s");
    x.position = f.at("position");
    x.probe_c_deg = optional(f, "probe_c_deg");
    if (m.feature(n.id)) throw InputError(path, 0, "feature " + n.id + " is listed twice");
    m.features.push_back(x);
  }
  for (const auto& c : j.at("cycles")) {
    ManifestCycle x;
    x.cycle = c.at("cycle");
    x.phase = c.at("phase");
    x.c_axis_rpm_before = c.at("c_axis_rpm_before");
    x.start_s = c.at("start_s");
    x.end_s = c.at("end_s");
    x.z_path = c.at("z_path");
    x.facet = c.at("facet");
    x.c_x_deg = c.at("c_x_deg");
    x.c_y_deg = c.at("c_y_deg");
    m.cut_cycles.push_back(x);
  }
  for (const auto& c : j.at("cuts")) {
    ManifestCut x;
    x.id = c.at("id");
    x.program = c.at("program");
    x.feature = c.at("feature");
    x.cycle = c.at("cycle");
    x.tool = c.at("tool");
    x.c_deg = c.at("c_deg");
    x.start_s = c.at("start_s");
    x.end_s = c.at("end_s");
    x.from_mm = readVec(c.at("from_mm"), path, "cuts[].from_mm");
    x.to_mm = readVec(c.at("to_mm"), path, "cuts[].to_mm");
    m.cuts.push_back(x);
  }
  for (const auto& p : j.at("points")) {
    ManifestPoint q;
    q.feature = p.at("feature");
    q.position = p.at("position");
    q.point = p.at("point");
    q.contact_mm = readVec(p.at("contact_mm"), path, "points[].contact_mm");
    q.approach = readVec(p.at("approach"), path, "points[].approach");
    q.c_deg = p.at("c_deg");
    q.time_in_cycle_s = p.at("time_in_cycle_s");
    const auto* f = m.feature(q.feature);
    if (!f) throw InputError(path, 0, "a point names the feature " + q.feature + ", which the manifest does not list");
    if (f->position != q.position)
      throw InputError(path, 0, "a point of feature " + q.feature + " has position " + std::to_string(q.position) +
                                    ", the feature " + std::to_string(f->position));
    m.points.push_back(q);
  }
  for (const auto& e : j.at("evaluation"))
    m.evaluation.push_back({e.at("output"), e.at("formula"), e.at("source"), e.at("features")});
  readSchedule(j.at("schedule"), m);
}

}  // namespace

std::optional<PieceKind> parsePieceKind(const std::string& name) {
  if (name == "sphere_artifact") return PieceKind::SphereArtifact;
  if (name == "thermal_test_piece") return PieceKind::ThermalTestPiece;
  if (name == "stepped_workpiece") return PieceKind::SteppedWorkpiece;
  return std::nullopt;
}

PieceKind PlanManifest::pieceKind() const {
  if (const auto k = parsePieceKind(kind)) return *k;
  throw InputError(file, 0, "manifest kind '" + kind + "': plans are made for sphere_artifact, thermal_test_piece and stepped_workpiece");
}

PlanManifest readManifest(const std::string& path) { return parseManifest(readFile(path, kJsonInput), path); }

PlanManifest parseManifest(const std::string& text, const std::string& path) {
  ordered_json j;
  try {
    j = ordered_json::parse(text);
  } catch (const ordered_json::parse_error& e) {
    const std::string kind = describeContent(text);
    throw InputError(path, 0, "not a plan manifest: " + (kind.empty() ? std::string("not valid JSON (") + e.what() + ")"
                                                                      : "the file looks like " + kind +
                                                                            "; the manifest is the plan.json that `probeloop plan` writes"));
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
    for (const auto& p : j.at("programs")) {
      ManifestProgram q;
      q.file = p.at("file").get<std::string>();
      q.dialect = p.at("dialect").get<std::string>();
      q.log_file = p.at("log_file").get<std::string>();
      q.role = p.value("role", "");
      q.start_s = p.value("start_s", 0.0);
      q.duration_s = p.value("duration_s", 0.0);
      m.programs.push_back(q);
    }
    const auto& mc = j.at("machine");
    m.machine_name = mc.at("name");
    m.c_axis_centre_mm = Eigen::Vector2d(mc.at("c_axis_centre_mm").at(0).get<double>(),
                                         mc.at("c_axis_centre_mm").at(1).get<double>());
    m.c_positive_is_clockwise = mc.at("c_positive_is_clockwise");
    if (mc.contains("tilt_axis")) {
      const auto& ta = mc.at("tilt_axis");
      ManifestTiltAxis t;
      t.name = ta.at("name").get<std::string>();
      if (t.name != "A" && t.name != "B") throw InputError(path, 0, "machine.tilt_axis.name: expected \"A\" or \"B\"");
      t.centre_mm = readVec2(ta.at("centre_mm"), path, "machine.tilt_axis.centre_mm");
      t.positive_is_clockwise = ta.at("positive_is_clockwise");
      m.tilt_axis = t;
    }
    m.table_surface_z_mm = mc.at("table_surface_z_mm");
    m.coordinate_resolution_mm = mc.at("coordinate_resolution_mm");
    const auto& pr = j.at("probe");
    m.probe_tool = pr.at("tool");
    m.tip_radius_mm = pr.at("tip_radius_mm");
    m.probe_repeatability_2sigma_um = pr.at("repeatability_2sigma_um");
    m.probe_tool_change_repeatability_2sigma_um = optional(pr, "tool_change_repeatability_2sigma_um");
    if (m.kind != "sphere_artifact") {
      readGeneric(j, m);
      return m;
    }
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
      s.tilt_deg = f.value("tilt_deg", 0.0);
      if (!std::isfinite(s.tilt_deg)) throw InputError(path, 0, "features[].tilt_deg: not a finite number");
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
    readSchedule(j.at("schedule"), m);
  } catch (const ordered_json::exception& e) {
    throw InputError(path, 0, std::string("manifest field missing or of the wrong type: ") + e.what());
  }
  if (m.spheres.size() < 3) throw InputError(path, 0, "manifest has fewer than 3 sphere positions");
  if (m.points.size() % m.spheres.size() != 0)
    throw InputError(path, 0, "manifest points are not the same number per sphere");
  for (const auto& p : m.points)
    if (!m.sphere(p.position))
      throw InputError(path, 0, "point of feature " + p.feature + " names a missing position");
  return m;
}

}  // namespace probeloop::parts
