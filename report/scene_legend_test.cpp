#include "report/scene_legend.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.hpp"
#include "parts/thermal_test_piece.hpp"
#include "report/scene.hpp"
#include "report/ttp_scene.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;

// The shipped thermal test piece as its plan manifest carries it (as in ttp_scene_test.cpp).
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

// Facets change by `facet_um_per_cycle` × cycle, Z paths by `z_um_per_cycle` × cycle (deeper).
json evaluationFor(const parts::PlanManifest& m, double facet_um_per_cycle, double z_um_per_cycle) {
  json features = json::array(), cycles = json::array();
  for (const auto& f : m.features) {
    const auto& n = f.nominal;
    if (n.role == "facet")
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", n.index}, {"cycle", f.cycle},
                          {"d_mm", 97.5 + 1e-3 * facet_um_per_cycle * f.cycle}, {"depth_mm", nullptr}});
    else if (n.role == "z_path")
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", n.index}, {"cycle", f.cycle},
                          {"depth_mm", 12.1 + 1e-3 * z_um_per_cycle * f.cycle}, {"d_mm", nullptr}});
    else
      features.push_back({{"id", n.id}, {"group", n.group}, {"index", 0}, {"cycle", nullptr}});
  }
  for (int c = 0; c <= 8; ++c)
    cycles.push_back({{"cycle", c}, {"phase", c == 0 ? "reference" : c <= 4 ? "warm_up" : "hold"},
                      {"time_s", 1200 + 3600 * c}, {"values", json::array()}});
  return {{"format", "probeloop-evaluation"}, {"version", 1}, {"kind", "thermal_test_piece"},
          {"features", features}, {"cycles", cycles}};
}

const std::string kNoThree = "/nonexistent/three";

std::string ticks(const std::string& html) {
  std::string out;
  for (std::size_t p = html.find("<text class=\"tick\""); p != std::string::npos; p = html.find("<text class=\"tick\"", p + 1)) {
    const std::size_t a = html.find('>', p) + 1, b = html.find("</text>", a);
    out += (out.empty() ? "" : " | ") + html.substr(a, b - a);
  }
  return out;
}

TEST(SceneLegend, TicksComeFromTheScenesColourScale) {
  const auto m = ttpManifest();
  // Z paths 3 µm deeper per cycle: the largest |change| is 24 µm at cycle 8, so the scene's
  // limit is the next 1-2-5 step, 50 µm, and the ticks are ±50, ±25 and 0.
  const std::string scene = thermalTestPieceSceneGltf(m, evaluationFor(m, 1.0, 3.0), 1000);
  const std::string html = sceneLegendHtml(scene, "scene.gltf", kNoThree);
  EXPECT_EQ(ticks(html), "-50 \u00b5m | -25 \u00b5m | 0 | +25 \u00b5m | +50 \u00b5m");
  EXPECT_NE(html.find("<svg id=\"colour-scale\""), std::string::npos);
  // 1 µm per cycle on the Z paths: 8 µm at most, limit 10 µm.
  const std::string small = sceneLegendHtml(thermalTestPieceSceneGltf(m, evaluationFor(m, 0.5, 1.0), 250), "s.gltf", kNoThree);
  EXPECT_EQ(ticks(small), "-10 \u00b5m | -5 \u00b5m | 0 | +5 \u00b5m | +10 \u00b5m");
  // The exaggeration as the scene holds it: x250 draws 1 µm as 0.25 mm.
  EXPECT_NE(small.find("\u00d7250: a displacement of 1 \u00b5m draws 0.25 mm"), std::string::npos);
  EXPECT_NE(html.find("\u00d71000: a displacement of 1 \u00b5m draws 1 mm"), std::string::npos);
}

TEST(SceneLegend, GradientShowsTheScenesColoursInSrgb) {
  const auto m = ttpManifest();
  const std::string html = sceneLegendHtml(thermalTestPieceSceneGltf(m, evaluationFor(m, 1.0, 3.0), 1000), "scene.gltf", kNoThree);
  // Linear 0.90 grey is sRGB 0.9547 = 243 (IEC 61966-2-1); linear 0.13, 0.30, 0.75 = 101, 149, 225.
  EXPECT_NE(html.find("stop-color=\"#f3f3f3\""), std::string::npos);
  EXPECT_NE(html.find("stop-color=\"#6595e1\""), std::string::npos);
}

