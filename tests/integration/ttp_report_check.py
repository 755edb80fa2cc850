#!/usr/bin/env python3
"""Opens a thermal-test-piece report (`probeloop report ttp --html`) in headless Chromium and
checks that every plot drew, with html_render.py's machinery, plus what this page promises.

Usage: ttp_report_check.py REPORT.html [--plots N] [--quantities EX_um,EY_um,...] [--r-test] [--inputs inputs.csv]
       (exit 0 when every check passes, 1 otherwise, 2 on bad usage)

From another test:
    sys.path.insert(0, "<...>/tests/integration"); from ttp_report_check import check
    ok, text = check("report.html", quantities=["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"],
                     r_test=True, inputs="run/inputs.csv")

Checks (report/ttp_report.hpp is the contract):
  - static, on the file: every plot's Vega spec parses (<script type="application/json"
    id="plot-k-spec">); its usermeta names the quantity; the quantities come in the report's
    order (E_X, E_Y, E_Z, E_B, E_TTP, ΔT) and, when given, are exactly the expected ones;
    every series data set holds at least one finite value; with --r-test, every plot but
    E_TTP has an "r_test" series;
  - with --inputs (the run's inputs.csv given to `report ttp --inputs`): a temperature plot
    whose series are the file's *_C columns and a C-load plot whose series is c_rpm, each
    row's value the file's at that time_s (usermeta "inputs"; not counted as quantities);
  - the page as a reader sees it: no path into our notes ("notes/seed"), no source-file line
    number ("L2226"), no "seed 004"; the misprinted Eqs. 7.1/7.2 ("as printed") only after
    the appendix's start; spans' periods as h:mm;
  - in Chromium (html_render's machinery, one render): as many plot containers as specs,
    each marked data-rendered="true" with drawn marks and no NaN coordinates, and
    #vega-errors empty (no script error, no Vega error); with --inputs, every temperature
    and the C-load series drew its line (the mark group named <data>_line has a path).
Plain python3, no third-party modules.
"""
import json
import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from html_render import TreeBuilder, check_dom, render  # noqa: E402

ORDER = ["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"]
SPEC = re.compile(r'<script type="application/json" id="plot-(\d+)-spec">(.*?)</script>', re.S)


def specs(html):
    """The plot specs of a page, in page order: [(k, spec or exception)]."""
    out = []
    for m in SPEC.finditer(html):
        try:
            out.append((int(m.group(1)), json.loads(m.group(2))))
        except ValueError as e:
            out.append((int(m.group(1)), e))
    return out


def read_inputs(path):
    """inputs.csv -> {column: {time_s: value}} (comments skipped)."""
    with open(path, encoding="utf-8") as f:
        rows = [l.strip().split(",") for l in f if l.strip() and not l.startswith("#")]
    header, out = rows[0], {}
    for r in rows[1:]:
        for name, v in zip(header[1:], r[1:]):
            try:
                out.setdefault(name, {})[float(r[0])] = float(v)
            except ValueError:
                pass
    return out


def check_inputs(found, inputs_path):
    """The input plots against the file; returns (ok, lines, the series data names drawn)."""
    lines, ok, names = [], True, []
    table = read_inputs(inputs_path)
    temps = [c for c in table if c.endswith("_C")]
    plots = {s["usermeta"]["inputs"]: s for _, s in found if isinstance(s, dict) and "inputs" in s.get("usermeta", {})}
    for kind, expected in (("temperatures", temps), ("c_load", ["c_rpm"] if "c_rpm" in table else [])):
        s = plots.get(kind)
        if s is None:
            ok = False
            lines.append(f"FAIL no {kind} plot from {inputs_path}")
            continue
        data = {d.get("name"): d for d in s.get("data", [])}
        series = s["usermeta"].get("series", [])
        columns = [x.get("column") for x in series]
        if columns != expected:
            ok = False
            lines.append(f"FAIL {kind} plot: series {columns}, the file has {expected}")
            continue
        bad = 0
        for x in series:
            values = data.get(x["data"], {}).get("values", [])
            bad += sum(1 for v in values if abs(table[x["column"]].get(v["time_s"], float("nan")) - v["value"]) > 1e-9) + (not values)
            names.append(x["data"])
        if bad:
            ok = False
            lines.append(f"FAIL {kind} plot: {bad} values not the file's")
        else:
            lines.append(f"ok   {kind} plot: {', '.join(columns)} as in {os.path.basename(inputs_path)}")
    return ok, lines, names


def check_reader(html):
    """What a reader of the page must not meet (outside the inlined scripts)."""
    text = re.sub(r"<script\b.*?</script>", "", html, flags=re.S)
    lines, ok = [], True
    for pattern, what in ((r"notes/seed", "a path into our notes"), (r"\bL\d{3,4}\b", "a source-file line number"),
                          (r"seed 004", "the notes' name of the thesis")):
        m = re.search(pattern, text)
        if m:
            ok = False
            lines.append(f"FAIL {what} in the page: ...{text[max(0, m.start() - 60):m.end() + 60]}...")
    appendix = text.find('id="appendix-printed"')
    printed = [m.start() for m in re.finditer(r"as printed \(", text)]
    if printed and (appendix < 0 or min(printed) < appendix):
        ok = False
        lines.append("FAIL the misprinted Eqs. 7.1/7.2 appear before the appendix")
    periods = re.findall(r"<tr><th>(\d+:\d\d|[\d.]+ h)[ <]", text)
    if any(not re.fullmatch(r"\d+:\d\d", p) for p in periods):
        ok = False
        lines.append(f"FAIL spans' periods not as h:mm: {periods}")
    if ok:
        lines.append(f"ok   no notes paths, line numbers or misprints in the main page; periods {', '.join(periods[:3])} ...")
    return ok, lines


