#include "report/ttp_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "report/gltf_builder.hpp"

namespace probeloop::report {

std::array<double, 4> TtpColourScale::colour(double change_um) const {
  const double t = std::clamp(change_um / limit_um, -1.0, 1.0);
  const auto& end = t < 0 ? kNegative : kPositive;
  const double a = std::abs(t);
  return {kZero[0] + a * (end[0] - kZero[0]), kZero[1] + a * (end[1] - kZero[1]), kZero[2] + a * (end[2] - kZero[2]),
          1.0};
}

double ttpColourLimit(double max_abs_change_um) {
  if (!(max_abs_change_um > 0) || !std::isfinite(max_abs_change_um)) return 1.0;
  const double decade = std::pow(10.0, std::floor(std::log10(max_abs_change_um)));
  for (const double step : {1.0, 2.0, 5.0, 10.0})
    if (step * decade >= max_abs_change_um * (1 - 1e-12)) return step * decade;
  return 10.0 * decade;
}

namespace {

using nlohmann::json;
using namespace gltf;
using Eigen::Vector3d;

constexpr int kCircleSegments = 128;
const Rgba kDatumGrey = {0.55, 0.55, 0.58, 1.0};
const Rgba kUnknownGrey = {0.30, 0.30, 0.30, 1.0};
const Rgba kOutline = {0.15, 0.15, 0.15, 1.0};
const Rgba kVector = {0.05, 0.05, 0.05, 1.0};

std::optional<double> finiteNumber(const json& o, const char* key) {
  if (!o.is_object()) return std::nullopt;
  const auto it = o.find(key);
  if (it == o.end() || !it->is_number()) return std::nullopt;
  const double v = it->get<double>();
  return std::isfinite(v) ? std::optional<double>(v) : std::nullopt;
}

std::string textOf(const json& o, const char* key) {
  if (!o.is_object()) return "";
  const auto it = o.find(key);
  return it != o.end() && it->is_string() ? it->get<std::string>() : "";
}

std::string oneDecimal(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.1f", x);
  std::string s = buf;
  if (s == "-0.0") s = "0.0";
  return s;
}
std::string signedOneDecimal(double x) {
  const std::string s = oneDecimal(x);
  return s[0] == '-' || s == "0.0" ? s : "+" + s;
}
std::string diameterText(double radius_mm) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", 2 * radius_mm);
  return buf;
}

// A measured facet or Z path with its change against its reference.
struct Measured {
  const parts::ManifestFeature* feature = nullptr;
  const json* evaluated = nullptr;
  int cycle = -1;
  bool is_reference = false;
  std::string reference_id;           // "" when the group has no measured reference
  std::optional<double> change_um;    // d - d_ref (facets) or depth - depth_ref (Z paths)
};

bool isMeasuredKind(const parts::ManifestFeature& f) {
  return f.nominal.role == "facet" || f.nominal.role == "z_path";
}

std::optional<double> measure(const Measured& m) {
  if (m.evaluated == nullptr) return std::nullopt;
  return finiteNumber(*m.evaluated, m.feature->nominal.role == "facet" ? "d_mm" : "depth_mm");
}

int referenceCycle(const json& evaluation, const parts::PlanManifest& manifest) {
  if (const auto it = evaluation.find("cycles"); it != evaluation.end() && it->is_array())
    for (const auto& c : *it)
      if (textOf(c, "phase") == "reference" && finiteNumber(c, "cycle")) return static_cast<int>(*finiteNumber(c, "cycle"));
  for (const auto& c : manifest.cut_cycles)
    if (c.phase == "reference") return c.cycle;
  return 0;
}

std::vector<Measured> measuredFeatures(const parts::PlanManifest& manifest, const json& evaluation, int reference) {
  std::map<std::string, const json*> by_id;
  if (const auto it = evaluation.find("features"); it != evaluation.end() && it->is_array())
    for (const auto& f : *it) {
      const std::string id = textOf(f, "id");
      if (id.empty()) continue;
      if (manifest.feature(id) == nullptr)
        throw InputError(manifest.file, 0,
                         "thermal-test-piece scene: the evaluation has feature \"" + id +
                             "\", which this manifest does not have (the evaluation was made with another plan?)");
      by_id.emplace(id, &f);  // the first entry of an id
    }
  std::vector<Measured> out;
  for (const auto& f : manifest.features) {
    if (!isMeasuredKind(f)) continue;
    const auto it = by_id.find(f.nominal.id);
    if (it == by_id.end()) continue;
    Measured m;
    m.feature = &f;
    m.evaluated = it->second;
    const auto c = finiteNumber(*it->second, "cycle");
    m.cycle = c ? static_cast<int>(*c) : f.cycle;
    m.is_reference = m.cycle == reference;
    out.push_back(m);
  }
  for (auto& m : out) {
    const Measured* ref = nullptr;
    for (const auto& r : out)
      if (r.is_reference && r.feature->nominal.group == m.feature->nominal.group &&
          r.feature->nominal.role == m.feature->nominal.role) {
        ref = &r;
        break;
      }
    if (ref == nullptr) continue;
    m.reference_id = ref->feature->nominal.id;
    const auto v = measure(m), v_ref = measure(*ref);
    if (v && v_ref) m.change_um = (*v - *v_ref) * 1e3;
  }
  return out;
}

tinygltf::Value numberValue(double x) { return tinygltf::Value(x); }
tinygltf::Value stringValue(const std::string& s) { return tinygltf::Value(s); }
tinygltf::Value colourValue(const std::array<double, 3>& c) {
  return tinygltf::Value(tinygltf::Value::Array{numberValue(c[0]), numberValue(c[1]), numberValue(c[2])});
}

// A plane quad: CCW seen from its outward normal (u × v = n for v = n × u).
int addQuad(GltfBuilder& b, const std::string& name, const parts::NominalFeature& f, int material) {
  if (!(f.half_u_mm > 0) || !(f.half_v_mm > 0)) return b.addNode(name, -1);  // nothing to draw, no degenerate triangles
  const Vector3d n = f.direction.normalized(), u = f.u.normalized(), v = n.cross(u);
  const Vector3d p = f.point_mm;
  const std::vector<Eigen::Vector3f> corners{
      toMetresF(p - f.half_u_mm * u - f.half_v_mm * v), toMetresF(p + f.half_u_mm * u - f.half_v_mm * v),
      toMetresF(p + f.half_u_mm * u + f.half_v_mm * v), toMetresF(p - f.half_u_mm * u + f.half_v_mm * v)};
  const std::vector<Eigen::Vector3f> normals(4, n.cast<float>());
  const int position = b.addVec3(corners);
  const int normal = b.addVec3(normals);
  const int index = b.addIndices({0, 1, 2, 0, 2, 3});
  const int mesh = b.addMesh(name, primitive(TINYGLTF_MODE_TRIANGLES, position, material, normal, index));
  return b.addNode(name, mesh);
}

int addCircle(GltfBuilder& b, const std::string& name, double radius_mm, double z_mm, int material) {
  std::vector<Eigen::Vector3f> ring;
  for (int i = 0; i < kCircleSegments; ++i) {
    const double a = 2.0 * kPi * i / kCircleSegments;
    ring.push_back(toMetresF(Vector3d(radius_mm * std::cos(a), radius_mm * std::sin(a), z_mm)));
  }
  const int mesh = b.addMesh(name, primitive(TINYGLTF_MODE_LINE_LOOP, b.addVec3(ring), material));
  return b.addNode(name, mesh);
}

// The side of a cylinder (axis along the feature's direction through its point).
int addCylinderBand(GltfBuilder& b, const std::string& name, const parts::NominalFeature& f, int material) {
  const Vector3d axis = f.direction.normalized();
  const Vector3d e1 = (std::abs(axis.z()) < 0.9 ? axis.cross(Vector3d::UnitZ()) : axis.cross(Vector3d::UnitX())).normalized();
  const Vector3d e2 = axis.cross(e1);
  std::vector<Eigen::Vector3f> positions, normals;
  for (int i = 0; i <= kCircleSegments; ++i) {
    const double a = 2.0 * kPi * i / kCircleSegments;
    const Vector3d radial = std::cos(a) * e1 + std::sin(a) * e2;
    for (const double s : {-1.0, 1.0}) {
      positions.push_back(toMetresF(f.point_mm + f.radius_mm * radial + s * f.half_v_mm * axis));
      normals.push_back(radial.cast<float>());
    }
  }
  std::vector<std::uint32_t> indices;
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(kCircleSegments); ++i) {
    const std::uint32_t lo = 2 * i, hi = lo + 1, lo2 = lo + 2, hi2 = lo + 3;  // CCW seen from outside
    indices.insert(indices.end(), {lo, lo2, hi2, lo, hi2, hi});
  }
  const int position = b.addVec3(positions);
  const int normal = b.addVec3(normals);
  const int index = b.addIndices(indices);
  return b.addNode(name, b.addMesh(name, primitive(TINYGLTF_MODE_TRIANGLES, position, material, normal, index)));
}

