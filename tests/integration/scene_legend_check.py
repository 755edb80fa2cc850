#!/usr/bin/env python3
"""Opens the legend page written beside a glTF scene (`probeloop evaluate … --scene FILE.gltf`
writes FILE.html; report/scene_legend.hpp) in headless Chromium and checks it against the scene.

Usage: scene_legend_check.py FILE.gltf    (the page is FILE.html; exit 0 when every check passes)

Checks, the numbers taken from the scene file itself (its extras), not from the page's code:
  - the page loads in Chromium and its DOM holds the scene's name; with the embedded view
    (three.js from Debian's libjs-three), #viewer is marked data-rendered="true" with more than
    1000 drawn (non-background) pixels and #viewer-errors is empty; without it, the page says
    why (#no-viewer) and holds no script;
  - with a colour scale in the scene: <svg id="colour-scale"> holds five tick labels reading
    -L, -L/2, 0, +L/2, +L µm with L = colour_scale.limit_um, in that order, each inside the svg;
    the gradient's stops are the scene's three colours (linear RGB -> sRGB);
  - without one: the page says the scene has no colour scale;
  - the exaggeration the scene holds is printed, with the length 1 µm draws;
  - every object kind of the scene (its node names) is counted in the objects table.
Plain python3, no third-party modules.
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from html_render import Node, TreeBuilder, render  # noqa: E402


def srgb_hex(linear):
    out = "#"
    for v in linear[:3]:
        v = min(max(v, 0.0), 1.0)
        s = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
        out += "%02x" % round(255 * s)
    return out


def number(v):
    return ("%d" % v) if v == int(v) else ("%g" % v)


def check(gltf_path):
    lines, ok = [], True

    def say(name, cond, detail=""):
        nonlocal ok
        ok = ok and cond
        lines.append(("ok   " if cond else "FAIL ") + name + ("" if cond or not detail else "\n     " + str(detail)[:600]))

    page = os.path.splitext(gltf_path)[0] + ".html"
    scene = json.load(open(gltf_path))
    extras = (scene.get("scenes") or [{}])[0].get("extras") or scene.get("asset", {}).get("extras", {})
    if not os.path.isfile(page):
        return False, f"FAIL no legend page {page}"
    dom = render(page)[0]
    tree = TreeBuilder()
    tree.feed(dom)
    tree.close()
    nodes = list(tree.root.walk())
    text = tree.root.text()
    viewer = next((n for n in nodes if n.attrs.get("id") == "viewer"), None)
    if viewer is not None:
        # The embedded view (three.js from libjs-three): drawn, not a blank canvas, no error.
        errors = next((n for n in nodes if n.attrs.get("id") == "viewer-errors"), None)
        drawn = int(viewer.attrs.get("data-drawn-pixels", "0") or 0)
        say("the embedded view rendered the scene (WebGL, offline)",
            viewer.attrs.get("data-rendered") == "true" and drawn > 1000 and errors is not None and not errors.text().strip(),
            (viewer.attrs, errors.text() if errors is not None else "no #viewer-errors"))
        say("no script loads anything from outside", not any(n.tag == "script" and n.attrs.get("src") for n in nodes))
    else:
        say("no embedded view: the page says why and holds no script",
            any(n.attrs.get("id") == "no-viewer" for n in nodes) and not any(n.tag == "script" for n in nodes))
    say("it names the scene", os.path.basename(gltf_path) in text)
    scale = extras.get("colour_scale")
    svg = next((n for n in nodes if n.tag == "svg" and n.attrs.get("id") == "colour-scale"), None)
    if scale:
        L = scale["limit_um"]
        want = ["-" + number(L) + " µm", "-" + number(L / 2) + " µm", "0", "+" + number(L / 2) + " µm", "+" + number(L) + " µm"]
        ticks = [(t.text(), float(t.attrs.get("x", "nan"))) for t in (svg.walk() if svg else []) if t.tag == "text"]
        say(f"five ticks {want} from the scene's limit {L} µm", [t for t, _ in ticks] == want, ticks)
        width = float(svg.attrs.get("width", 0)) if svg else 0
        say("every tick lies inside the scale's svg (with room for its half width)",
            bool(ticks) and all(7 * len(t) / 2 <= x <= width - 7 * len(t) / 2 for t, x in ticks), (width, ticks))
        stops = [n.attrs.get("stop-color") for n in (svg.walk() if svg else []) if n.tag == "stop"]
        colours = [srgb_hex(scale[k]) for k in ("negative", "zero", "positive")]
        say(f"the gradient runs through the scene's colours {colours}", stops == colours, stops)
    else:
        say("no colour scale in the scene: the page says so", svg is None and "has no colour scale" in text, text[:400])
    if "exaggeration" in extras:
        x = extras["exaggeration"]
        say(f"the exaggeration x{number(x)} and what 1 µm draws ({number(x / 1000)} mm)",
            f"×{number(x)}: a displacement of 1 µm draws {number(x / 1000)} mm" in text, text[:600])
    names = [n.get("name", "") for n in scene.get("nodes", []) if not n.get("children")]
    table = next((n for n in nodes if n.tag == "table" and "objects" in n.attrs.get("class", "")), None)
    counted = 0
    for row in (table.walk() if table else []):
        if row.tag == "tr":
            cells = [c.text() for c in row.children if isinstance(c, Node) and c.tag == "td"]
            if len(cells) == 4 and cells[1].isdigit():
                counted += int(cells[1])
    say(f"the objects table counts all {len(names)} objects of the scene", counted == len(names), counted)
    return ok, "\n".join([f"scene_legend_check: {page}"] + lines + ["scene_legend_check: " + ("OK" if ok else "FAILED")])


def main(argv):
    if len(argv) != 2:
        print("usage: scene_legend_check.py FILE.gltf", file=sys.stderr)
        return 2
    ok, text = check(argv[1])
    print(text)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
