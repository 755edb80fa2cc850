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
#include "report/gltf_builder.hpp"

namespace probeloop::report {
namespace {

// The glTF writing shared with the thermal-test-piece scene: report/gltf_builder.hpp.
using namespace gltf;

// Tessellation: fine enough to look round at report scale, small enough to keep the
// embedded base64 in the tens of kilobytes.
constexpr int kTableSegments = 96;
constexpr int kSphereSlices = 32;
constexpr int kSphereStacks = 16;

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

  return b.serialise("machine frame (Z up, m)", std::move(children), "probeloop campaign", extras(exaggeration, reference_cycle));
}

}  // namespace probeloop::report
