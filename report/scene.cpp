#include "report/scene.hpp"

// Debian's libtinygltf ships the implementation as a shared library (TinyGLTF::TinyGLTF),
// so this file only includes the declarations: no TINYGLTF_IMPLEMENTATION here, and no
// TINYGLTF_NO_* defines either (they only change default member initialisers, and keeping
// the library's defaults keeps us identical to how it was built).
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <locale>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "core/units.hpp"

namespace probeloop::report {
namespace {

// glTF buffers are little-endian; we copy host floats and integers byte for byte.
static_assert(std::endian::native == std::endian::little, "glTF writer assumes little-endian");

constexpr double kMetresPerMm = 1e-3;

// Tessellation: fine enough to look round at report scale, small enough to keep the
// embedded base64 in the tens of kilobytes.
constexpr int kTableSegments = 96;
constexpr int kSphereSlices = 32;
constexpr int kSphereStacks = 16;

// glTF viewers take +Y as up; the machine frame has +Z up. The root node turns the
// machine frame (-90 deg about X: machine +Z -> glTF +Y) so every vertex can stay in
// machine coordinates.
const std::vector<double> kMachineToGltfRotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};

using Rgba = std::array<double, 4>;

Eigen::Vector3f toMetresF(const Eigen::Vector3d& p_mm) {
  return (p_mm * kMetresPerMm).cast<float>();
}

// "10000" for integral factors, shortest "%g"-style text otherwise; used in node names.
std::string formatFactor(double factor) {
  if (std::abs(factor) < 1e12 && factor == std::round(factor))
    return std::to_string(static_cast<long long>(std::llround(factor)));
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << factor;
  return s.str();
}

// Accumulates one embedded buffer plus the views, accessors, meshes, materials and nodes
// that refer to it. Every view starts on a 4-byte boundary so any component type is
// aligned (glTF §3.6.2.4).
class GltfBuilder {
 public:
  GltfBuilder() { model_.buffers.emplace_back(); }

