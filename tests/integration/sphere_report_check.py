#!/usr/bin/env python3
"""Opens a sphere-campaign report (`probeloop report sphere --html`) in headless Chromium and
checks what it shows against the files it was made from, with html_render.py's machinery.

Usage: sphere_report_check.py REPORT.html --evaluation EVAL.json [--inputs inputs.csv]
                              [--manifest plan.json] [--scene HREF] [--plots N]
       (exit 0 when every check passes, 1 otherwise, 2 on bad usage)

From another test:
    sys.path.insert(0, "<...>/tests/integration"); from sphere_report_check import check
    ok, text = check("report.html", "eval/evaluation.json", inputs="run/inputs.csv", manifest="plan/plan.json")

Checks (report/sphere_report.hpp is the contract; the references are the input files, read here):
  - static, on the file: every plot's Vega spec parses; the first seven are the location
    errors EX0C_um ... EC0C_urad in that order, each holding one row per evaluated cycle with
    the evaluation's time_s, value and U (its budget's), exactly; with inputs, the input plots'
    columns are exactly inputs.csv's columns but time_s, each once, and the °C plot's are the
    columns whose names end in _C; the samples are the file's;
  - in Chromium (the DOM after Vega ran): html_render's contract (every plot rendered, no NaN,
    #vega-errors empty); in each error plot the symbol mark "values" draws one symbol per
    cycle, the area "u_band" draws one band through value − U and value + U of every cycle
    (2 points per cycle in its path) and is higher than a line wherever a U > 0, the y axis
    title carries the unit (µm / µrad); in each input plot the legend names its columns and
    every column draws a line;
  - the tables in the DOM: the summary has a row per error, the cycle table a row per cycle,
    the last cycle's budget tables one row per contribution the evaluation lists for that
    error, the schedule one row per planned cycle (with --manifest), and the scene link
    (with --scene).
Plain python3, no third-party modules.
"""
import csv
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from html_render import TreeBuilder, check_dom, render  # noqa: E402

ERRORS = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]
SPEC = re.compile(r'<script type="application/json" id="plot-(\d+)-spec">(.*?)</script>', re.S)
NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e-?\d+)?")


def specs(html):
    out = []
    for m in SPEC.finditer(html):
        try:
            out.append((int(m.group(1)), json.loads(m.group(2))))
        except ValueError as e:
            out.append((int(m.group(1)), e))
    return out


def cycle_values(evaluation, error):
    """{cycle: (time_s, value, U)} from the evaluation: the budget's value and U."""
    out = {}
    for c in evaluation.get("cycles", []):
        label = error.rsplit("_", 1)[0]  # budgets name the quantity "EX0C", unit "um"
        budget = next((b for b in c.get("budgets", []) if b.get("quantity") in (label, error)), None)
        if budget is not None:
            out[c["cycle"]] = (c["time_s"], budget["value"], budget["U"])
    return out


def read_inputs(path):
    with open(path, newline="", encoding="utf-8") as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#")) if r]
    return rows[0], rows[1:]