std::string featureName(const Measured& m) {
  const auto& n = m.feature->nominal;
  const bool facet = n.role == "facet";
  std::string s = (facet ? "facet " : "Z path ") + n.id + " (";
  if (m.is_reference) return s + "reference, cycle " + std::to_string(m.cycle) + ")";
  s += "cycle " + std::to_string(m.cycle) + "): ";
  if (!m.change_um)
    return s + (m.reference_id.empty() ? "no reference measured" : measure(m) ? "reference without a value" : "no value");
  return s + (facet ? oneDecimal(*m.change_um) + " um" : "depth " + signedOneDecimal(*m.change_um) + " um");
}

// Displacement of the surface, mm: facets +Δd along the outward normal; Z paths -Δdepth along +Z.
Vector3d displacementMm(const Measured& m) {
  const double sign = m.feature->nominal.role == "facet" ? 1.0 : -1.0;
  return sign * (*m.change_um * 1e-3) * m.feature->nominal.direction.normalized();
}

double outerRadiusMm(const parts::PlanManifest& manifest) {
  double r = 0;
  for (const auto& f : manifest.features) {
    const auto& n = f.nominal;
    if (n.role == "datum_top") r = std::max(r, n.half_u_mm);
    if (n.kind == "cylinder") r = std::max(r, n.radius_mm);
    r = std::max(r, n.point_mm.head<2>().norm());
  }
  return r > 0 ? r : 100.0;
}

