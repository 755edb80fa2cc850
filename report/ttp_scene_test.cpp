#include "report/ttp_scene.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/error.hpp"
#include "parts/thermal_test_piece.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
constexpr double kExaggeration = 1000.0;

// The shipped piece's features as a plan manifest would carry them: facet and path k are cut
// in the cycle c with order[c] = k.
parts::PlanManifest ttpManifest() {
  const auto t = parts::loadThermalTestPiece(std::string(PROBELOOP_SOURCE_DIR) + "/parts/thermal_test_piece.yaml");
  parts::PlanManifest m;
  m.file = "plan/plan.json";
  m.kind = "thermal_test_piece";
  for (const auto& n : parts::nominalFeatures(t)) {
    parts::ManifestFeature f;
    f.nominal = n;
    if (n.role == "facet" || n.role == "z_path")
      for (std::size_t c = 0; c < t.order.size(); ++c)
        if (t.order[c] == n.index) f.cycle = static_cast<int>(c);
    m.features.push_back(f);
  }
  for (const auto& c : parts::cuttingCycles(t)) {
    parts::ManifestCycle mc;
    mc.cycle = c.cycle;
    mc.phase = c.phase;
    m.cut_cycles.push_back(mc);
  }
  return m;
}

// Changes against the reference (um) by cycle c: Z paths 3 c deeper; facets X1 -2.05 c,
// Y1 +c, X2 +2 c, Y2 -c. The largest |change| is 24 um (Z, cycle 8): colour limit 50 um.
double facetChangeUm(const std::string& group, int c) {
  if (group == "X1") return -2.05 * c;
  if (group == "Y1") return 1.0 * c;
  if (group == "X2") return 2.0 * c;
  return -1.0 * c;
}

json evaluationFor(const parts::PlanManifest& m) {
  json features = json::array(), cycles = json::array();
  for (const auto& f : m.features) {
    const auto& n = f.nominal;
    if (n.role == "facet")
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", n.index}, {"cycle", f.cycle},
                          {"d_mm", 97.5 + 1e-3 * facetChangeUm(n.group, f.cycle)}, {"depth_mm", nullptr}});
    else if (n.role == "z_path")
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", n.index}, {"cycle", f.cycle},
                          {"depth_mm", 12.1 + 3e-3 * f.cycle}, {"d_mm", nullptr}});
    else
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", 0}, {"cycle", nullptr}});
  }
  for (int c = 0; c <= 8; ++c)
    cycles.push_back({{"cycle", c}, {"phase", c == 0 ? "reference" : c <= 4 ? "warm_up" : "hold"},
                      {"time_s", 1200 + 3600 * c}, {"values", json::array()}});
  return {{"format", "probeloop-evaluation"}, {"version", 1},         {"kind", "thermal_test_piece"},
          {"features", features},           {"cycles", cycles}};
}

tinygltf::Model parse(const std::string& text) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadASCIIFromString(&model, &err, &warn, text.c_str(), static_cast<unsigned int>(text.size()), "");
  EXPECT_TRUE(ok) << err;
  EXPECT_EQ(warn, "");
  return model;
}

const tinygltf::Node* findNode(const tinygltf::Model& model, const std::string& name) {
  for (const auto& n : model.nodes)
    if (n.name == name) return &n;
  return nullptr;
}

std::vector<Eigen::Vector3f> positions(const tinygltf::Model& model, const tinygltf::Node& node) {
  const auto& prim = model.meshes.at(node.mesh).primitives.at(0);
  const auto& acc = model.accessors.at(prim.attributes.at("POSITION"));
  const auto& view = model.bufferViews.at(acc.bufferView);
  const auto& data = model.buffers.at(view.buffer).data;
  std::vector<Eigen::Vector3f> out;
  for (std::size_t i = 0; i < acc.count; ++i) {
    Eigen::Vector3f v;
    std::memcpy(v.data(), data.data() + view.byteOffset + acc.byteOffset + i * 3 * sizeof(float), 3 * sizeof(float));
    out.push_back(v);
  }
  return out;
}

