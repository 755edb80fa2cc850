#!/usr/bin/env python3
"""The stepped workpiece (seed 000) evaluated from the CMM's stated planes, no points (issue 34
item 3; docs/stepped-workpiece.md#evaluating-from-features).

plan W8 on the 3-axis VMC -> simulate it with the QIF plan as the CMM's points (the virtual CMM
writes cmm_results.qif and cmm_results.dmo) -> evaluate the QIF with its points and the probe log
(the point route). Then the CMM side from features only, the probe log unchanged:
(a) that QIF with its point sets removed here (MeasuredFeatures only);
(b) a feature-actuals CSV written here from the QIF's features (location, normal, form, the point
    count of each set) with foreign ids in a shuffled order, matched by nominal geometry, plus an
    alignment plane of the CMM's that fits no plane of the plan (listed, not used);
(c) the DMIS output's FA(..)=FEAT/PLANE actuals with every point line removed.
Every value (e_pos, e_proc, e_splz, k_pos and per step the widths, depth, tilts, slopes, Oz of the
CMM) agrees with the point route within the combined U sqrt(U_points^2 + U_features^2); the
largest ratio per quantity is printed. The outputs say what is lost. Refusals: a plane missing
from the file (as the point route refuses a plane without points), a plane's id given to a row of
another kind, one plane given twice, each with the file (and line). About 3 s.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR.
"""
import json
import math
import os
import random
import re
import shutil
import sys
import tempfile
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks, cli  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
VMC = f"{SRC}/parts/machines/vmc3.yaml"
PIECE = f"{SRC}/parts/stepped_workpiece.yaml"
W = tempfile.mkdtemp(prefix="probeloop-swfeat-")
Q = "{http://qifstandards.org/xsd/qif3}"
HEADER = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points"
SEPARATED = ["e_pos_x_um", "e_pos_y_um", "e_pos_z_um", "e_proc_x_um", "e_proc_y_um", "e_splz_um"]
GEOMETRY = [("width_x_error_um", None), ("width_y_error_um", None), ("depth_error_um", None),
            ("wall_tilt_x_urad", "U_wall_tilt_x_urad"), ("wall_tilt_y_urad", "U_wall_tilt_y_urad"),
            ("floor_slope_x_urad", "U_floor_slope_x_urad"), ("floor_slope_y_urad", "U_floor_slope_y_urad"),
            ("oz_urad", "U_oz_urad")]
check = Checks()
run, must = cli(PL, W)


def write(name, text):
    path = f"{W}/{name}"
    with open(path, "w") as f:
        f.write(text)
    return path


def evaluate(cmm, out, *extra):
    return run("evaluate", cmm, "--probe-log", LOG, "--manifest", PLAN, "--out", f"{W}/{out}", *extra)


def ratios(ev_f, ev_p):
    """Per quantity the largest |features - points| / sqrt(U_points^2 + U_features^2) over the
    steps, and the range of U_features / U_points over every value."""
    r = {}
    u = []

    def put(name, d, U, Uf=None, Up=None):
        r[name] = max(r.get(name, 0.0), abs(d) / U if U > 0 else math.inf)
        if Uf is not None and Up > 0:
            u.append(Uf / Up)

    for sf, sp in zip(ev_f["separation"], ev_p["separation"]):
        for q in SEPARATED:
            put(q, sf[q]["value"] - sp[q]["value"], math.hypot(sf[q]["U"], sp[q]["U"]), sf[q]["U"], sp[q]["U"])
    for a in "xyz":
        q = f"k_pos_{a}_um_per_mm"
        put(q, ev_f[q]["value"] - ev_p[q]["value"], math.hypot(ev_f[q]["U"], ev_p[q]["U"]), ev_f[q]["U"], ev_p[q]["U"])
    for gf, gp, sf, sp in zip(ev_f["cmm"]["steps"], ev_p["cmm"]["steps"], ev_f["separation"], ev_p["separation"]):
        for q, uq in GEOMETRY:
            if uq is None:  # the CMM's width/depth: its u (MPE, planes, temperature) x 2
                key = {"width_x_error_um": "u_cmm_width_x_um", "width_y_error_um": "u_cmm_width_y_um",
                       "depth_error_um": "u_cmm_depth_um"}[q]
                Uf, Up = 2 * sf[key], 2 * sp[key]
            else:
                Uf, Up = gf[uq], gp[uq]
            put("cmm " + q, gf[q] - gp[q], math.hypot(Uf, Up), Uf, Up)
    return r, (min(u), max(u))


