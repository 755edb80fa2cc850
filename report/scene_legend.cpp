#include "report/scene_legend.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "report/vega.hpp"

namespace probeloop::report {
namespace {

using nlohmann::json;
using namespace web;

// The scene's extras: the scene's own, else the asset's (both writers set both).
const json& sceneExtras(const json& g) {
  const json& scenes = array(g, "scenes");
  if (!scenes.empty()) {
    const json& e = object(scenes[0], "extras");
    if (!e.empty()) return e;
  }
  return object(object(g, "asset"), "extras");
}

// glTF colours are linear RGB; a page is sRGB (IEC 61966-2-1's transfer function).
std::string srgbHex(const json& linear) {
  std::array<int, 3> c{0, 0, 0};
  for (std::size_t i = 0; i < 3; ++i) {
    const double v = std::clamp(number(i < linear.size() ? &linear[i] : nullptr).value_or(0.0), 0.0, 1.0);
    const double s = v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1 / 2.4) - 0.055;
    c[i] = static_cast<int>(std::lround(255 * s));
  }
  char b[8];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c[0], c[1], c[2]);
  return b;
}

std::string signedUm(double v) {
  const std::string n = formatNumber(v);
  return (v > 0 ? "+" : "") + n + " \u00b5m";
}

// Numbered gradient: −L … 0 … +L with five ticks.
std::string colourScaleSvg(double limit_um, const std::string& neg, const std::string& zero, const std::string& pos) {
  constexpr int kLeft = 40, kWidth = 560, kBarTop = 10, kBarHeight = 28, kHeight = 70;
  std::string s = "<svg id=\"colour-scale\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(kLeft * 2 + kWidth) +
                  "\" height=\"" + std::to_string(kHeight) + "\" role=\"img\" aria-label=\"colour scale from " +
                  esc(signedUm(-limit_um)) + " to " + esc(signedUm(limit_um)) + "\">\n" +
                  "<defs><linearGradient id=\"scale-gradient\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">"
                  "<stop offset=\"0\" stop-color=\"" + neg + "\"/><stop offset=\"0.5\" stop-color=\"" + zero +
                  "\"/><stop offset=\"1\" stop-color=\"" + pos + "\"/></linearGradient></defs>\n" +
                  "<rect class=\"bar\" x=\"" + std::to_string(kLeft) + "\" y=\"" + std::to_string(kBarTop) + "\" width=\"" +
                  std::to_string(kWidth) + "\" height=\"" + std::to_string(kBarHeight) +
                  "\" fill=\"url(#scale-gradient)\" stroke=\"#888\"/>\n";
  for (int k = 0; k <= 4; ++k) {
    const double value = limit_um * (k - 2) / 2.0;
    const std::string x = std::to_string(kLeft + kWidth * k / 4);
    s += "<line x1=\"" + x + "\" x2=\"" + x + "\" y1=\"" + std::to_string(kBarTop + kBarHeight) + "\" y2=\"" +
         std::to_string(kBarTop + kBarHeight + 6) + "\" stroke=\"#444\"/>\n<text class=\"tick\" x=\"" + x + "\" y=\"" +
         std::to_string(kBarTop + kBarHeight + 20) + "\" text-anchor=\"middle\" font-family=\"sans-serif\" font-size=\"12\">" +
         esc(value == 0 ? "0" : signedUm(value)) + "</text>\n";
  }
  return s + "</svg>\n";
}

struct ObjectKind {
  const char* prefix;
  const char* what;
};
// In the order the writers add them; the first matching prefix wins.
constexpr ObjectKind kKinds[] = {
    {"table", "the rotary table: a disc at the table surface around the C axis"},
    {"C axis", "the C axis: a line along +Z through its centre"},
    {"sphere ", "a sphere of the artifact at its nominal centre"},
    {"probe points", "the nominal contact points of the probing plan"},
    {"error vectors cycle ", "one cycle's error vectors: from each sphere's nominal centre to nominal + exaggeration \u00d7 "
                             "(its centre in that cycle \u2212 its centre in the reference cycle)"},
    {"datum ", "a datum of the piece, grey (the finished top's outline, the notch flanks, the datum band)"},
    {"facet ", "a measured facet at its nominal place, coloured by its change \u0394d = d \u2212 d_ref against the same "
               "group's reference facet; dark grey where the change is unknown"},
    {"Z path ", "a measured Z path at its nominal place, coloured by its change in depth against its reference"},
    {"deviation ", "a deviation vector: exaggeration \u00d7 the surface's displacement (facets along the outward normal, "
                   "Z paths along \u2212Z for a deeper floor)"},
    {"colour scale", "the colour scale as a bar of quads beside the piece, \u2212L at \u2212Y to +L at +Y"},
};

struct KindCount {
  int count = 0;
  std::string example;
};