std::vector<double> baseColour(const tinygltf::Model& model, const tinygltf::Node& node) {
  return model.materials.at(model.meshes.at(node.mesh).primitives.at(0).material).pbrMetallicRoughness.baseColorFactor;
}

class TtpScene : public ::testing::Test {
 protected:
  parts::PlanManifest manifest = ttpManifest();
  json evaluation = evaluationFor(manifest);
  std::string text = thermalTestPieceSceneGltf(manifest, evaluation, kExaggeration);
  tinygltf::Model model = parse(text);
};

TEST(TtpColourScale, LimitAndColours) {
  EXPECT_DOUBLE_EQ(ttpColourLimit(24.0), 50.0);
  EXPECT_DOUBLE_EQ(ttpColourLimit(4.1), 5.0);
  EXPECT_DOUBLE_EQ(ttpColourLimit(5.0), 5.0);
  EXPECT_DOUBLE_EQ(ttpColourLimit(0.13), 0.2);
  EXPECT_DOUBLE_EQ(ttpColourLimit(0.0), 1.0);
  const TtpColourScale s{10.0};
  EXPECT_EQ(s.colour(0.0), (std::array<double, 4>{0.90, 0.90, 0.90, 1.0}));
  const auto red = s.colour(25.0);  // clamped
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(red[i], TtpColourScale::kPositive[i], 1e-12);
  const auto half = s.colour(-5.0);
  EXPECT_NEAR(half[0], (0.90 + 0.13) / 2, 1e-12);
  EXPECT_NEAR(half[2], (0.90 + 0.75) / 2, 1e-12);
}

TEST_F(TtpScene, OneQuadPerMeasuredFeatureWithNamesThatSayWhatTheyAre) {
  int facets = 0, paths = 0, vectors = 0;
  for (const auto& n : model.nodes) {
    if (n.name.rfind("facet ", 0) == 0) {
      ++facets;
      ASSERT_GE(n.mesh, 0) << n.name;
      EXPECT_EQ(positions(model, n).size(), 4u) << n.name;
    }
    if (n.name.rfind("Z path ", 0) == 0) ++paths;
    if (n.name.rfind("deviation ", 0) == 0) ++vectors;
  }
  EXPECT_EQ(facets, 36);
  EXPECT_EQ(paths, 9);
  EXPECT_EQ(vectors, 45 - 5);  // the references (Z5 and the four facets 5) have none
  for (const char* name : {"facet X1_2 (cycle 2): -4.1 um", "facet X1_5 (reference, cycle 0)",
                           "Z path Z1 (cycle 1): depth +3.0 um", "Z path Z9 (cycle 8): depth +24.0 um",
                           "datum TOP (finished top outline, \u00d8199 mm)", "datum FLANK_P", "datum FLANK_N",
                           "datum CYL (band \u00d8201 mm)", "deviation X1_2 (x1000)",
                           "colour scale: blue -50.0 um ... grey 0 ... red +50.0 um (change against the reference)"})
    EXPECT_NE(findNode(model, name), nullptr) << name;
  // The outline is the finished top (the TOP feature's extent), not the blank.
  const auto* top = findNode(model, "datum TOP (finished top outline, \u00d8199 mm)");
  ASSERT_NE(top, nullptr);
  EXPECT_DOUBLE_EQ(manifest.feature("TOP")->nominal.half_u_mm, 99.5);
  for (const auto& p : positions(model, *top)) EXPECT_NEAR(p.head<2>().norm(), 99.5e-3, 1e-7);
  // Fewer measured features: fewer quads.
  json partial = evaluation;
  partial["features"].erase(partial["features"].end() - 1);  // the last facet (Y2_9)
  const auto m2 = parse(thermalTestPieceSceneGltf(manifest, partial, kExaggeration));
  int facets2 = 0;
  for (const auto& n : m2.nodes) facets2 += n.name.rfind("facet ", 0) == 0;
  EXPECT_EQ(facets2, 35);
}