def check_static(html, evaluation, inputs):
    lines, ok = [], True
    found = specs(html)
    errors = [(k, s) for k, s in found if isinstance(s, dict) and s.get("usermeta", {}).get("kind") == "error"]
    shown = [s["usermeta"]["error"] for _, s in errors]
    if shown != ERRORS:
        ok = False
        lines.append(f"FAIL error plots {shown}, expected {ERRORS}")
    for k, s in found:
        if isinstance(s, Exception):
            ok = False
            lines.append(f"FAIL plot-{k}: the spec is not JSON ({s})")
    for k, s in errors:
        e = s["usermeta"]["error"]
        data = {d["name"]: d for d in s["data"]}
        rows = data.get("cycles", {}).get("values", [])
        want = cycle_values(evaluation, e)
        got = {r["cycle"]: (r["time_s"], r["value"], r["U"]) for r in rows}
        if len(rows) != len(want) or got != want:
            ok = False
            diff = sorted(c for c in set(want) | set(got) if want.get(c) != got.get(c))[:5]
            lines.append(f"FAIL plot-{k} ({e}): {len(rows)} rows, the evaluation has {len(want)}; differ at cycles {diff}")
        else:
            lines.append(f"ok   plot-{k} ({e}): {len(rows)} cycles, time_s, value and U as in the evaluation")
    n_inputs = 0
    if inputs is not None:
        header, rows = inputs
        columns = [c for c in header if c != "time_s"]
        plotted, celsius = [], None
        for k, s in found:
            if not isinstance(s, dict) or s.get("usermeta", {}).get("kind") != "inputs":
                continue
            n_inputs += 1
            meta = s["usermeta"]
            names = [c["column"] for c in meta["columns"]]
            plotted += names
            if meta.get("unit") == "\u00b0C":
                celsius = names
            values = next(d for d in s["data"] if d["name"] == "inputs")["values"]
            t = header.index("time_s")
            bad = 0
            for i, (r, v) in enumerate(zip(rows, values)):
                if float(r[t]) != v["time_s"]:
                    bad += 1
                for c in meta["columns"]:
                    if float(r[header.index(c["column"])]) != v[c["field"]]:
                        bad += 1
            if len(values) != len(rows) or bad:
                ok = False
                lines.append(f"FAIL plot-{k} ({meta['group']}): {len(values)} samples of {len(rows)}, {bad} differ from the file")
            else:
                lines.append(f"ok   plot-{k} ({meta['group']}): {', '.join(names)}, {len(values)} samples as in the file")
        if sorted(plotted) != sorted(columns) or len(plotted) != len(set(plotted)):
            ok = False
            lines.append(f"FAIL input columns plotted {plotted}, inputs.csv has {columns}")
        want_c = [c for c in columns if c.endswith("_C")]
        if celsius != want_c:
            ok = False
            lines.append(f"FAIL the temperature plot shows {celsius}, expected the _C columns {want_c}")
        else:
            lines.append(f"ok   the temperature plot shows the _C columns {want_c}")
    return ok, lines, found


def mark_group(svg, name):
    for g in svg.walk():
        if g.tag == "g" and "role-mark" in g.classes() and name in g.classes():
            return g
    return None


def paths(group):
    return [n for n in group.walk() if n.tag == "path" and n.attrs.get("d", "").strip()] if group else []


def texts(svg, role):
    return [n.text().strip() for g in svg.walk() if g.tag == "g" and role in g.classes()
            for n in g.walk() if n.tag == "text"]


TRANSLATE = re.compile(r"translate\(\s*(-?[\d.e-]+)[ ,]+(-?[\d.e-]+)\s*\)")


def symbol_centres(group):
    """(x, y) of each drawn symbol: Vega places a symbol with transform="translate(x,y)"."""
    out = []
    for n in paths(group):
        m = TRANSLATE.search(n.attrs.get("transform", ""))
        if m:
            out.append((float(m.group(1)), float(m.group(2))))
    return out


def band_points(d):
    """The (x, y) vertices of a linear area path: M/L commands, 'Z' closing."""
    nums = [float(x) for x in NUMBER.findall(d)]
    return list(zip(nums[0::2], nums[1::2]))


