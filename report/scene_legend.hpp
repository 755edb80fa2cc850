// The page beside a glTF scene (`probeloop evaluate … --scene FILE.gltf` writes FILE.html):
// what the colours mean in µm, the exaggeration, what each object is, and how to open the
// scene. A glTF viewer shows colours without numbers; this page gives them.
//
// Contract:
// - Input: the text of a scene written by report/scene.hpp (sphere campaign) or
//   report/ttp_scene.hpp (thermal test piece), and the scene's file name as the page links
//   it. Every number on the page is read back from the scene itself (the scene's extras:
//   exaggeration, reference_cycle, colour_scale {limit_um, negative, zero, positive,
//   meaning}; the node names), never passed beside it, so page and scene cannot disagree.
//   Text that is not a glTF JSON object is InputError.
// - Output: one HTML5 page (UTF-8) that needs no network:
//   * an interactive view of the scene (<div id="viewer">, WebGL) when three_js_dir holds
//     Debian's libjs-three (three.min.js, examples/js/loaders/GLTFLoader.js,
//     examples/js/controls/OrbitControls.js): the three files and the scene (its JSON, with
//     <, > and & escaped) are inlined; the view marks #viewer data-rendered="true" and
//     data-drawn-pixels, and writes errors into #viewer-errors. Without them: a note
//     <p id="no-viewer"> naming the package, and nothing else changes;
//   * with a colour scale: an inline SVG gradient <svg id="colour-scale"> from −L through 0
//     to +L, the scene's own colours converted from glTF's linear RGB to sRGB so the page
//     shows what a viewer shows, with five numbered ticks −L, −L/2, 0, +L/2, +L in µm
//     (<text class="tick">), and the scale's meaning; without one (the sphere campaign): a
//     sentence that the vectors are one colour and only their length carries the error;
//   * the exaggeration (×N: 1 µm draws N/1000 mm) and the reference cycle;
//   * a table of the objects by kind (table, C axis, spheres, probe points, error vectors
//     per cycle, datums, facets, Z paths, deviation vectors, the colour bar), each with how
//     many the scene holds, one example name and what it is;
//   * how to view the scene (Blender, any glTF 2.0 viewer), docs/report-thermal-test-piece.md.
// - Every string from the scene is HTML-escaped; numbers in the C locale; deterministic.
#pragma once
#include <string>

namespace probeloop::report {

// Where Debian's libjs-three installs three.js: /usr/share/javascript/three.
std::string defaultThreePath();

std::string sceneLegendHtml(const std::string& gltf_text, const std::string& scene_file_name,
                            const std::string& three_js_dir = defaultThreePath());

// The page's path for a scene's path: FILE.gltf -> FILE.html (any other extension: + ".html").
std::string sceneLegendPath(const std::string& scene_path);

}  // namespace probeloop::report