TEST_F(TtpScene, QuadAtTheNominalPlaceColouredByItsChange) {
  const auto* node = findNode(model, "facet X1_2 (cycle 2): -4.1 um");
  ASSERT_NE(node, nullptr);
  const parts::NominalFeature& f = manifest.feature("X1_2")->nominal;
  const Eigen::Vector3d v = f.direction.cross(f.u);
  const auto corners = positions(model, *node);
  const Eigen::Vector3d c0 = (f.point_mm - f.half_u_mm * f.u - f.half_v_mm * v) * 1e-3;
  const Eigen::Vector3d c2 = (f.point_mm + f.half_u_mm * f.u + f.half_v_mm * v) * 1e-3;
  EXPECT_LT((corners[0].cast<double>() - c0).norm(), 1e-7);
  EXPECT_LT((corners[2].cast<double>() - c2).norm(), 1e-7);
  // -4.1 um on the +-50 um scale: 8.2 % of the way from grey to blue.
  const auto colour = baseColour(model, *node);
  ASSERT_EQ(colour.size(), 4u);
  const double t = 4.1 / 50.0;
  EXPECT_NEAR(colour[0], 0.90 + t * (0.13 - 0.90), 1e-9);
  EXPECT_NEAR(colour[1], 0.90 + t * (0.30 - 0.90), 1e-9);
  EXPECT_NEAR(colour[2], 0.90 + t * (0.75 - 0.90), 1e-9);
  EXPECT_NEAR(node->extras.Get("change_um").GetNumberAsDouble(), -4.1, 1e-9);
  EXPECT_EQ(node->extras.Get("reference").Get<std::string>(), "X1_5");
  // Z9, +24 um deeper: 48 % of the way to red.
  const auto z9 = baseColour(model, *findNode(model, "Z path Z9 (cycle 8): depth +24.0 um"));
  EXPECT_NEAR(z9[0], 0.90 + 0.48 * (0.80 - 0.90), 1e-9);
  EXPECT_NEAR(z9[1], 0.90 + 0.48 * (0.12 - 0.90), 1e-9);
  // The reference: grey.
  EXPECT_NEAR(baseColour(model, *findNode(model, "facet X1_5 (reference, cycle 0)"))[0], 0.90, 1e-12);
}

TEST_F(TtpScene, DeviationVectorIsTheExaggeratedSurfaceDisplacement) {
  // Facet X1_2: d 4.1 um smaller -> 4.1 mm inward along its normal at x1000.
  const parts::NominalFeature& f = manifest.feature("X1_2")->nominal;
  const auto* vx = findNode(model, "deviation X1_2 (x1000)");
  ASSERT_NE(vx, nullptr);
  EXPECT_EQ(model.meshes[vx->mesh].primitives[0].mode, TINYGLTF_MODE_LINE);
  const auto ends = positions(model, *vx);
  ASSERT_EQ(ends.size(), 2u);
  EXPECT_LT((ends[0].cast<double>() - f.point_mm * 1e-3).norm(), 1e-7);
  EXPECT_LT((ends[1].cast<double>() - (f.point_mm - 4.1 * f.direction) * 1e-3).norm(), 1e-7);
  // Z path Z1: 3 um deeper -> the floor 3 mm lower at x1000.
  const parts::NominalFeature& z = manifest.feature("Z1")->nominal;
  const auto zends = positions(model, *findNode(model, "deviation Z1 (x1000)"));
  EXPECT_LT((zends[1].cast<double>() - (z.point_mm - Eigen::Vector3d(0, 0, 3.0)) * 1e-3).norm(), 1e-7);
}