  // VEC3 float accessor; min/max come from the float values actually stored, because
  // the validator compares them exactly.
  int addVec3(const std::vector<Eigen::Vector3f>& values) {
    std::vector<double> min_v(3, std::numeric_limits<double>::infinity());
    std::vector<double> max_v(3, -std::numeric_limits<double>::infinity());
    std::vector<float> flat;
    flat.reserve(values.size() * 3);
    for (const auto& v : values) {
      for (int i = 0; i < 3; ++i) {
        min_v[i] = std::min(min_v[i], static_cast<double>(v(i)));
        max_v[i] = std::max(max_v[i], static_cast<double>(v(i)));
        flat.push_back(v(i));
      }
    }
    tinygltf::Accessor a;
    a.bufferView = addView(flat.data(), flat.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.type = TINYGLTF_TYPE_VEC3;
    a.count = values.size();
    a.minValues = std::move(min_v);
    a.maxValues = std::move(max_v);
    return push(model_.accessors, std::move(a));
  }

  // Index accessor: 16-bit when every index fits below 65535 (the primitive-restart
  // value, which glTF forbids as an index), else 32-bit.
  int addIndices(const std::vector<std::uint32_t>& indices) {
    const std::uint32_t max_index =
        indices.empty() ? 0 : *std::max_element(indices.begin(), indices.end());
    tinygltf::Accessor a;
    if (max_index < 65535) {
      std::vector<std::uint16_t> narrow(indices.begin(), indices.end());
      a.bufferView = addView(narrow.data(), narrow.size() * sizeof(std::uint16_t),
                             TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    } else {
      a.bufferView = addView(indices.data(), indices.size() * sizeof(std::uint32_t),
                             TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    }
    a.type = TINYGLTF_TYPE_SCALAR;
    a.count = indices.size();
    return push(model_.accessors, std::move(a));
  }

  int addMaterial(const std::string& name, const Rgba& base_colour, double metallic,
                  double roughness, bool double_sided = false) {
    tinygltf::Material m;
    m.name = name;
    m.pbrMetallicRoughness.baseColorFactor.assign(base_colour.begin(), base_colour.end());
    m.pbrMetallicRoughness.metallicFactor = metallic;
    m.pbrMetallicRoughness.roughnessFactor = roughness;
    m.doubleSided = double_sided;
    return push(model_.materials, std::move(m));
  }

  int addMesh(const std::string& name, tinygltf::Primitive primitive) {
    tinygltf::Mesh mesh;
    mesh.name = name;
    mesh.primitives.push_back(std::move(primitive));
    return push(model_.meshes, std::move(mesh));
  }

  // mesh < 0: a named node without geometry (e.g. a cycle with no usable centres).
  int addNode(const std::string& name, int mesh,
              const Eigen::Vector3d& translation_m = Eigen::Vector3d::Zero()) {
    tinygltf::Node node;
    node.name = name;
    node.mesh = mesh;
    if (translation_m != Eigen::Vector3d::Zero())
      node.translation = {translation_m.x(), translation_m.y(), translation_m.z()};
    return push(model_.nodes, std::move(node));
  }

  tinygltf::Model& model() { return model_; }

 private:
  template <class T>
  static int push(std::vector<T>& list, T item) {
    list.push_back(std::move(item));
    return static_cast<int>(list.size()) - 1;
  }

  int addView(const void* bytes, std::size_t byte_length, int target) {
    auto& data = model_.buffers[0].data;
    data.resize((data.size() + 3) / 4 * 4, 0);  // zero padding keeps output deterministic
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = byte_length;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(bytes);
    data.insert(data.end(), p, p + byte_length);
    return push(model_.bufferViews, std::move(view));
  }

  tinygltf::Model model_;
};

struct Materials {
  int table, axis, sphere, vectors, points;
};

Materials addMaterials(GltfBuilder& b) {
  Materials m{};
  m.table = b.addMaterial("table grey", {0.45, 0.45, 0.47, 1.0}, 0.0, 0.8, true);
  m.axis = b.addMaterial("axis green", {0.1, 0.6, 0.2, 1.0}, 0.0, 1.0);
  m.sphere = b.addMaterial("sphere silver", {0.85, 0.85, 0.88, 1.0}, 1.0, 0.25);
  m.vectors = b.addMaterial("error vector red", {0.9, 0.05, 0.05, 1.0}, 0.0, 1.0);
  m.points = b.addMaterial("probe point blue", {0.1, 0.25, 0.95, 1.0}, 0.0, 1.0);
  return m;
}

tinygltf::Primitive primitive(int mode, int position, int material, int normal = -1,
                              int indices = -1) {
  tinygltf::Primitive p;
  p.mode = mode;
  p.attributes["POSITION"] = position;
  if (normal >= 0) p.attributes["NORMAL"] = normal;
  p.indices = indices;
  p.material = material;
  return p;
}

// Triangle fan as an indexed triangle list (centre vertex 0, rim 1..n), facing +Z.
int addTableNode(GltfBuilder& b, const parts::PlanManifest& m, int material) {
  const double radius_mm = m.radius_from_axis_mm + 2.0 * m.sphere_radius_mm;
  const Eigen::Vector3d centre_mm(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(),
                                  m.table_surface_z_mm);
  std::vector<Eigen::Vector3f> positions{toMetresF(centre_mm)};
  for (int i = 0; i < kTableSegments; ++i) {
    const double a = 2.0 * kPi * i / kTableSegments;
    positions.push_back(
        toMetresF(centre_mm + radius_mm * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0)));
  }
  std::vector<std::uint32_t> indices;
  for (std::uint32_t i = 1; i <= kTableSegments; ++i)
    indices.insert(indices.end(), {0u, i, i % kTableSegments + 1});  // CCW seen from +Z
  const std::vector<Eigen::Vector3f> normals(positions.size(), Eigen::Vector3f::UnitZ());
  // Separate statements: argument evaluation order is unspecified, and the accessor order
  // must not depend on the compiler for the output to be deterministic.
  const int position = b.addVec3(positions);
  const int normal = b.addVec3(normals);
  const int index = b.addIndices(indices);
  const int mesh =
      b.addMesh("table", primitive(TINYGLTF_MODE_TRIANGLES, position, material, normal, index));
  return b.addNode("table", mesh);
}

// From a little below the table to above the highest sphere, so it reads as an axis.
int addAxisNode(GltfBuilder& b, const parts::PlanManifest& m, int material) {
  const double table_radius_mm = m.radius_from_axis_mm + 2.0 * m.sphere_radius_mm;
  double top_z_mm = m.table_surface_z_mm + table_radius_mm;
  for (const auto& s : m.spheres)
    top_z_mm = std::max(top_z_mm, s.nominal_centre_mm.z() + 2.0 * m.sphere_radius_mm);
  const double bottom_z_mm = m.table_surface_z_mm - 0.25 * table_radius_mm;
  const Eigen::Vector3d axis_mm(m.c_axis_centre_mm.x(), m.c_axis_centre_mm.y(), 0.0);
  const std::vector<Eigen::Vector3f> ends{
      toMetresF(axis_mm + bottom_z_mm * Eigen::Vector3d::UnitZ()),
      toMetresF(axis_mm + top_z_mm * Eigen::Vector3d::UnitZ())};
  const int mesh = b.addMesh("C axis", primitive(TINYGLTF_MODE_LINE, b.addVec3(ends), material));
  return b.addNode("C axis", mesh);
}

// UV sphere about the origin; each sphere node places it by translation. Rows 0 and
// kSphereStacks are the poles, where one triangle per quad is dropped so no triangle is
// degenerate.
int addSphereMesh(GltfBuilder& b, double radius_m, int material) {
  std::vector<Eigen::Vector3f> positions, normals;
  for (int i = 0; i <= kSphereStacks; ++i) {
    const double polar = kPi * i / kSphereStacks;
    for (int j = 0; j <= kSphereSlices; ++j) {
      const double azimuth = 2.0 * kPi * j / kSphereSlices;
      const Eigen::Vector3d n(std::sin(polar) * std::cos(azimuth),
                              std::sin(polar) * std::sin(azimuth), std::cos(polar));
      normals.push_back(n.normalized().cast<float>());
      positions.push_back((radius_m * n).cast<float>());
    }
  }
  std::vector<std::uint32_t> indices;
  constexpr std::uint32_t row = kSphereSlices + 1;
  for (std::uint32_t i = 0; i < kSphereStacks; ++i) {
    for (std::uint32_t j = 0; j < kSphereSlices; ++j) {
      const std::uint32_t a = i * row + j, below = a + row;  // CCW seen from outside
      if (i != 0) indices.insert(indices.end(), {a, below, a + 1});
      if (i + 1 != kSphereStacks) indices.insert(indices.end(), {a + 1, below, below + 1});
    }
  }
  const int position = b.addVec3(positions);
  const int normal = b.addVec3(normals);
  const int index = b.addIndices(indices);
  return b.addMesh("sphere", primitive(TINYGLTF_MODE_TRIANGLES, position, material, normal, index));
}

int addProbePointsNode(GltfBuilder& b, const parts::PlanManifest& m, int material) {
  if (m.points.empty()) return b.addNode("probe points", -1);  // a POINTS accessor needs count >= 1
  std::vector<Eigen::Vector3f> positions;
  for (const auto& p : m.points) positions.push_back(toMetresF(p.contact_mm));
  const int mesh =
      b.addMesh("probe points", primitive(TINYGLTF_MODE_POINTS, b.addVec3(positions), material));
  return b.addNode("probe points", mesh);
}

// One line per position that has a centre in both this cycle and the reference cycle.
int addErrorVectorNode(GltfBuilder& b, const parts::PlanManifest& m, const CycleCentres& cycle,
                       const CycleCentres& reference, double exaggeration, int material) {
  std::vector<Eigen::Vector3f> ends;
  for (std::size_t k = 0; k < m.spheres.size(); ++k) {
    if (!cycle.centre_mm[k] || !reference.centre_mm[k]) continue;
    const Eigen::Vector3d& nominal_mm = m.spheres[k].nominal_centre_mm;
    const Eigen::Vector3d shift_mm = *cycle.centre_mm[k] - *reference.centre_mm[k];
    ends.push_back(toMetresF(nominal_mm));
    ends.push_back(toMetresF(nominal_mm + exaggeration * shift_mm));
  }
  const std::string label = "error vectors cycle " + std::to_string(cycle.cycle);
  const std::string name = label + " (x" + formatFactor(exaggeration) + ")";
  if (ends.empty()) return b.addNode(name, -1);  // keeps one node per cycle, no empty accessor
  return b.addNode(name,
                   b.addMesh(label, primitive(TINYGLTF_MODE_LINE, b.addVec3(ends), material)));
}

// Everything that would otherwise end up as a NaN, an empty or a degenerate object in
// the file is refused here with a message that says what is wrong.
const CycleCentres& checkInputs(const parts::PlanManifest& m,
                                const std::vector<CycleCentres>& cycles, int reference_cycle,
                                double exaggeration) {
  if (!(m.sphere_radius_mm > 0) || !(m.radius_from_axis_mm >= 0))
    throw GeometryError(
        "glTF scene: needs sphere_radius_mm > 0 and radius_from_axis_mm >= 0 (got " +
        std::to_string(m.sphere_radius_mm) + " and " + std::to_string(m.radius_from_axis_mm) + ")");
  if (!std::isfinite(exaggeration))
    throw InputError("", 0, "glTF scene: the exaggeration factor must be finite");
  const CycleCentres* reference = nullptr;
  for (const auto& c : cycles) {
    if (c.centre_mm.size() != m.spheres.size())
      throw InputError("", 0,
                       "glTF scene: cycle " + std::to_string(c.cycle) + " has " +
                           std::to_string(c.centre_mm.size()) + " centres, expected " +
                           std::to_string(m.spheres.size()) + " (one per manifest sphere)");
    for (const auto& centre : c.centre_mm)
      if (centre && !centre->allFinite())
        throw InputError(
            "", 0,
            "glTF scene: cycle " + std::to_string(c.cycle) + " has a non-finite sphere centre");
    if (c.cycle == reference_cycle) reference = &c;
  }
  if (!reference)
    throw InputError("", 0,
                     "glTF scene: reference cycle " + std::to_string(reference_cycle) +
                         " is not among the cycles given");
  return *reference;
}

tinygltf::Value extras(double exaggeration, int reference_cycle) {
  tinygltf::Value::Object o;
  o["exaggeration"] = tinygltf::Value(exaggeration);
  o["reference_cycle"] = tinygltf::Value(reference_cycle);
  return tinygltf::Value(std::move(o));
}

}  // namespace

std::string campaignSceneGltf(const parts::PlanManifest& manifest,
                              const std::vector<CycleCentres>& cycles, int reference_cycle,
                              double exaggeration) {
  const CycleCentres& reference = checkInputs(manifest, cycles, reference_cycle, exaggeration);

  GltfBuilder b;
  const Materials mat = addMaterials(b);
  std::vector<int> children;
  children.push_back(addTableNode(b, manifest, mat.table));
  children.push_back(addAxisNode(b, manifest, mat.axis));
  const int sphere_mesh = addSphereMesh(b, manifest.sphere_radius_mm * kMetresPerMm, mat.sphere);
  for (const auto& s : manifest.spheres)
    children.push_back(
        b.addNode("sphere " + s.id, sphere_mesh, s.nominal_centre_mm * kMetresPerMm));
  children.push_back(addProbePointsNode(b, manifest, mat.points));
  for (const auto& c : cycles)
    if (c.cycle != reference_cycle)
      children.push_back(addErrorVectorNode(b, manifest, c, reference, exaggeration, mat.vectors));

  tinygltf::Model& model = b.model();
  tinygltf::Node root;
  root.name = "machine frame (Z up, m)";
  root.rotation = kMachineToGltfRotation;
  root.children = std::move(children);
  model.nodes.push_back(std::move(root));

  tinygltf::Scene scene;
  scene.name = "probeloop campaign";
  scene.nodes = {static_cast<int>(model.nodes.size()) - 1};
  // Asset extras for tools that read the file; scene extras because viewers such as
  // three.js surface those (as userData) and drop the asset's.
  scene.extras = extras(exaggeration, reference_cycle);
  model.scenes.push_back(std::move(scene));
  model.defaultScene = 0;
  model.asset.version = "2.0";
  model.asset.generator = "probeloop";
  model.asset.extras = extras(exaggeration, reference_cycle);

  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, out, /*prettyPrint=*/true, /*writeBinary=*/false))
    throw std::runtime_error("glTF scene: tinygltf failed to serialise the model");
  return out.str();
}

}  // namespace probeloop::report
