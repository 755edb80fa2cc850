#!/usr/bin/env python3
"""`probeloop report sphere` through the real CLI, on a campaign this test makes itself.

plan the shipped sphere artifact for 6 cycles on the NMV 5000 (Fanuc) -> simulate it on the
virtual machine with the demo's truth (examples/truth_campaign.yaml: the thermal network, the
C-axis duty) -> evaluate the DPRNT log with a glTF scene -> report sphere with the inputs, the
plan and the scene -> sphere_report_check.py: what the page shows in headless Chromium against
the evaluation, inputs.csv and plan.json it was made from; the same inputs give the same bytes;
the page without the optional inputs; refusals (a thermal test piece's evaluation and plan, an
inputs file without time_s, an errors.csv given as inputs) with exit 1, the file and what was
expected named, and the page written before left as it was. About 5 s.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR; chromium from scripts/setup.sh.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
from sphere_report_check import check as report_check  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
NMV = f"{SRC}/parts/machines/nmv5000.yaml"
W = tempfile.mkdtemp(prefix="probeloop-sphere-report-")
check = Checks()
t_start = time.monotonic()


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def must(*args):
    code, out, err = run(*args)
    if code != 0:
        print(f"FAIL probeloop {' '.join(args)}: exit {code}\n{err}")
        shutil.rmtree(W, ignore_errors=True)
        raise SystemExit(1)
    return out


try:
    art = f"{W}/artifact.yaml"
    text = open(f"{SRC}/parts/sphere_artifact.yaml").read()
    assert "  count: 12\n" in text
    open(art, "w").write(text.replace("  count: 12\n", "  count: 6\n"))
    must("plan", art, "--machine", NMV, "--out", f"{W}/plan")
    must("simulate", f"{W}/plan/sphere_cycle.nc", "--machine", NMV, "--part", art,
         "--truth", f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "1")
    must("evaluate", f"{W}/run/dprnt.txt", "--format", "fanuc", "--manifest", f"{W}/plan/plan.json",
         "--out", f"{W}/eval", "--scene", f"{W}/eval/campaign.gltf")
    print(f"     campaign planned, simulated and evaluated in {time.monotonic() - t_start:.1f} s")
    ev, inputs, plan = f"{W}/eval/evaluation.json", f"{W}/run/inputs.csv", f"{W}/plan/plan.json"
    evaluation = json.load(open(ev))
    check("the evaluation holds the 6 cycles", len(evaluation["cycles"]) == 6, len(evaluation["cycles"]))

    # --- the full page ------------------------------------------------------------------------
    html = f"{W}/eval/report.html"
    code, out, err = run("report", "sphere", "--evaluation", ev, "--inputs", inputs, "--manifest", plan,
                         "--scene", f"{W}/eval/campaign.gltf", "--html", html)
    check("report sphere writes the page and says so", code == 0 and out.startswith(f"Wrote {html} "), out + err)
    # 11 plots: the 7 errors, then the simulator's inputs by unit: °C, rpm, mm/min, no unit.
    ok, text = report_check(html, ev, inputs=inputs, manifest=plan, scene="campaign.gltf", n_plots=11)
    print("\n".join("     " + line for line in text.splitlines()))
    check("the page shows the errors with U, the inputs, the budgets and the schedule (Chromium)", ok)
    page = open(html, encoding="utf-8").read()
    machine = json.load(open(plan))["machine"]["name"]
    check("the header names the machine, the cycles and the span",
          f"on {machine}</h1>" in page and "6 evaluated, reference cycle 1" in page and "(h:mm)" in page, page[:3000])

    # --- same inputs, same bytes; a scene link relative to another folder --------------------
    os.makedirs(f"{W}/pages")
    again = f"{W}/pages/report.html"
    must("report", "sphere", "--evaluation", ev, "--inputs", inputs, "--manifest", plan, "--html", again)
    must("report", "sphere", "--evaluation", ev, "--inputs", inputs, "--manifest", plan, "--html", f"{W}/pages/r2.html")
    check("same inputs, byte-identical pages",
          open(again, "rb").read() == open(f"{W}/pages/r2.html", "rb").read())
    must("report", "sphere", "--evaluation", ev, "--scene", f"{W}/eval/campaign.gltf", "--html", f"{W}/pages/min.html")
    check("the scene is linked relative to the page's folder",
          '<a href="../eval/campaign.gltf">' in open(f"{W}/pages/min.html", encoding="utf-8").read())

    # --- without the optional inputs: the seven errors, said what is missing -----------------
    ok, text = report_check(f"{W}/pages/min.html", ev, scene="../eval/campaign.gltf", n_plots=7)
    print("\n".join("     " + line for line in text.splitlines() if not line.startswith("ok   plot-")))
    check("without --inputs and --manifest: the seven error plots, no schedule (Chromium)", ok)
    minimal = open(f"{W}/pages/min.html", encoding="utf-8").read()
    check("the page says what the missing inputs would add",
          "No inputs given" in minimal and "No plan given (--manifest" in minimal)

    # --- refusals: exit 1, the file and what was expected, the page left as it was -----------
    before = open(html, "rb").read()

    def refused(name, args, *needles):
        code, out, err = run("report", "sphere", *args, "--html", html)
        msg = out + err
        check(f"refused: {name}", code == 1 and all(n in msg for n in needles) and open(html, "rb").read() == before,
              f"exit {code}: {msg}")

    ttp_eval = f"{W}/ttp_evaluation.json"
    json.dump({"format": "probeloop-evaluation", "version": 1, "kind": "thermal_test_piece", "cycles": []},
              open(ttp_eval, "w"))
    refused("a thermal test piece's evaluation", ["--evaluation", ttp_eval],
            ttp_eval, 'has kind "thermal_test_piece", expected "sphere_artifact"')
    with open(inputs) as f:
        lines = f.read().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("time_s,"))  # after the # comments
    lines[header] = lines[header].replace("time_s,", "t_s,", 1)
    no_time = f"{W}/no_time.csv"
    open(no_time, "w").write("\n".join(lines) + "\n")
    refused("inputs without a time_s column", ["--evaluation", ev, "--inputs", no_time],
            f"{no_time}:{header + 1}:", "no time_s column")
    refused("an errors.csv given as the inputs", ["--evaluation", ev, "--inputs", f"{W}/eval/errors.csv"],
            f"{W}/eval/errors.csv", "an error series")
    code, _, err = run("plan", f"{SRC}/parts/thermal_test_piece.yaml", "--machine", NMV, "--out", f"{W}/ttp_plan")
    check("plan the thermal test piece (a manifest of another kind)", code == 0, err)
    refused("a thermal test piece's plan as the manifest", ["--evaluation", ev, "--manifest", f"{W}/ttp_plan/plan.json"],
            f"{W}/ttp_plan/plan.json", 'expected "sphere_artifact"')
    code, _, err = run("report", "sphere", "--evaluation", ev)
    check("--html is required (usage, exit 2)", code == 2 and "--html" in err, err)
finally:
    shutil.rmtree(W, ignore_errors=True)
print(f"     {time.monotonic() - t_start:.1f} s")
check.finish()