TEST_F(TtpScene, ScaleAndExaggerationInExtras) {
  ASSERT_EQ(model.scenes.size(), 1u);
  const auto& e = model.scenes[0].extras;
  EXPECT_DOUBLE_EQ(e.Get("exaggeration").GetNumberAsDouble(), kExaggeration);
  EXPECT_EQ(e.Get("reference_cycle").GetNumberAsInt(), 0);
  EXPECT_DOUBLE_EQ(e.Get("colour_scale").Get("limit_um").GetNumberAsDouble(), 50.0);
  EXPECT_DOUBLE_EQ(model.asset.extras.Get("colour_scale").Get("limit_um").GetNumberAsDouble(), 50.0);
}

TEST_F(TtpScene, IsDeterministic) { EXPECT_EQ(thermalTestPieceSceneGltf(manifest, evaluation, kExaggeration), text); }

TEST_F(TtpScene, MissingValueOrReferenceIsDarkGreyWithoutVector) {
  json e = evaluation;
  for (auto& f : e["features"]) {
    if (f["id"] == "X2_5") f["d_mm"] = nullptr;  // the X2 reference without a value
    if (f["id"] == "Y1_3") f["d_mm"] = nullptr;
  }
  const auto m = parse(thermalTestPieceSceneGltf(manifest, e, kExaggeration));
  const auto* x2 = findNode(m, "facet X2_2 (cycle 2): reference without a value");
  ASSERT_NE(x2, nullptr);
  EXPECT_NEAR(baseColour(m, *x2)[0], 0.30, 1e-12);
  EXPECT_EQ(findNode(m, "deviation X2_2 (x1000)"), nullptr);
  EXPECT_NE(findNode(m, "facet Y1_3 (cycle 3): no value"), nullptr);
}

TEST_F(TtpScene, RefusesFilesThatDoNotBelongTogether) {
  json e = evaluation;
  e["features"].push_back({{"id", "X7_1"}, {"d_mm", 1.0}, {"cycle", 1}});
  try {
    thermalTestPieceSceneGltf(manifest, e, kExaggeration);
    FAIL() << "expected InputError";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("X7_1"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find("plan/plan.json"), std::string::npos) << err.what();
  }
  parts::PlanManifest sphere = manifest;
  sphere.kind = "sphere_artifact";
  EXPECT_THROW(thermalTestPieceSceneGltf(sphere, evaluation, kExaggeration), InputError);
  json other = evaluation;
  other["kind"] = "sphere_artifact";
  EXPECT_THROW(thermalTestPieceSceneGltf(manifest, other, kExaggeration), InputError);
  EXPECT_THROW(thermalTestPieceSceneGltf(manifest, evaluation, NAN), InputError);
}

TEST_F(TtpScene, KhronosValidatorReportsNoErrorsOrWarnings) {
  namespace fs = std::filesystem;
  const fs::path tools = fs::path(PROBELOOP_SOURCE_DIR) / "tests" / "tools";
  const bool have_node = std::system("command -v node >/dev/null 2>&1") == 0;
  const bool have_validator = fs::exists(tools / "node_modules" / "gltf-validator" / "package.json");
  ASSERT_TRUE(have_node && have_validator) << "glTF validator not set up; run: npm ci --prefix " << tools.string();
  const std::string stem = "probeloop_ttp_scene_test_" + std::to_string(::getpid());
  const fs::path gltf = fs::temp_directory_path() / (stem + ".gltf");
  const fs::path log = fs::temp_directory_path() / (stem + ".log");
  std::ofstream(gltf, std::ios::binary) << text;
  const std::string command =
      "node '" + (tools / "validate_gltf.mjs").string() + "' '" + gltf.string() + "' >'" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  std::stringstream output;
  output << std::ifstream(log).rdbuf();
  fs::remove(gltf);
  fs::remove(log);
  std::cout << output.str();
  ASSERT_TRUE(WIFEXITED(status)) << command;
  EXPECT_EQ(WEXITSTATUS(status), 0) << "validator failed (its output is above): " << command;
  EXPECT_NE(output.str().find("errors=0 warnings=0"), std::string::npos) << "issues listed above";
}

}  // namespace
}  // namespace probeloop::report
