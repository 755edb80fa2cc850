#include "parts/workpiece.hpp"

#include "core/error.hpp"
#include "parts/yaml_reader.hpp"

namespace probeloop::parts {

const CuttingTool* Workpiece::tool(int number) const {
  for (const auto& t : tools)
    if (t.number == number) return &t;
  return nullptr;
}

std::string partKind(const std::string& path) {
  const YAML::Node n = loadYamlFile(path);
  if (!n.IsMap() || !n["kind"] || !n["kind"].IsScalar())
    throw InputError(path, 1, "kind: expected the kind of part (sphere_artifact, thermal_test_piece or workpiece)");
  return n["kind"].Scalar();
}

namespace {

std::pair<double, double> range(YamlMap& m, const std::string& key) {
  const auto v = m.quantityList(key, Dimension::Length);
  if (v.size() != 2 || !(v[1] > v[0])) m.fail(key, "expected [min, max] with max > min");
  return {v[0], v[1]};
}

}  // namespace

WorkpieceMaterial readMaterial(YamlMap m) {
  WorkpieceMaterial out;
  out.name = m.string("name");
  out.alpha_um_per_m_K = m.number("alpha_um_per_m_K");
  out.alpha_per_K = out.alpha_um_per_m_K * 1e-6;
  out.specific_cutting_force_N_per_mm2 = m.number("specific_cutting_force_N_per_mm2");
  out.radial_force_ratio = m.numberOr("radial_force_ratio", 0.4);
  if (!(out.alpha_per_K >= 0 && out.alpha_per_K < 1e-4))
    m.fail("alpha_um_per_m_K", "expected an expansion coefficient in um/(m K), e.g. 23.4 for aluminium");
  if (!(out.specific_cutting_force_N_per_mm2 > 0)) m.fail("specific_cutting_force_N_per_mm2", "must be positive");
  if (out.radial_force_ratio < 0) m.fail("radial_force_ratio", "must not be negative");
  m.finish();
  return out;
}

std::vector<CuttingTool> readCuttingTools(YamlMap& parent, const std::string& key) {
  std::vector<CuttingTool> out;
  for (auto& t : parent.mapList(key)) {
    CuttingTool c;
    c.number = t.integer("number");
    c.kind = t.choice("kind", {"flat_end_mill", "engraving"});
    c.name = t.stringOr("name", "");
    c.diameter_mm = t.quantity("diameter", Dimension::Length);
    c.length_mm = t.quantity("length", Dimension::Length);
    c.stickout_mm = t.quantity("stickout", Dimension::Length);
    c.flute_length_mm = t.quantity("flute_length", Dimension::Length);
    c.youngs_modulus_N_per_mm2 = t.number("youngs_modulus_GPa") * 1e3;
    c.flutes = t.integerOr("flutes", 3);
    if (!(c.diameter_mm > 0)) t.fail("diameter", "must be positive");
    if (!(c.length_mm > 0)) t.fail("length", "must be positive");
    if (!(c.stickout_mm > 0 && c.stickout_mm <= c.length_mm)) t.fail("stickout", "must be positive and at most the length");
    if (!(c.flute_length_mm > 0 && c.flute_length_mm <= c.stickout_mm))
      t.fail("flute_length", "must be positive and at most the stickout");
    if (!(c.youngs_modulus_N_per_mm2 > 0)) t.fail("youngs_modulus_GPa", "must be positive");
    for (const auto& e : out)
      if (e.number == c.number) t.fail("number", "tool T" + std::to_string(c.number) + " is listed twice");
    t.finish();
    out.push_back(c);
  }
  return out;
}

CmmSpec readCmm(YamlMap c) {
  CmmSpec out;
  out.mpe_constant_um = c.quantity("mpe_constant", Dimension::Micrometre);
  out.mpe_length_mm = c.quantityOr("mpe_length", Dimension::Length, 0);
  out.temperature_half_width_K = c.quantityOr("temperature_half_width", Dimension::Temperature, 0);
  if (out.mpe_constant_um < 0) c.fail("mpe_constant", "must not be negative");
  if (out.mpe_length_mm < 0) c.fail("mpe_length", "must not be negative");
  if (out.temperature_half_width_K < 0) c.fail("temperature_half_width", "must not be negative");
  c.finish();
  return out;
}

Workpiece loadWorkpiece(const std::string& path) {
  YamlMap root(loadYamlFile(path), path, "");
  root.choice("kind", {"workpiece"});
  Workpiece w;
  w.file = path;
  w.name = root.stringOr("name", "workpiece");
  YamlMap s = root.map("stock");
  const auto x = range(s, "x"), y = range(s, "y"), z = range(s, "z");
  w.stock_min_mm = Eigen::Vector3d(x.first, y.first, z.first);
  w.stock_max_mm = Eigen::Vector3d(x.second, y.second, z.second);
  s.finish();
  w.material = readMaterial(root.map("material"));
  w.tools = readCuttingTools(root, "tools");
  if (auto c = root.mapIfPresent("cmm")) w.cmm = readCmm(*c);
  root.finish();
  return w;
}

}  // namespace probeloop::parts
