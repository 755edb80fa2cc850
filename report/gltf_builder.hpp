// The glTF writing the project's scenes share (report/scene, report/ttp_scene): one embedded
// buffer with 4-byte-aligned views, float VEC3 accessors whose min/max are the stored floats
// (the Khronos validator compares them exactly), 16- or 32-bit indices, materials, meshes and
// nodes, in the order they are added (so the output is deterministic when the callers are).
//
// Debian's libtinygltf ships the implementation as a shared library (TinyGLTF::TinyGLTF), so
// this header only includes the declarations.
#pragma once
#include <tiny_gltf.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <locale>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace probeloop::report::gltf {

// glTF buffers are little-endian; we copy host floats and integers byte for byte.
static_assert(std::endian::native == std::endian::little, "glTF writer assumes little-endian");

constexpr double kMetresPerMm = 1e-3;

// glTF viewers take +Y as up; the machine frame has +Z up. The root node turns the
// machine frame (-90 deg about X: machine +Z -> glTF +Y) so every vertex can stay in
// machine coordinates.
inline const std::vector<double> kMachineToGltfRotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};

using Rgba = std::array<double, 4>;

inline Eigen::Vector3f toMetresF(const Eigen::Vector3d& p_mm) {
  return (p_mm * kMetresPerMm).cast<float>();
}

// "10000" for integral factors, shortest "%g"-style text otherwise; used in node names.
inline std::string formatFactor(double factor) {
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

  // The finished file: a root node (the Z-up frame turned to glTF's +Y up) over `children`,
  // one scene holding it, `extras` on the scene (three.js surfaces those as userData) and on
  // the asset (for tools that read the file), pretty-printed JSON with the buffer embedded.
  std::string serialise(const std::string& root_name, std::vector<int> children, const std::string& scene_name,
                        const tinygltf::Value& extras) {
    tinygltf::Node root;
    root.name = root_name;
    root.rotation = kMachineToGltfRotation;
    root.children = std::move(children);
    model_.nodes.push_back(std::move(root));
    tinygltf::Scene scene;
    scene.name = scene_name;
    scene.nodes = {static_cast<int>(model_.nodes.size()) - 1};
    scene.extras = extras;
    model_.scenes.push_back(std::move(scene));
    model_.defaultScene = 0;
    model_.asset.version = "2.0";
    model_.asset.generator = "probeloop";
    model_.asset.extras = extras;
    std::ostringstream out;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model_, out, /*prettyPrint=*/true, /*writeBinary=*/false))
      throw std::runtime_error("glTF scene: tinygltf failed to serialise the model");
    return out.str();
  }

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

inline tinygltf::Primitive primitive(int mode, int position, int material, int normal = -1,
                                     int indices = -1) {
  tinygltf::Primitive p;
  p.mode = mode;
  p.attributes["POSITION"] = position;
  if (normal >= 0) p.attributes["NORMAL"] = normal;
  p.indices = indices;
  p.material = material;
  return p;
}

}  // namespace probeloop::report::gltf