def check_dom_content(dom, found, evaluation, manifest, scene):
    lines, ok = [], True
    tree = TreeBuilder()
    tree.feed(dom)
    tree.close()
    nodes = list(tree.root.walk())
    by_id = {n.attrs.get("id"): n for n in nodes if n.attrs.get("id")}
    for k, s in found:
        if not isinstance(s, dict):
            continue
        div = by_id.get(f"plot-{k}")
        svg = next((n for n in div.walk() if n.tag == "svg" and "marks" in n.classes()), None) if div else None
        if svg is None:
            ok = False
            lines.append(f"FAIL plot-{k}: no svg in the DOM")
            continue
        meta = s["usermeta"]
        if meta["kind"] == "error":
            e = meta["error"]
            want = cycle_values(evaluation, e)
            symbols = len(paths(mark_group(svg, "values")))
            band = paths(mark_group(svg, "u_band"))
            problems = []
            if symbols != len(want):
                problems.append(f"{symbols} symbols drawn, {len(want)} cycles")
            if len(band) != 1:
                problems.append(f"{len(band)} band paths, expected 1")
            else:
                pts = band_points(band[0].attrs["d"])
                n_u = sum(1 for _, v, u in want.values() if u is not None)
                widest_u = max((u for _, _, u in want.values() if u is not None), default=0)
                if len(pts) != 2 * n_u:
                    problems.append(f"the band has {len(pts)} vertices, expected 2 per cycle ({2 * n_u})")
                # Upper and lower edge at the same x (a cycle's time): the band's middle is the
                # cycle's symbol and its thickness is 2U times one scale factor (px per unit).
                upper, lower = pts[:n_u], list(reversed(pts[n_u:]))
                centres = symbol_centres(mark_group(svg, "values"))
                us = [u for _, _, u in sorted(want.values()) if u is not None]
                pairs = [(a, b) for a, b in zip(upper, lower) if abs(a[0] - b[0]) < 1e-3]
                if len(pairs) != n_u or len(us) != n_u:
                    problems.append("the band's edges are not at the cycles' times")
                elif widest_u > 0:
                    scale = max(abs(a[1] - b[1]) for a, b in pairs) / (2 * widest_u)
                    for (a, b), u in zip(pairs, us):
                        mid = (a[1] + b[1]) / 2
                        near = [y for x, y in centres if abs(x - a[0]) < 0.5]
                        if not near or abs(near[0] - mid) > 0.6:
                            problems.append(f"at x = {a[0]:.1f} px the band's middle {mid:.1f} px is not the symbol {near}")
                            break
                        if abs(abs(a[1] - b[1]) - 2 * u * scale) > 0.02 * 2 * u * scale + 0.6:
                            problems.append(f"at x = {a[0]:.1f} px the band is {abs(a[1] - b[1]):.1f} px thick, "
                                            f"2U = {2 * u * scale:.1f} px")
                            break
                    if scale * widest_u < 0.5:
                        problems.append(f"the band has no thickness though U reaches {widest_u}")
            unit = meta["unit"]
            titles = texts(svg, "role-axis-title")
            if not any(t.endswith(f"({unit})") for t in titles):
                problems.append(f"no axis title with ({unit}): {titles}")
            if problems:
                ok = False
                lines.append(f"FAIL plot-{k} ({e}) as drawn: " + "; ".join(problems))
            else:
                lines.append(f"ok   plot-{k} ({e}) as drawn: {symbols} symbols, the U band, axis '{[t for t in titles if unit in t][0]}'")
        elif meta["kind"] == "inputs":
            names = [c["column"] for c in meta["columns"]]
            legend = texts(svg, "role-legend-label")
            drawn = [len(paths(mark_group(svg, f"input_{i}"))) for i in range(len(names))]
            if legend != names or 0 in drawn:
                ok = False
                lines.append(f"FAIL plot-{k} ({meta['group']}) as drawn: legend {legend}, columns {names}, lines {drawn}")
            else:
                lines.append(f"ok   plot-{k} ({meta['group']}) as drawn: legend {legend}, a line each")

    def table_rows(cls):  # body rows of every <table class=cls>, in page order
        return [sum(1 for b in t.walk() if b.tag == "tbody" for r in b.walk() if r.tag == "tr")
                for t in nodes if t.tag == "table" and cls in t.classes()]

    cycles = evaluation.get("cycles", [])
    summary, per_cycle = table_rows("summary"), table_rows("cycles")
    if summary != [7] or per_cycle != [len(cycles)]:
        ok = False
        lines.append(f"FAIL tables: summary rows {summary} (7 expected), cycle rows {per_cycle} ({len(cycles)} expected)")
    else:
        lines.append(f"ok   tables: a summary row per error, a row per cycle ({len(cycles)})")
    ref = evaluation.get("reference_cycle")
    last = [c for c in cycles if c.get("cycle") != ref and c.get("budgets")][-1]
    want_budget = [len(b["contributions"]) for b in last["budgets"]]
    got_budget = table_rows("budget")
    if got_budget != want_budget:
        ok = False
        lines.append(f"FAIL budget tables of cycle {last['cycle']}: rows {got_budget}, the evaluation lists {want_budget}")
    else:
        lines.append(f"ok   budget tables of cycle {last['cycle']}: rows {got_budget} as the evaluation's contributions")
    if manifest is not None:
        planned = manifest["schedule"]["cycles"]
        got = table_rows("schedule")
        if got != [planned]:
            ok = False
            lines.append(f"FAIL schedule rows {got}, the plan has {planned} cycles")
        else:
            lines.append(f"ok   schedule: a row per planned cycle ({planned})")
    if scene is not None:
        links = [n.attrs.get("href") for n in nodes if n.tag == "a"]
        if scene not in links:
            ok = False
            lines.append(f"FAIL no link to the scene {scene!r} (links: {links})")
        else:
            lines.append(f"ok   the scene is linked: {scene}")
    return ok, lines


