#include "interop/summary.hpp"

#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/csv.hpp"

namespace probeloop::interop {

std::string cmmWarningText(const CmmDocument& d, const CmmWarning& w) {
  return d.file + ":" + std::to_string(w.line) + ": warning: " + w.what;
}

namespace {

std::string kindOf(const CmmFeature& f) { return f.kind == CmmFeatureKind::Other ? f.kind_name : cmmFeatureKindName(f.kind); }

nlohmann::ordered_json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::ordered_json geometry(const CmmGeometry& g) {
  nlohmann::ordered_json j;
  if (!g.given) return j;
  j["location_mm"] = vec(g.location_mm);
  if (g.direction.norm() > 0) j["direction"] = vec(g.direction);
  if (std::isfinite(g.diameter_mm)) j["diameter_mm"] = g.diameter_mm;
  if (std::isfinite(g.form_mm)) j["form_mm"] = g.form_mm;
  return j;
}

std::string mm(double v) { return formatNumber(v, 4); }

}  // namespace

std::string cmmDocumentText(const CmmDocument& d) {
  std::ostringstream o;
  std::map<std::string, int> kinds;
  std::size_t points = 0;
  for (const auto& f : d.features) {
    ++kinds[kindOf(f)];
    points += f.points.size();
  }
  o << d.file << ": " << d.features.size() << " features";
  if (!kinds.empty()) {
    o << " (";
    bool first = true;
    for (const auto& [k, n] : kinds) {
      o << (first ? "" : ", ") << n << " " << k;
      first = false;
    }
    o << ")";
  }
  o << ", " << points << " points, " << d.runs << " measurement run" << (d.runs == 1 ? "" : "s") << "; lengths in "
    << d.length_unit << (d.length_unit == "mm" ? "" : ", shown in mm") << "\n";
  for (const auto& f : d.features) {
    const auto& g = f.measured.given ? f.measured : f.nominal;
    o << "  " << kindOf(f) << " " << (f.name.empty() ? "(no name)" : f.name) << "  line " << f.line;
    if (d.runs > 1) o << ", run " << f.run;
    if (g.given) {
      o << "  at " << mm(g.location_mm.x()) << " " << mm(g.location_mm.y()) << " " << mm(g.location_mm.z());
      if (std::isfinite(g.diameter_mm)) o << "  d " << mm(g.diameter_mm);
      if (std::isfinite(g.form_mm)) o << "  form " << mm(g.form_mm);
    }
    o << "  " << f.points.size() << " points\n";
  }
  for (const auto& c : d.characteristics)
    o << "  characteristic " << c.name << " = " << formatNumber(c.value, 9) << (c.angular ? " rad" : " mm")
      << (std::isfinite(c.u) ? " (u " + formatNumber(c.u, 9) + ")" : std::string()) << "\n";
  if (d.point_sets > 0)
    o << "  measured point sets: " << d.point_sets << " with " << d.point_set_points << " points, " << points
      << " of them assigned to features\n";
  for (const auto& n : d.notes) o << "  note: " << n << "\n";
  for (const auto& w : d.warnings) o << "  " << cmmWarningText(d, w) << "\n";
  return o.str();
}

std::string cmmDocumentJson(const CmmDocument& d) {
  nlohmann::ordered_json j;
  j["file"] = d.file;
  j["length_unit"] = d.length_unit;
  j["runs"] = d.runs;
  auto& fs = j["features"] = nlohmann::ordered_json::array();
  for (const auto& f : d.features) {
    nlohmann::ordered_json x{{"name", f.name}, {"kind", kindOf(f)}, {"line", f.line}, {"run", f.run}, {"internal", f.internal}};
    if (f.nominal.given) x["nominal"] = geometry(f.nominal);
    if (f.measured.given) x["measured"] = geometry(f.measured);
    auto& ps = x["points_mm"] = nlohmann::ordered_json::array();
    for (const auto& p : f.points) ps.push_back(vec(p.p_mm));
    fs.push_back(x);
  }
  auto& cs = j["characteristics"] = nlohmann::ordered_json::array();
  for (const auto& c : d.characteristics) {
    nlohmann::ordered_json x{{"name", c.name}, {"unit", c.angular ? "rad" : "mm"}, {"value", c.value}};
    if (std::isfinite(c.u)) x["u"] = c.u;
    cs.push_back(x);
  }
  j["notes"] = d.notes;
  if (d.point_sets > 0) j["point_sets"] = {{"count", d.point_sets}, {"points", d.point_set_points}};
  auto& ws = j["warnings"] = nlohmann::ordered_json::array();
  for (const auto& w : d.warnings) ws.push_back({{"line", w.line}, {"what", w.what}});
  return j.dump(2) + "\n";
}

}  // namespace probeloop::interop