def agrees(label, ev_f, ev_p, u_floor=None):
    r, (lo, hi) = ratios(ev_f, ev_p)
    print(f"     {label}: largest |features - points| / sqrt(U_points^2 + U_features^2) over the 4 steps:")
    print("       " + ", ".join(f"{q} {v:.3f}" for q, v in r.items()))
    print(f"       U_features / U_points from {lo:.3f} to {hi:.3f}")
    check(f"{label}: every value within the combined U of the point route's (largest ratio {max(r.values()):.3f})",
          all(v <= 1 for v in r.values()), r)
    if u_floor is not None:
        check(f"{label}: with the forms stated, no U below {u_floor} of the point route's", lo >= u_floor, lo)


try:
    must("plan", PIECE, "--machine", VMC, "--out", f"{W}/plan", "--experiment", "W8")
    PLAN = f"{W}/plan/plan.json"
    must("simulate", f"{W}/plan/roughing.ngc", f"{W}/plan/finishing.ngc", f"{W}/plan/probing.ngc", "--machine", VMC,
         "--part", PIECE, "--truth", f"{SRC}/examples/stepped_workpiece/truth.yaml", "--cmm-points", f"{W}/plan/cmm_plan.qif",
         "--schedule", PLAN, "--out", f"{W}/run", "--seed", "3")
    LOG = f"{W}/run/sw_probe.log"
    QIF = f"{W}/run/cmm_results.qif"
    code, out_p, err = evaluate(QIF, "points")
    check("the point route: the simulated CMM's QIF results with their points", code == 0, err)
    ev_p = json.load(open(f"{W}/points/evaluation.json"))
    check("  21 planes fitted from points, no from_features", len(ev_p["cmm"]["planes"]) == 21 and
          "from_features" not in ev_p["cmm"] and "CMM planes from the stated features" not in out_p)

    # --- (a) the QIF with its point sets removed: MeasuredFeatures only -----------------------
    text = open(QIF).read()
    bare = re.sub(r"\s*<PointList n=\"\d+\">.*?</PointList>", "", text, flags=re.S)
    bare = re.sub(r"\s*<MeasuredPointSets n=\"\d+\">.*?</MeasuredPointSets>", "", bare, flags=re.S)
    check("(a) the QIF without points holds 21 plane measurements and no point set",
          bare.count("<PlaneFeatureMeasurement") == 21 and "MeasuredPointSet" not in bare and "<Points>" not in bare)
    qa = write("features.qif", bare)
    code, out, err = evaluate(qa, "qif")
    check("(a) evaluate reads the QIF's stated planes (auto: a QIF without points)", code == 0 and
          out.startswith(f"CMM planes from the stated features of {qa} (no points; 21 planes matched by labels"), out + err)
    ev_a = json.load(open(f"{W}/qif/evaluation.json")) if code == 0 else ev_p
    agrees("(a) QIF MeasuredFeatures", ev_a, ev_p, u_floor=0.95)
    ff = ev_a["cmm"].get("from_features", {})
    check("(a) evaluation.json: each plane's row, how it was matched, its form and the sigma used",
          ff.get("format") == "qif" and len(ff.get("planes", [])) == 21 and
          all(p["matched_by"] == "id" and p["form_um"] is not None and p["sigma_um"] > 0 and p["n_stated"] == 0
              for p in ff["planes"]), ff)
    notes = " ".join(ev_a["notes"])
    report = open(f"{W}/qif/report.md").read() if code == 0 else ""
    lost = "lost against the point route: the real point layout and residuals"
    criterion = "The file states the fitting criterion of 21 of its 21 features: least squares for 21"
    check("(a) what is lost, in the notes and report.md (layout and residuals, outliers, the lines), and the criterion "
          "the QIF states (SubstituteFeatureAlgorithm)",
          lost in notes and lost in report and "outliers" in notes and "line of each point" in notes and
          criterion in notes and "## CMM planes from the stated features" in report, notes)
    e_pos = ev_a["separation"][0]["e_pos_x_um"]["contributions"]
    check("(a) the e_pos budget's CMM term says it comes from the stated features",
          any(c["input"] == "CMM planes as stated" and c["basis"].startswith("from the stated features") for c in e_pos),
          [c["input"] for c in e_pos])

    # --- (b) a feature CSV from the QIF's features: foreign ids, shuffled, an alignment plane ---
    root = ET.fromstring(text)
    names = {i.get("id"): i.find(f"{Q}FeatureName").text for i in root.iter(f"{Q}PlaneFeatureItem")}
    counts = {s.get("id"): int(s.get("count")) for s in root.iter(f"{Q}MeasuredPointSet")}
    rows = []
    for f in root.iter(f"{Q}PlaneFeatureMeasurement"):
        loc = f.find(f"{Q}Location").text.split()
        nrm = f.find(f"{Q}Normal").text.split()
        n = counts[f.find(f"{Q}PointList/{Q}WholePointSetId").text]
        form = float(f.find(f"{Q}Form").text) * 1e3
        rows.append((names[f.find(f"{Q}FeatureItemId").text], loc, nrm, form, n))
    random.Random(7).shuffle(rows)
    lines = [HEADER]
    for k, (_, loc, nrm, form, n) in enumerate(rows):
        lines.append(f"1,Plane {k + 1},PLANE,{','.join(loc)},{','.join(nrm)},,{form!r},{n}")
    lines.append("1,ALIGN_Z,plane,15,15,40,0,0,1,,0.8,12")  # the CMM's own alignment plane, 40 mm above the top
    csv = write("features.csv", "\n".join(lines) + "\n")
    code, out, err = evaluate(csv, "csv")
    check("(b) the feature CSV (auto-detected): 21 planes matched by nominal geometry, the alignment row listed",
          code == 0 and "21 planes matched by nominal geometry, 1 row fits no plane" in out and
          f"{csv}:23: plane 'ALIGN_Z' (nearest TOP, 40 mm: off its plane by 40 mm (at most 0.5))" in out, out + err)
    ev_b = json.load(open(f"{W}/csv/evaluation.json")) if code == 0 else ev_p
    agrees("(b) feature CSV, foreign ids", ev_b, ev_p, u_floor=0.95)
    fb = ev_b["cmm"].get("from_features", {})
    by_id = {p["id"]: p for p in fb.get("planes", [])}
    first = rows[0][0]
    check("(b) the first shuffled row is the plane it was written from, with the file's n and line",
          by_id.get(first, {}).get("row") == f"Plane 1 ({csv}:2)" and by_id[first]["n_stated"] == rows[0][4] and
          by_id[first]["matched_by"] == "nominal geometry" and fb["unmatched"] == [
              f"{csv}:23: plane 'ALIGN_Z' (nearest TOP, 40 mm: off its plane by 40 mm (at most 0.5))"], fb)
    code2, _, _ = evaluate(csv, "csv2")
    same = code2 == 0 and all(open(f"{W}/csv/{f}", "rb").read() == open(f"{W}/csv2/{f}", "rb").read()
                              for f in ("errors.csv", "evaluation.json", "report.md", "compensation.json", "results.qif"))
    check("(b) the same file evaluated again: byte-identical outputs", same)

    # --- (c) the DMIS output's FA actuals, every point line removed ----------------------------
    dmo = open(f"{W}/run/cmm_results.dmo").read().split("\n")
    kept, skip = [], False
    for line in dmo:
        if skip or re.match(r"FA\(\w+_P\d+\)=FEAT/POINT", line):
            skip = line.rstrip().endswith("$")  # its continuation line goes with it
            continue
        kept.append(line)
    dm = write("features.dmo", "\n".join(kept))
    check("(c) the DMIS output without points holds 21 FA(..)=FEAT/PLANE actuals",
          sum(1 for l in kept if re.match(r"FA\(\w+\)=FEAT/PLANE", l)) == 21 and
          not any(re.match(r"FA\(\w+_P\d+\)", l) for l in kept))
    code, out, err = evaluate(dm, "dmis")
    check("(c) evaluate reads the DMIS actuals' planes", code == 0 and out.startswith(f"CMM planes from the stated features of {dm}"),
          out + err)
    ev_c = json.load(open(f"{W}/dmis/evaluation.json")) if code == 0 else ev_p
    agrees("(c) DMIS FA actuals", ev_c, ev_p)
    check("(c) no form stated: the notes say U may be below the point route's",
          any(n.startswith("Neither a form nor an uncertainty stated for") and "may be below the point route's" in n
              for n in ev_c["notes"]), ev_c["notes"])
    check("(c) DMIS states no form: every plane's sigma is the MPE's, the e_pos terms type B (no dof)",
          all(p["sigma_from"] == "MPE" and p["form_um"] is None for p in ev_c["cmm"]["from_features"]["planes"]) and
          all(c["type"] == "B" and c["dof"] is None for s in ev_c["separation"] for q in ("e_pos_x_um", "e_pos_z_um")
              for c in s[q]["contributions"] if c["input"] == "CMM planes as stated"))

    # --- refusals -------------------------------------------------------------------------------
    body = open(csv).read().splitlines()
    s2yn = [i for i, r in enumerate(rows) if r[0] == "S2_YN"][0] + 1  # its line index in body
    holed = write("holed.csv", "\n".join(l for i, l in enumerate(body) if i != s2yn) + "\n")
    code, out, err = evaluate(holed, "holed")
    check("refused: a plane missing from the file, named with the values that need it",
          code == 1 and f"{holed}: feature S2_YN (wall): not in the file" in err and "step 2's width Y" in err and
          not os.path.exists(f"{W}/holed"), err)
    pts = open(f"{W}/run/cmm_export.csv").read().splitlines()
    pholed = write("holed_points.csv", "\n".join(l for l in pts if not l.startswith("S2_YN,")) + "\n")
    code, out, err = evaluate(pholed, "pholed")
    check("  as the point route refuses that plane without points", code == 1 and "feature S2_YN: no points measured" in err, err)
    named = [HEADER] + [f"1,{r[0]},plane,{','.join(r[1])},{','.join(r[2])},,{r[3]!r},{r[4]}" for r in rows]
    line = [l.split(",")[1] for l in named].index("S1_XP") + 1
    _, loc, nrm, form, n = rows[line - 2]
    wrong = write("wrong_kind.csv", "\n".join(named[:line - 1] + [f"1,S1_XP,cylinder,{','.join(loc)},{','.join(nrm)},12,{form!r},{n}"] +
                                              named[line:]) + "\n")
    code, out, err = evaluate(wrong, "wrong")
    check("refused: a plane's id on a row of another kind, with file:line",
          code == 1 and f"{wrong}:{line}: 'S1_XP' is a plane in the plan" in err and "the file gives a cylinder" in err, err)
    twice = write("twice.csv", "\n".join(named + [named[line - 1].replace(",S1_XP,", ",WALL_A,")]) + "\n")
    code, out, err = evaluate(twice, "twice")
    check("refused: one plane given twice (by its id and by a foreign row on it), both lines named",
          code == 1 and f"{twice}:{len(named) + 1}: feature S1_XP is given twice: by the row at line {line} ('S1_XP') and "
          f"the row at line {len(named) + 1} ('WALL_A')" in err, err)
finally:
    shutil.rmtree(W, ignore_errors=True)
check.finish()