def check(path, evaluation, inputs=None, manifest=None, scene=None, n_plots=None):
    """Static checks, then the page in headless Chromium; returns (ok, text)."""
    if not os.path.isfile(path):
        return False, f"FAIL no such file: {path}"
    with open(path, encoding="utf-8") as f:
        html = f.read()
    with open(evaluation, encoding="utf-8") as f:
        ev = json.load(f)
    inp = read_inputs(inputs) if inputs else None
    man = None
    if manifest:
        with open(manifest, encoding="utf-8") as f:
            man = json.load(f)
    ok, lines, found = check_static(html, ev, inp)
    if n_plots is not None and len(found) != n_plots:
        ok = False
        lines.append(f"FAIL {len(found)} plots, expected {n_plots}")
    try:
        dom, seconds, _ = render(path)
    except Exception as e:  # noqa: BLE001 - reported as a failure
        return False, "\n".join(lines + [f"FAIL rendering {path}: {e}"])
    rendered_ok, rendered = check_dom(dom, len(found))
    content_ok, content = check_dom_content(dom, found, ev, man, scene)
    ok = ok and rendered_ok and content_ok
    head = f"sphere_report_check: {path} ({os.path.getsize(path) / 1e6:.2f} MB, rendered in {seconds:.1f} s)"
    return ok, "\n".join([head] + lines + rendered + content + ["sphere_report_check: " + ("OK" if ok else "FAILED")])


def main(argv):
    args = argv[1:]
    path, opts = None, {"--evaluation": None, "--inputs": None, "--manifest": None, "--scene": None, "--plots": None}
    try:
        while args:
            a = args.pop(0)
            if a in opts:
                opts[a] = args.pop(0)
            elif path is None and not a.startswith("--"):
                path = a
            else:
                raise ValueError(a)
    except (IndexError, ValueError):
        path = None
    if path is None or opts["--evaluation"] is None or not (opts["--plots"] or "0").isdigit():
        print("usage: sphere_report_check.py REPORT.html --evaluation EVAL.json [--inputs inputs.csv] "
              "[--manifest plan.json] [--scene HREF] [--plots N]", file=sys.stderr)
        return 2
    ok, text = check(path, opts["--evaluation"], opts["--inputs"], opts["--manifest"], opts["--scene"],
                     int(opts["--plots"]) if opts["--plots"] else None)
    print(text, flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
