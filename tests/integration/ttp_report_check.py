#!/usr/bin/env python3
"""Opens a thermal-test-piece report (`probeloop report ttp --html`) in headless Chromium and
checks that every plot drew, with html_render.py's machinery, plus what this page promises.

Usage: ttp_report_check.py REPORT.html [--plots N] [--quantities EX_um,EY_um,...] [--r-test]
       (exit 0 when every check passes, 1 otherwise, 2 on bad usage)

From another test:
    sys.path.insert(0, "<...>/tests/integration"); from ttp_report_check import check
    ok, text = check("report.html", quantities=["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"],
                     r_test=True)

Checks (report/ttp_report.hpp is the contract):
  - static, on the file: every plot's Vega spec parses (<script type="application/json"
    id="plot-k-spec">); its usermeta names the quantity; the quantities come in the report's
    order (E_X, E_Y, E_Z, E_B, E_TTP, ΔT) and, when given, are exactly the expected ones;
    every series data set holds at least one finite value; with --r-test, every plot but
    E_TTP has an "r_test" series;
  - in Chromium (html_render.check): as many plot containers as specs, each marked
    data-rendered="true" with drawn marks and no NaN coordinates, and #vega-errors empty
    (no script error, no Vega error).
Plain python3, no third-party modules.
"""
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from html_render import check as render_check  # noqa: E402

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


def check(path, quantities=None, r_test=False, n_plots=None):
    """Static checks plus rendering in headless Chromium; returns (ok, text)."""
    if not os.path.isfile(path):
        return False, f"FAIL no such file: {path}"
    with open(path, encoding="utf-8") as f:
        html = f.read()
    ok, lines, found = check_static(html, quantities, r_test)
    if n_plots is not None and found != n_plots:
        ok = False
        lines.append(f"FAIL {found} plot specs, expected {n_plots}")
    rendered_ok, rendered = render_check(path, found if n_plots is None else n_plots)
    ok = ok and rendered_ok
    return ok, "\n".join(["ttp_report_check: " + path] + lines + [rendered, "ttp_report_check: " + ("OK" if ok else "FAILED")])


def main(argv):
    args = argv[1:]
    path, quantities, r_test, n_plots = None, None, False, None
    try:
        while args:
            a = args.pop(0)
            if a == "--plots":
                n_plots = int(args.pop(0))
            elif a == "--quantities":
                quantities = [q for q in args.pop(0).split(",") if q]
            elif a == "--r-test":
                r_test = True
            elif path is None and not a.startswith("--"):
                path = a
            else:
                raise ValueError(a)
    except (IndexError, ValueError):
        path = None
    if path is None:
        print("usage: ttp_report_check.py REPORT.html [--plots N] [--quantities EX_um,...] [--r-test]", file=sys.stderr)
        return 2
    ok, text = check(path, quantities, r_test, n_plots)
    print(text, flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
