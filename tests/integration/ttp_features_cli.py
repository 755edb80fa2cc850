#!/usr/bin/env python3
"""The thermal test piece evaluated from the features a CMM states, without points (issue 34
item 3; docs/thermal-test-piece-evaluation.md §10).

plan the shipped piece (20 min between cycles) on the NMV 5000 -> simulate the test and the CMM
(its QIF 3.0 Results and DMIS output, features and points) -> evaluate the point route from the
QIF, and from the same QIF with foreign feature names (points assigned by the nominal geometry:
the same values). Then, from the same CMM run, with the points removed here in Python:
- the QIF's MeasuredFeatures only: every value equals the point route's to the file's rounding
  (6 decimals of a mm) and lies within the combined U sqrt(U_points^2 + U_features^2);
- a feature CSV written from the QIF's features: foreign ids in a shuffled order (matched by the
  nominal geometry), the planned point counts stated, a reference sphere and a point the plan
  does not have (listed as not used, not dropped silently): the same;
- the DMIS output's FA actuals without the point statements (no form stated: the specification
  carries the scatter): the same values to the file's rounding, within the combined U;
- refused with the file and what is missing: a datum absent, a plane row named as the cylinder.
The largest |features - points| / combined U per quantity is printed. About 5 s.

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
NMV = f"{SRC}/parts/machines/nmv5000.yaml"
W = tempfile.mkdtemp(prefix="probeloop-ttp-features-")
check = Checks()
run, must = cli(PL, W)
Q = ["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"]
HEADER = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points"


def values(ev):
    """(cycle, quantity) -> (value, U)"""
    return {(c["cycle"], b["quantity"]): (b["value"], b["U"]) for c in ev["cycles"] for b in c["values"]}


def compare(name, ev_p, ev_f, exact=None):
    """Every value of the point route present and within the combined U; the largest ratio per quantity."""
    vp, vf = values(ev_p), values(ev_f)
    missing = sorted(set(vp) - set(vf))
    worst = {}
    for key, (v, U) in vp.items():
        if key not in vf or key[0] == 0:
            continue
        w, Uf = vf[key]
        r = abs(w - v) / math.hypot(U, Uf)
        q = key[1]
        if r >= worst.get(q, (0, 0))[0]:
            worst[q] = (r, abs(w - v))
    print(f"     {name}: largest |features - points| / sqrt(U_points^2 + U_features^2), largest difference:")
    for q in Q:
        r, d = worst[q]
        print(f"       {q:8s} {r:.4f}  {d:.4f} {q.split('_')[1]}")
    check(f"{name}: every value of every cycle is given", not missing, missing[:5])
    check(f"{name}: every value within the combined U", all(r <= 1 for r, _ in worst.values()), worst)
    if exact is not None:
        d = max(d for q, (r, d) in worst.items() if q != "EB_urad")
        check(f"{name}: the same values as the point route to the file's rounding ({d:.4f} <= {exact})", d <= exact, worst)


def u_ratios(ev_p, ev_f):
    """U_features / U_points over every value of the measurement cycles."""
    vp, vf = values(ev_p), values(ev_f)
    return [vf[k][1] / vp[k][1] for k in vp if k[0] > 0 and k in vf and vp[k][1] > 0]


def strip_qif_points(text):
    text = re.sub(r'\s*<PointList n="\d+">\s*<WholePointSetId>\d+</WholePointSetId>\s*</PointList>', "", text)
    return re.sub(r'\s*<MeasuredPointSets n="\d+">.*?</MeasuredPointSets>', "", text, flags=re.S)


def strip_dmis_points(text):
    out, lines, i = [], text.split("\n"), 0
    while i < len(lines):
        stmt = [lines[i]]
        while stmt[-1].rstrip().endswith("$") and not stmt[-1].startswith("$$") and i + 1 < len(lines):
            i += 1
            stmt.append(lines[i])
        if not re.match(r"FA\([A-Z0-9_]+_P\d+\)=FEAT/POINT", stmt[0]):
            out += stmt
        i += 1
    return "\n".join(out)


def qif_features(text):
    """(name, kind, location, direction, diameter, form_mm) of every measured feature, by the names of the QIF's Features."""
    ns = {"q": "http://qifstandards.org/xsd/qif3"}
    root = ET.fromstring(text)
    names = {}
    for item in root.iter():
        if item.tag.endswith("FeatureItem") and item.get("id"):
            n = item.find("q:FeatureName", ns)
            names[item.get("id")] = n.text if n is not None else None
    out = []
    for m in root.iter():
        if not m.tag.endswith("FeatureMeasurement"):
            continue
        kind = m.tag.split("}")[1].replace("FeatureMeasurement", "").lower()
        name = names[m.find("q:FeatureItemId", ns).text]
        nums = lambda tag: [float(x) for x in m.find(tag, ns).text.split()]  # noqa: E731
        if kind == "plane":
            loc, d, size = nums("q:Location"), nums("q:Normal"), ""
        else:
            loc, d, size = nums("q:Axis/q:AxisPoint"), nums("q:Axis/q:Direction"), float(m.find("q:Diameter", ns).text)
        out.append((name, kind, loc, d, size, float(m.find("q:Form", ns).text)))
    return out