std::string objectsTable(const json& g) {
  std::vector<KindCount> counts(std::size(kKinds));
  KindCount other;
  for (const auto& n : array(g, "nodes")) {
    if (!array(n, "children").empty()) continue;  // the root that turns the frame
    const std::string name = text(n, "name");
    std::size_t k = 0;
    while (k < std::size(kKinds) && name.rfind(kKinds[k].prefix, 0) != 0) ++k;
    KindCount& c = k < std::size(kKinds) ? counts[k] : other;
    if (c.count++ == 0) c.example = name;
  }
  std::string t = "<table class=\"objects\">\n<thead><tr>" + th("object") + th("in the scene", true) + th("for example") +
                  th("what it is") + "</tr></thead>\n<tbody>\n";
  for (std::size_t k = 0; k < std::size(kKinds); ++k)
    if (counts[k].count > 0)
      t += "<tr>" + td(kKinds[k].prefix) + td(std::to_string(counts[k].count), true) + td(counts[k].example) +
           td(kKinds[k].what) + "</tr>\n";
  if (other.count > 0)
    t += "<tr>" + td("other") + td(std::to_string(other.count), true) + td(other.example) + td(kDash) + "</tr>\n";
  return t + "</tbody>\n</table>\n";
}

// ---- The embedded view: three.js r111 from Debian's libjs-three, inlined like Vega.
struct ThreeFile {
  const char* path;  // under the libjs-three directory
  const char* what;
};
constexpr ThreeFile kThreeFiles[] = {
    {"three.min.js", "three.js"},
    {"examples/js/loaders/GLTFLoader.js", "GLTFLoader"},
    {"examples/js/controls/OrbitControls.js", "OrbitControls"},
};

// Script text that cannot end its <script> element ("</script", "<!--" only occur in string
// literals of these files, where \x3C means the same "<").
std::string scriptSafe(std::string js) {
  std::string lower = js;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const std::string from : {"</script", "<!--"})
    for (std::size_t pos = lower.find(from); pos != std::string::npos; pos = lower.find(from, pos + 1)) {
      js.replace(pos, 1, "\\x3C");
      lower.replace(pos, 1, "\\x3C");
    }
  return js;
}

// The three scripts, or nullopt when one is missing (the page then says how to get them).
std::optional<std::string> threeRuntime(const std::string& dir) {
  std::string js;
  for (const auto& f : kThreeFiles) {
    std::ifstream in(std::filesystem::path(dir) / f.path, std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream s;
    s << in.rdbuf();
    js += "<script>/* " + std::string(f.what) + " (Debian libjs-three) */\n" + scriptSafe(s.str()) + "\n</script>\n";
  }
  return js;
}

// Loads the scene from its <script type="application/json">, frames it, renders on demand;
// marks #viewer data-rendered="true" and data-drawn-pixels (pixels not background) so a test
// can tell a drawn view from a blank canvas; errors land in #viewer-errors.
constexpr const char* kViewerScript = R"JS(
(function () {
  var div = document.getElementById('viewer'), errors = document.getElementById('viewer-errors');
  function fail(e) { var p = document.createElement('p'); p.textContent = 'viewer: ' + (e && e.message ? e.message : String(e)); errors.appendChild(p); }
  try {
    var W = 900, H = 560;
    var renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
    renderer.setSize(W, H);
    div.appendChild(renderer.domElement);
    var scene = new THREE.Scene();
    scene.background = new THREE.Color(0xffffff);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x555555, 1.0));
    var camera = new THREE.PerspectiveCamera(40, W / H, 0.001, 1000);
    var controls = new THREE.OrbitControls(camera, renderer.domElement);
    var draw = function () { renderer.render(scene, camera); };
    new THREE.GLTFLoader().parse(document.getElementById('scene-gltf').textContent, '', function (gltf) {
      scene.add(gltf.scene);
      var box = new THREE.Box3().setFromObject(gltf.scene);
      var c = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3()).length();
      camera.position.set(c.x + 0.6 * size, c.y + 0.6 * size, c.z + 0.9 * size);
      camera.lookAt(c);
      controls.target.copy(c);
      controls.update();
      controls.addEventListener('change', draw);
      draw();
      var gl = renderer.getContext(), px = new Uint8Array(4 * W * H), n = 0;
      gl.readPixels(0, 0, W, H, gl.RGBA, gl.UNSIGNED_BYTE, px);
      for (var i = 0; i < px.length; i += 4) if (px[i] < 250 || px[i + 1] < 250 || px[i + 2] < 250) n++;
      div.setAttribute('data-drawn-pixels', String(n));
      div.setAttribute('data-rendered', 'true');
    }, fail);
  } catch (e) { fail(e); }
})();
)JS";

}  // namespace

std::string defaultThreePath() { return "/usr/share/javascript/three"; }

std::string sceneLegendPath(const std::string& scene_path) {
  std::filesystem::path p(scene_path);
  if (p.extension() == ".gltf") return p.replace_extension(".html").string();
  return scene_path + ".html";
}