// The colour scale as a bar of kBarSegments quads beside the piece (+X side, in the top
// face's plane, facing +Z), from -limit (at -Y) to +limit (at +Y), one material each.
int addColourBar(GltfBuilder& b, const TtpColourScale& scale, double outer_mm) {
  constexpr int kBarSegments = 11;
  constexpr double kStepMm = 10, kWidthMm = 8;
  const std::string l = oneDecimal(scale.limit_um);
  const std::string name =
      "colour scale: blue -" + l + " um ... grey 0 ... red +" + l + " um (change against the reference)";
  int mesh = -1;
  for (int k = 0; k < kBarSegments; ++k) {
    const double value = scale.limit_um * (2.0 * k / (kBarSegments - 1) - 1.0);
    const auto c = scale.colour(value);
    const int material = b.addMaterial("scale " + oneDecimal(value) + " um", {c[0], c[1], c[2], c[3]}, 0.0, 0.7, true);
    const double x = outer_mm + 15, y = (k - (kBarSegments - 1) / 2.0) * kStepMm;
    const std::vector<Eigen::Vector3f> corners{toMetresF(Vector3d(x, y - kStepMm / 2, 0)),
                                               toMetresF(Vector3d(x + kWidthMm, y - kStepMm / 2, 0)),
                                               toMetresF(Vector3d(x + kWidthMm, y + kStepMm / 2, 0)),
                                               toMetresF(Vector3d(x, y + kStepMm / 2, 0))};
    const int position = b.addVec3(corners);
    const int normal = b.addVec3(std::vector<Eigen::Vector3f>(4, Eigen::Vector3f::UnitZ()));
    const int index = b.addIndices({0, 1, 2, 0, 2, 3});
    auto p = primitive(TINYGLTF_MODE_TRIANGLES, position, material, normal, index);
    if (mesh < 0)
      mesh = b.addMesh(name, std::move(p));
    else
      b.model().meshes[mesh].primitives.push_back(std::move(p));
  }
  return b.addNode(name, mesh);
}

tinygltf::Value sceneExtras(double exaggeration, int reference, const TtpColourScale& scale) {
  tinygltf::Value::Object c;
  c["limit_um"] = numberValue(scale.limit_um);
  c["negative"] = colourValue(TtpColourScale::kNegative);
  c["zero"] = colourValue(TtpColourScale::kZero);
  c["positive"] = colourValue(TtpColourScale::kPositive);
  c["meaning"] = stringValue(
      "change against the same group's reference feature: facets d - d_ref, Z paths depth - depth_ref (um); "
      "linear from zero to the end colours at -limit and +limit, clamped");
  tinygltf::Value::Object o;
  o["exaggeration"] = numberValue(exaggeration);
  o["reference_cycle"] = tinygltf::Value(reference);
  o["colour_scale"] = tinygltf::Value(std::move(c));
  o["deviation_vectors"] = stringValue(
      "surface displacement x exaggeration: facets +(d - d_ref) along the outward normal, Z paths -(depth - depth_ref) "
      "along +Z");
  o["frame"] = stringValue("part frame (docs/thermal-test-piece.md), metres");
  return tinygltf::Value(std::move(o));
}

}  // namespace