try:
    piece = f"{W}/ttp.yaml"
    text = open(f"{SRC}/parts/thermal_test_piece.yaml").read()
    assert "  wait: 1 h " in text
    open(piece, "w").write(text.replace("  wait: 1 h ", "  wait: 20 min "))
    must("plan", piece, "--machine", NMV, "--out", f"{W}/plan")
    PLAN = f"{W}/plan/plan.json"
    plan = json.load(open(PLAN))
    must("simulate", *[f"{W}/plan/{p}" for p in ("pre_machining.nc", "thermal_test.nc", "inspection.nc")], "--machine", NMV,
         "--part", piece, "--truth", f"{SRC}/examples/truth_thermal_test.yaml", "--cmm-points", f"{W}/plan/cmm_plan.qif",
         "--out", f"{W}/run", "--seed", "5")
    must("evaluate", f"{W}/run/cmm_results.qif", "--manifest", PLAN, "--out", f"{W}/points")
    ev_p = json.load(open(f"{W}/points/evaluation.json"))
    check("the point route evaluates 8 cycles", len(ev_p["cycles"]) == 9 and ev_p["input"]["points"] == 364, ev_p["input"])

    # --- 0. the QIF's points under foreign names: the point route by the nominal geometry ------
    k = iter(range(1, 1000))
    foreign = re.sub(r"<FeatureName>[A-Z0-9_]+</FeatureName>", lambda m: f"<FeatureName>FEAT_{next(k):03d}</FeatureName>",
                     open(f"{W}/run/cmm_results.qif").read())
    open(f"{W}/foreign_points.qif", "w").write(foreign)
    code, out, err = run("evaluate", f"{W}/foreign_points.qif", "--manifest", PLAN, "--out", f"{W}/foreign_points")
    ev_fp = json.load(open(f"{W}/foreign_points/evaluation.json")) if code == 0 else {"cycles": [], "input": {}}
    check("QIF points under foreign names: assigned by the nominal geometry, the same values as by labels",
          code == 0 and ev_fp["input"]["assigned_by"] == "nominal geometry" and values(ev_fp) == values(ev_p), err)

    # --- 1. the QIF's MeasuredFeatures only ------------------------------------------------------
    qif = strip_qif_points(open(f"{W}/run/cmm_results.qif").read())
    check("the test removed every point set", "MeasurePoint" not in qif and "WholePointSetId" not in qif)
    open(f"{W}/features.qif", "w").write(qif)
    code, out, err = run("evaluate", f"{W}/features.qif", "--manifest", PLAN, "--out", f"{W}/qif")
    check("evaluate: a QIF of features only takes the features route", code == 0 and
          "the features a CMM states (qif)" in out and "49 features matched by labels" in out, out + err)
    ev_q = json.load(open(f"{W}/qif/evaluation.json"))
    compare("QIF MeasuredFeatures", ev_p, ev_q, exact=0.002)
    r = u_ratios(ev_p, ev_q)
    print(f"     U_features / U_points: {min(r):.3f} to {max(r):.3f}")
    check("the stated forms' U is the point route's within -5 % / +30 % (the forms pooled: a range-based estimate of the "
          "same scatter)", 0.95 <= min(r) and max(r) <= 1.3, (min(r), max(r)))
    st = ev_q["stated_features"]
    check("evaluation.json states each feature, its form and the sigma used, and what is lost",
          len(st["features"]) == 49 and all(f["form_um"] > 0 and f["point_sigma_um"] > 0 for f in st["features"]) and
          any("Lost against the point route" in n for n in st["notes"]), st["features"][:2])
    b = [c for c in ev_q["cycles"] if c["cycle"] == 3][0]["values"][0]
    inputs = {x["input"]: x for x in b["contributions"]}
    check("the budget names its scatter: the stated features (forms pooled or the MPE), no type A of points",
          "CMM point scatter from the stated features, this and the reference cycle" in inputs and
          inputs["point scatter (type A), this and the reference cycle"]["u"] == 0, list(inputs))
    report = open(f"{W}/qif/report.md").read()
    check("report.md lists the stated features", "## Stated features" in report and "| TOP | TOP |" in report)
    check("the QIF states least squares for every feature (SubstituteFeatureAlgorithm), and the notes say so",
          any("The file states the fitting criterion of 49 of its 49 features: least squares for 49" in n for n in st["notes"]),
          st["notes"])

    # --- 2. a feature CSV: foreign ids, shuffled, counts stated, extra rows ----------------------
    counts = {}
    for p in plan["points"]:
        counts[p["feature"]] = counts.get(p["feature"], 0) + 1
    feats = qif_features(qif)
    random.Random(7).shuffle(feats)
    # The fitting criterion stated per row (column algorithm): least squares, one facet Chebyshev.
    rows = [HEADER + ",algorithm", "1,REF_SPHERE,sphere,300,0,50,,,,25.4,0.3,25,", "1,PT_7,point,1,2,3,,,,,,1,"]
    chebyshev = sorted(name for name, *_ in feats if name.startswith("X1_"))[0]
    for k, (name, kind, loc, d, size, form) in enumerate(feats):
        kind = "circle" if kind == "cylinder" else kind  # a CMM reports the one-level band as a circle
        rows.append(f"1,{kind.upper()}_{k + 1},{kind},{loc[0]!r},{loc[1]!r},{loc[2]!r},{d[0]!r},{d[1]!r},{d[2]!r},"
                    f"{size!r},{form * 1e3!r},{counts[name]},{'MINMAX' if name == chebyshev else 'least_squares'}"
                    .replace(",'',", ",,"))
    open(f"{W}/features.csv", "w").write("\n".join(rows) + "\n")
    code, out, err = run("evaluate", f"{W}/features.csv", "--manifest", PLAN, "--out", f"{W}/csv")
    check("evaluate: a feature CSV (auto-detected), foreign ids by the nominal geometry",
          code == 0 and "49 features matched by nominal geometry" in out, out + err)
    ev_c = json.load(open(f"{W}/csv/evaluation.json"))
    compare("feature CSV, foreign ids", ev_p, ev_c, exact=0.002)
    st = ev_c["stated_features"]
    check("the sphere the plan does not have is listed as not used, the point row counted",
          len(st["unmatched"]) == 1 and "sphere 'REF_SPHERE' (nearest feature: none of its kind)" in st["unmatched"][0] and
          f"{W}/features.csv:2" in st["unmatched"][0] and st["rows_of_other_kinds_not_used"] == 1, st["unmatched"])
    # Ten times the planned points stated for every feature (a scanning CMM): U not below the
    # planned layout's (the counts only change the form's d2(n)).
    many = [rows[0]] + [",".join(r.split(",")[:11] + [str(10 * int(r.split(",")[11]))] + r.split(",")[12:]) for r in rows[1:]]
    open(f"{W}/many.csv", "w").write("\n".join(many) + "\n")
    code, out, err = run("evaluate", f"{W}/many.csv", "--manifest", PLAN, "--out", f"{W}/many")
    ev_m = json.load(open(f"{W}/many/evaluation.json")) if code == 0 else {"cycles": []}
    r = u_ratios(ev_p, ev_m)
    check("ten times the planned points stated: U stays at least 0.95 of the point route's, and a note says why",
          code == 0 and min(r) >= 0.95 and any(n.startswith("More points stated than planned") for n in ev_m["stated_features"]["notes"]),
          (min(r) if r else None, err))
    check("each feature names its row and the counts the file states",
          all(f["matched_by"] == "nominal geometry" and f["n_points_stated"] == counts[f["id"]] for f in st["features"]))
    check("the criterion the rows state: 48 least squares, the one Chebyshev facet named",
          any(f"least squares for 48 (the point route's criterion); another for {chebyshev} (MINMAX)" in n for n in st["notes"]),
          st["notes"])

    # --- 3. the DMIS output's FA actuals, no points ------------------------------------------------
    dmo = strip_dmis_points(open(f"{W}/run/cmm_results.dmo").read())
    check("the test removed every FEAT/POINT statement",
          not any("=FEAT/POINT" in l for l in dmo.splitlines() if not l.startswith("$$")))
    open(f"{W}/features.dmo", "w").write(dmo)
    code, out, err = run("evaluate", f"{W}/features.dmo", "--manifest", PLAN, "--out", f"{W}/dmis")
    check("evaluate: a DMIS output of FA actuals only takes the features route",
          code == 0 and "the features a CMM states (dmis)" in out, out + err)
    ev_d = json.load(open(f"{W}/dmis/evaluation.json"))
    compare("DMIS FA actuals", ev_p, ev_d, exact=0.002)
    check("DMIS FA states no criterion: taken as least squares, said so",
          any(n.startswith("The file does not say how its features were fitted") for n in ev_d["stated_features"]["notes"]))
    check("no form in DMIS FA: the notes say U may be below the point route's",
          any(n.startswith("Neither a form nor an uncertainty stated for") and "may be below the point route's" in n
              for n in ev_d["stated_features"]["notes"]))
    r = u_ratios(ev_p, ev_d)
    print(f"     DMIS: U_features / U_points: {min(r):.3f} to {max(r):.3f}")
    check("no form in DMIS FA: every feature's scatter is the specification",
          all(f["point_sigma_from"] == "specification" and f["form_um"] is None for f in ev_d["stated_features"]["features"]))

    # --- 4. refusals ------------------------------------------------------------------------------
    flank = [r for r in rows[1:] if ",plane," in r and abs(float(r.split(",")[4]) - 55) < 0.5 and abs(float(r.split(",")[5]) + 5.25) < 0.5]
    check("the test found FLANK_P's row", len(flank) == 1, flank)
    open(f"{W}/no_flank.csv", "w").write("\n".join(r for r in rows if r not in flank) + "\n")
    code, out, err = run("evaluate", f"{W}/no_flank.csv", "--manifest", PLAN, "--out", f"{W}/no_flank")
    check("refused: a datum missing, naming it and what the frame needs",
          code == 1 and "the datum FLANK_P is not among the file's features" in err and not os.path.exists(f"{W}/no_flank"), err)
    named = [r.replace(r.split(",")[1], "CYL", 1) if r in flank else r for r in rows]
    open(f"{W}/named_cyl.csv", "w").write("\n".join(named) + "\n")
    line = named.index([r for r in named if ",CYL," in r][0]) + 1
    code, out, err = run("evaluate", f"{W}/named_cyl.csv", "--manifest", PLAN, "--out", f"{W}/named_cyl")
    check("refused: a plane row named as the cylinder, with its line",
          code == 1 and f"named_cyl.csv:{line}: 'CYL' is a cylinder in the plan" in err, err)
finally:
    shutil.rmtree(W, ignore_errors=True)
check.finish()