std::string sceneLegendHtml(const std::string& gltf_text, const std::string& scene_file_name, const std::string& three_js_dir) {
  const json g = json::parse(gltf_text, nullptr, false);
  if (!g.is_object() || !field(g, "asset"))
    throw InputError(scene_file_name, 0, "scene legend: not a glTF 2.0 JSON scene (no \"asset\")");
  const json& extras = sceneExtras(g);
  const std::optional<double> exaggeration = number(extras, "exaggeration");
  const std::optional<double> reference = number(extras, "reference_cycle");
  const json& scale = object(extras, "colour_scale");
  const std::optional<double> limit = number(scale, "limit_um");

  std::string h = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"generator\" "
                  "content=\"probeloop\">\n<title>" +
                  esc("Scene " + scene_file_name + ": colours, exaggeration, objects") + "</title>\n<style>" + kStyle +
                  ".viewer canvas { border: 1px solid #ddd; }\n</style>\n</head>\n<body>\n<header>\n<h1>" + esc("Scene " + scene_file_name) + "</h1>\n" +
                  "<p>The glTF 2.0 scene <a href=\"" + esc(scene_file_name) + "\">" + esc(scene_file_name) +
                  "</a>: what its colours mean in \u00b5m, how much its vectors are exaggerated, and what each object "
                  "is. Every number here is read from the scene file itself.</p>\n</header>\n";

  // The view first: what the numbers below describe.
  h += "<section class=\"view\">\n<h2>The scene</h2>\n";
  const std::optional<std::string> three = threeRuntime(three_js_dir);
  if (three) {
    h += "<div id=\"viewer\" class=\"viewer\"></div>\n<div id=\"viewer-errors\" class=\"errors\" role=\"alert\"></div>\n"
         "<p class=\"note\">Drag to turn, scroll to zoom, right-drag to pan (three.js " +
         std::string("r111, from Debian's libjs-three, inlined: the page opens offline).</p>\n") +
         "<script type=\"application/json\" id=\"scene-gltf\">" + scriptJson(g) + "</script>\n" + *three +
         "<script>" + kViewerScript + "</script>\n";
  } else {
    h += "<p id=\"no-viewer\" class=\"note\">No embedded view: it needs three.js from Debian's libjs-three (" +
         esc(three_js_dir) + "; apt-get install libjs-three, scripts/setup.sh installs it). Open the scene as below.</p>\n";
  }
  h += "</section>\n<section class=\"scale\">\n<h2>Colour scale</h2>\n";
  if (limit && *limit > 0) {
    h += colourScaleSvg(*limit, srgbHex(array(scale, "negative")), srgbHex(array(scale, "zero")),
                        srgbHex(array(scale, "positive")));
    h += "<p>Blue \u2212, light grey 0, red +: linear from 0 to the end colours at " + esc(signedUm(-*limit)) + " and " +
         esc(signedUm(*limit)) + ", clamped beyond. Dark grey: a feature whose change is unknown.</p>\n";
    const std::string meaning = text(scale, "meaning");
    if (!meaning.empty()) h += "<p class=\"note\">The scene's own words: " + esc(meaning) + "</p>\n";
  } else {
    h += "<p id=\"no-colour-scale\">This scene has no colour scale: its error vectors are drawn in one colour, and only "
         "their length and direction carry the error (see the exaggeration below).</p>\n";
  }
  h += "</section>\n<section class=\"exaggeration\">\n<h2>Exaggeration</h2>\n";
  if (exaggeration) {
    h += "<p>Vectors are drawn \u00d7" + esc(formatNumber(*exaggeration)) + ": a displacement of 1 \u00b5m draws " +
         esc(formatNumber(*exaggeration / 1000.0)) + " mm in the scene (its unit is the metre, glTF's).";
    if (reference) h += " Every change is against the reference cycle " + esc(whole(reference)) + ".";
    h += "</p>\n";
    const std::string vectors = text(extras, "deviation_vectors");
    if (!vectors.empty()) h += "<p class=\"note\">The scene's own words: " + esc(vectors) + "</p>\n";
  } else {
    h += "<p>" + esc(kDash) + " (the scene states no exaggeration)</p>\n";
  }
  h += "</section>\n<section class=\"objects\">\n<h2>Objects</h2>\n" + objectsTable(g) + "</section>\n";
  h += "<section class=\"viewing\">\n<h2>Viewing the scene</h2>\n<ul>\n"
       "<li>Blender: File \u2192 Import \u2192 glTF 2.0, then the Outliner lists the objects by the names above; "
       "switch the viewport to Material Preview to see the colours.</li>\n"
       "<li>Any glTF 2.0 viewer opens the file as it is: it is one self-contained .gltf (its buffers are embedded), "
       "in metres, turned so that the part's or the machine's +Z is the viewer's up (+Y).</li>\n"
       "<li>Lines (vectors, axes, outlines) are glTF line primitives: viewers draw them one pixel wide.</li>\n"
       "</ul>\n</section>\n</body>\n</html>\n";
  return h;
}

}  // namespace probeloop::report