def check_static(html, quantities=None, r_test=False):
    lines, ok = [], True
    found = specs(html)
    shown = []
    for k, s in found:
        if isinstance(s, Exception):
            ok = False
            lines.append(f"FAIL plot-{k}: the spec is not JSON ({s})")
            continue
        meta = s.get("usermeta", {})
        if "inputs" in meta:
            continue
        q = meta.get("quantity")
        shown.append(q)
        data = {d.get("name"): d for d in s.get("data", [])}
        problems = []
        series = meta.get("series", [])
        if not series:
            problems.append("no series in usermeta")
        for ser in series:
            values = data.get(ser.get("data"), {}).get("values", [])
            finite = [v for v in values if isinstance(v.get("value"), (int, float)) and math.isfinite(v["value"])]
            if not finite:
                problems.append(f"series {ser.get('label')!r} has no finite value")
        if r_test and q != "ETTP_um" and "r_test" not in data:
            problems.append("no R-test series")
        if problems:
            ok = False
            lines.append(f"FAIL plot-{k} ({q}): " + "; ".join(problems))
        else:
            labels = ", ".join(f"{ser.get('label')} ({len(data[ser['data']]['values'])})" for ser in series)
            lines.append(f"ok   plot-{k} ({q}): {labels}")
    if any(q not in ORDER for q in shown) or shown != sorted(shown, key=ORDER.index):
        ok = False
        lines.append(f"FAIL quantities {shown} are not in the report's order {ORDER}")
    if quantities is not None and shown != list(quantities):
        ok = False
        lines.append(f"FAIL plotted quantities {shown}, expected {list(quantities)}")
    elif quantities is not None:
        lines.append(f"ok   plotted quantities {shown}")
    return ok, lines, len(found)


def drawn_lines(dom, names):
    """Per series data name, whether the DOM has its line mark (<g class="... NAME_line">) with a path."""
    tree = TreeBuilder()
    tree.feed(dom)
    tree.close()
    out = {}
    for name in names:
        groups = [n for n in tree.root.walk() if n.tag == "g" and f"{name}_line" in n.classes()]
        out[name] = any(p.tag == "path" and p.attrs.get("d", "").strip() for g in groups for p in g.walk())
    return out


def check(path, quantities=None, r_test=False, n_plots=None, inputs=None):
    """Static checks plus rendering in headless Chromium; returns (ok, text)."""
    if not os.path.isfile(path):
        return False, f"FAIL no such file: {path}"
    with open(path, encoding="utf-8") as f:
        html = f.read()
    ok, lines, found = check_static(html, quantities, r_test)
    ok_r, lines_r = check_reader(html)
    ok, lines = ok and ok_r, lines + lines_r
    names = []
    if inputs is not None:
        ok_i, lines_i, names = check_inputs(specs(html), inputs)
        ok, lines = ok and ok_i, lines + lines_i
    if n_plots is not None and found != n_plots:
        ok = False
        lines.append(f"FAIL {found} plot specs, expected {n_plots}")
    try:
        dom, seconds, _ = render(path)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        return False, "\n".join(["ttp_report_check: " + path] + lines + [f"FAIL rendering: {e}", "ttp_report_check: FAILED"])
    rendered_ok, rendered = check_dom(dom, found if n_plots is None else n_plots)
    ok = ok and rendered_ok
    lines += [f"html_render: rendered by headless Chromium in {seconds:.1f} s"] + rendered
    if names:
        drawn = drawn_lines(dom, names)
        missing = [n for n, d in drawn.items() if not d]
        ok = ok and not missing
        lines.append(f"FAIL input series not drawn: {missing}" if missing else f"ok   input series drawn: {', '.join(drawn)}")
    return ok, "\n".join(["ttp_report_check: " + path] + lines + ["ttp_report_check: " + ("OK" if ok else "FAILED")])


def main(argv):
    args = argv[1:]
    path, quantities, r_test, n_plots, inputs = None, None, False, None, None
    try:
        while args:
            a = args.pop(0)
            if a == "--plots":
                n_plots = int(args.pop(0))
            elif a == "--quantities":
                quantities = [q for q in args.pop(0).split(",") if q]
            elif a == "--r-test":
                r_test = True
            elif a == "--inputs":
                inputs = args.pop(0)
            elif path is None and not a.startswith("--"):
                path = a
            else:
                raise ValueError(a)
    except (IndexError, ValueError):
        path = None
    if path is None:
        print("usage: ttp_report_check.py REPORT.html [--plots N] [--quantities EX_um,...] [--r-test] [--inputs inputs.csv]",
              file=sys.stderr)
        return 2
    ok, text = check(path, quantities, r_test, n_plots, inputs)
    print(text, flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