TEST(SceneLegend, NamesEveryKindOfObjectWithItsCount) {
  const auto m = ttpManifest();
  const std::string html = sceneLegendHtml(thermalTestPieceSceneGltf(m, evaluationFor(m, 1.0, 3.0), 1000), "scene.gltf", kNoThree);
  EXPECT_NE(html.find("<td>facet </td>"), std::string::npos);
  EXPECT_NE(html.find("<td>Z path </td>"), std::string::npos);
  EXPECT_NE(html.find("<td>deviation </td>"), std::string::npos);
  EXPECT_NE(html.find("<td>colour scale</td><td class=\"num\">1</td>"), std::string::npos);
  EXPECT_NE(html.find("<a href=\"scene.gltf\">"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);  // without three.js: nothing to run
  EXPECT_NE(html.find("id=\"no-viewer\""), std::string::npos);
  EXPECT_NE(html.find("libjs-three"), std::string::npos);
}

TEST(SceneLegend, SphereCampaignHasNoColourScaleAndSaysSo) {
  parts::PlanManifest m;
  m.sphere_radius_mm = 15;
  m.radius_from_axis_mm = 160;
  parts::ManifestSphere s;
  s.id = "S1";
  s.position = 1;
  s.nominal_centre_mm = Eigen::Vector3d(160, 0, 40);
  m.spheres.push_back(s);
  std::vector<CycleCentres> cycles{{1, {Eigen::Vector3d(160, 0, 40)}}, {2, {Eigen::Vector3d(160.002, 0, 40)}}};
  const std::string html = sceneLegendHtml(campaignSceneGltf(m, cycles, 1, 10000), "campaign.gltf", kNoThree);
  EXPECT_NE(html.find("id=\"no-colour-scale\""), std::string::npos);
  EXPECT_EQ(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("\u00d710000: a displacement of 1 \u00b5m draws 10 mm"), std::string::npos);
  EXPECT_NE(html.find("reference cycle 1."), std::string::npos);
  EXPECT_NE(html.find("<td>sphere </td><td class=\"num\">1</td><td>sphere S1</td>"), std::string::npos);
  EXPECT_NE(html.find("<td>error vectors cycle </td><td class=\"num\">1</td>"), std::string::npos);
}

TEST(SceneLegend, EscapesTheFileNameIsDeterministicAndRefusesWhatIsNotAScene) {
  const auto m = ttpManifest();
  const std::string scene = thermalTestPieceSceneGltf(m, evaluationFor(m, 1.0, 3.0), 1000);
  const std::string html = sceneLegendHtml(scene, "a<b>&\".gltf", kNoThree);
  EXPECT_EQ(html.find("a<b>"), std::string::npos);
  EXPECT_NE(html.find("a&lt;b&gt;&amp;&quot;.gltf"), std::string::npos);
  EXPECT_EQ(sceneLegendHtml(scene, "x.gltf", kNoThree), sceneLegendHtml(scene, "x.gltf", kNoThree));
  EXPECT_THROW(sceneLegendHtml("not json", "x.gltf", kNoThree), InputError);
  EXPECT_THROW(sceneLegendHtml("[1, 2]", "x.gltf", kNoThree), InputError);
  EXPECT_EQ(sceneLegendPath("out/scene.gltf"), "out/scene.html");
  EXPECT_EQ(sceneLegendPath("out/scene.glb"), "out/scene.glb.html");
}

TEST(SceneLegend, InlinesThreeJsAndTheSceneForAnOfflineView) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("probeloop-three-" + std::to_string(::getpid()));
  fs::create_directories(dir / "examples/js/loaders");
  fs::create_directories(dir / "examples/js/controls");
  std::ofstream(dir / "three.min.js") << "var THREE = {}; /* stand-in */ var s = '</script>';";
  std::ofstream(dir / "examples/js/loaders/GLTFLoader.js") << "THREE.GLTFLoader = function () {};";
  std::ofstream(dir / "examples/js/controls/OrbitControls.js") << "THREE.OrbitControls = function () {};";
  const auto m = ttpManifest();
  const std::string scene = thermalTestPieceSceneGltf(m, evaluationFor(m, 1.0, 3.0), 1000);
  const std::string html = sceneLegendHtml(scene, "scene.gltf", dir.string());
  fs::remove_all(dir);
  EXPECT_NE(html.find("<div id=\"viewer\""), std::string::npos);
  EXPECT_NE(html.find("THREE.GLTFLoader = function"), std::string::npos);
  EXPECT_NE(html.find("THREE.OrbitControls = function"), std::string::npos);
  EXPECT_EQ(html.find("'</script>'"), std::string::npos);  // a literal cannot end the element
  // The scene itself, parsed back from the page, is the scene given.
  const std::string open = "<script type=\"application/json\" id=\"scene-gltf\">";
  const std::size_t a = html.find(open), b = html.find("</script>", a);
  ASSERT_NE(a, std::string::npos);
  EXPECT_EQ(json::parse(html.substr(a + open.size(), b - a - open.size())), json::parse(scene));
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  // Without the files: the note, and the rest of the page unchanged.
  EXPECT_NE(sceneLegendHtml(scene, "scene.gltf", kNoThree).find("id=\"no-viewer\""), std::string::npos);
}

}  // namespace
}  // namespace probeloop::report