std::string thermalTestPieceSceneGltf(const parts::PlanManifest& manifest, const json& evaluation, double exaggeration) {
  if (manifest.kind != "thermal_test_piece")
    throw InputError(manifest.file, 0,
                     "thermal-test-piece scene: the manifest is of kind \"" + manifest.kind +
                         "\", expected \"thermal_test_piece\"");
  if (!evaluation.is_object() || textOf(evaluation, "kind") != "thermal_test_piece")
    throw InputError("", 0,
                     "thermal-test-piece scene: the evaluation is not a thermal-test-piece evaluation (kind \"" +
                         textOf(evaluation, "kind") + "\")");
  if (!std::isfinite(exaggeration)) throw InputError("", 0, "thermal-test-piece scene: the exaggeration must be finite");

  const int reference = referenceCycle(evaluation, manifest);
  const std::vector<Measured> measured = measuredFeatures(manifest, evaluation, reference);
  double max_abs = 0;
  for (const auto& m : measured)
    if (m.change_um) max_abs = std::max(max_abs, std::abs(*m.change_um));
  TtpColourScale scale;
  scale.limit_um = ttpColourLimit(max_abs);
  const std::string factor = formatFactor(exaggeration);

  GltfBuilder b;
  const int datum_material = b.addMaterial("datum grey", kDatumGrey, 0.0, 0.8, true);
  const int outline_material = b.addMaterial("outline", kOutline, 0.0, 1.0);
  int unknown_material = -1;  // added when first needed: an unused material is a validator info
  const int vector_material = b.addMaterial("deviation vector", kVector, 0.0, 1.0);
  std::vector<int> children;

  for (const auto& f : manifest.features) {
    const auto& n = f.nominal;
    if (n.role.rfind("datum", 0) != 0) continue;
    if (n.kind == "cylinder" && n.radius_mm > 0 && n.half_v_mm > 0) {
      children.push_back(addCylinderBand(b, "datum " + n.id + " (band \u00d8" + diameterText(n.radius_mm) + " mm)", n,
                                         datum_material));
    } else if (n.kind == "plane" && n.role == "datum_top" && n.half_u_mm > 0) {
      // The finished top (its extent is the radius of the band that reaches it, not the
      // blank's) is not a full disc (the notches cut through it): its outline only, which also
      // hides nothing of the surfaces below it.
      children.push_back(addCircle(b, "datum " + n.id + " (finished top outline, \u00d8" + diameterText(n.half_u_mm) + " mm)",
                                   n.half_u_mm, n.point_mm.z(), outline_material));
    } else if (n.kind == "plane" && n.half_u_mm > 0 && n.half_v_mm > 0) {
      children.push_back(addQuad(b, "datum " + n.id, n, datum_material));
    }
  }

  for (const auto& m : measured) {
    const std::string name = featureName(m);
    if (!m.change_um && unknown_material < 0)
      unknown_material = b.addMaterial("change unknown", kUnknownGrey, 0.0, 0.8, true);
    int material = unknown_material;
    if (m.change_um) {
      const auto c = scale.colour(*m.change_um);
      material = b.addMaterial("change " + oneDecimal(*m.change_um) + " um", {c[0], c[1], c[2], c[3]}, 0.0, 0.7, true);
    }
    const int node = addQuad(b, name, m.feature->nominal, material);
    tinygltf::Value::Object extras;
    extras["feature"] = stringValue(m.feature->nominal.id);
    extras["cycle"] = tinygltf::Value(m.cycle);
    extras["reference"] = stringValue(m.reference_id);
    if (m.change_um) extras["change_um"] = numberValue(*m.change_um);
    b.model().nodes[node].extras = tinygltf::Value(std::move(extras));
    children.push_back(node);
    if (m.change_um && !m.is_reference && *m.change_um != 0.0 && exaggeration != 0.0) {
      const Vector3d from = m.feature->nominal.point_mm;
      const Vector3d to = from + exaggeration * displacementMm(m);
      const std::string vname = "deviation " + m.feature->nominal.id + " (x" + factor + ")";
      const int mesh =
          b.addMesh(vname, primitive(TINYGLTF_MODE_LINE, b.addVec3({toMetresF(from), toMetresF(to)}), vector_material));
      children.push_back(b.addNode(vname, mesh));
    }
  }
  children.push_back(addColourBar(b, scale, outerRadiusMm(manifest)));

  return b.serialise("part frame (Z up, m)", std::move(children), "probeloop thermal test piece",
                     sceneExtras(exaggeration, reference, scale));
}

}  // namespace probeloop::report
