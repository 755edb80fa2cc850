#!/usr/bin/env python3
"""The sphere artifact evaluated from feature actuals (issue 34 item 3): sphere centres a CMM
package reports, no points (docs/formats.md#feature-actuals-csv).

plan the shipped sphere artifact for 4 cycles on the NMV 5000 -> simulate it with the demo's
truth -> evaluate the DPRNT log (the point route). Then feature CSVs written here, in Python, from
that evaluation.json:
- the point route's own known-radius centres, ids S<k>: every error equals the point route's to
  rounding (the same numbers go into the same least squares);
- the free-radius centres (another estimate of each centre: the pre-travel lifts them ~10 um),
  foreign ids in a shuffled order, the stated u per coordinate, a semicolon file with decimal
  commas and CRLF: every error agrees with the point route within the combined U
  sqrt(U_points^2 + U_features^2), and the largest difference per error is printed in units of it;
- a QIF 3.0 Results file with only MeasuredFeatures (one MeasurementResults per cycle, the
  point route's centres): the same errors; the same from points only (25 per sphere, exactly
  on a sphere about each centre: fitted here, with the known radius by default); on a 14.998 mm
  sphere (a 2 um pre-travel) --free-radius gives the same errors and the known radius moves each
  centre 3 um down, within the combined U; a sphere with neither refused; with a vendor's
  extension, the reader's warning in stdout, evaluation.json's input_warnings and report.md
  (issue 34 item 4), none in the clean file's outputs, and --strict refusing it;
- refusals with the file and line: an unknown kind, a missing column, two foreign rows on one
  place without time_s, a foreign row far from every sphere; a position without a centre in a
  cycle makes that cycle incomplete, listed as the point route lists it.
The simulator writes no CMM features for the sphere artifact (its CMM stage serves the other
pieces), so no feature file of its own is read here. About 5 s.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR.
"""
import json
import math
import os
import shutil
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks, cli  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
NMV = f"{SRC}/parts/machines/nmv5000.yaml"
W = tempfile.mkdtemp(prefix="probeloop-features-")
check = Checks()
HEADER = "cycle,id,kind,x_mm,y_mm,z_mm,i,j,k,size_mm,form_um,n_points"
NAMES = ["EX0C", "EY0C", "EZ0T", "ER0T", "EA0C", "EB0C", "EC0C"]


run, must = cli(PL, W)


def write(name, text, newline="\n"):
    path = f"{W}/{name}"
    with open(path, "w", newline="") as f:
        f.write(text.replace("\n", newline))
    return path


def evaluate_features(path, out):
    return run("evaluate", path, "--format", "features", "--manifest", PLAN, "--out", f"{W}/{out}")


def budgets(ev):
    return {c["cycle"]: c["budgets"] for c in ev["cycles"]}


try:
    art = f"{W}/artifact.yaml"
    text = open(f"{SRC}/parts/sphere_artifact.yaml").read()
    assert "  count: 12\n" in text
    open(art, "w").write(text.replace("  count: 12\n", "  count: 4\n"))
    must("plan", art, "--machine", NMV, "--out", f"{W}/plan")
    PLAN = f"{W}/plan/plan.json"
    must("simulate", f"{W}/plan/sphere_cycle.nc", "--machine", NMV, "--part", art,
         "--truth", f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "1")
    must("evaluate", f"{W}/run/dprnt.txt", "--format", "fanuc", "--manifest", PLAN, "--out", f"{W}/points")
    ev_p = json.load(open(f"{W}/points/evaluation.json"))
    plan = json.load(open(PLAN))
    tip = plan["probe"]["tip_radius_mm"]
    check("the point route evaluates the 4 cycles", len(ev_p["cycles"]) == 4, len(ev_p["cycles"]))

    # --- 1. the point route's own centres, ids S<k>: the same errors to rounding --------------
    rows = [HEADER]
    for c in ev_p["cycles"]:
        for s in c["spheres"]:
            x, y, z = s["centre_mm"]
            fr = s["free_radius"]
            rows.append(f"{c['cycle']},S{s['position']},sphere,{x!r},{y!r},{z!r},,,,"
                        f"{2 * (fr['radius_mm'] - tip)!r},{fr['form_um']!r},{s['points']}")
    same = write("same.csv", "\n".join(rows) + "\n")
    code, out, err = evaluate_features(same, "same")
    check("evaluate --format features runs on the point route's centres", code == 0, err)
    ev_s = json.load(open(f"{W}/same/evaluation.json"))
    bp, bs = budgets(ev_p), budgets(ev_s)
    worst = max(abs(bs[c][j]["value"] - bp[c][j]["value"]) for c in bp for j in range(7))
    check("the same centres give the same seven errors in every cycle (to 1e-9)", worst <= 1e-9, worst)
    check("and say where the centres came from",
          out.startswith(f"Sphere centres from the feature file {same}") and
          ev_s["centres_from"]["rows_of_other_kinds_not_used"] == 0 and
          all(s["centre_used"] == "feature_file" and s["feature"]["matched_by"] == "id"
              for c in ev_s["cycles"] for s in c["spheres"]), out)
    b = bs[4][0]
    inputs = [x["input"] for x in b["contributions"]]
    check("the budget says what is lost: no point scatter (0), the centres' stated terms carried instead",
          "sphere centres as the feature file states them, this cycle" in inputs and
          any(x["input"].startswith("probe point scatter") and x["u"] == 0 and "no points" in x["basis"]
              for x in b["contributions"]) and
          not any(x["input"].startswith("coordinate resolution") for x in b["contributions"]), inputs)
    report = open(f"{W}/same/report.md").read()
    check("report.md says the centres are the file's", "as the feature file states them (no points)" in report)

    # --- 2. other centres (free radius), foreign ids, stated u, ';' + decimal commas + CRLF ----
    rows = ["cycle;id;kind;x_mm;y_mm;z_mm;i;j;k;size_mm;form_um;n_points;u_x_um;u_y_um;u_z_um;time_s",
            "1;TABLE;plane;0;0;0;0;0;1;;3,5;40;;;;0"]  # another kind: read, not used
    for c in reversed(ev_p["cycles"]):
        for s in reversed(c["spheres"]):
            fr = s["free_radius"]
            x, y, z = (repr(v).replace(".", ",") for v in fr["centre_mm"])
            t = repr(c["time_s"] + 30.0 * s["position"]).replace(".", ",")  # the repeat (5 at 1's place) by time
            rows.append(f"{c['cycle']};Sphere_{6 - s['position']};SPHERE;{x};{y};{z};;;;"
                        f"{repr(2 * (fr['radius_mm'] - tip)).replace('.', ',')};0,4;{s['points']};0,6;0,6;0,8;{t}")
    foreign = write("foreign.csv", "\n".join(rows) + "\n", "\r\n")
    code, out, err = evaluate_features(foreign, "foreign")
    check("foreign ids, ';', decimal commas, CRLF, u stated and a plane: evaluated", code == 0, err)
    ev_f = json.load(open(f"{W}/foreign/evaluation.json"))
    check("every foreign sphere matched by its nominal centre; the plane counted, not used",
          all(s["feature"]["matched_by"] == "nearest nominal centre" for c in ev_f["cycles"] for s in c["spheres"]) and
          ev_f["centres_from"]["rows_of_other_kinds_not_used"] == 1 and
          [s["feature"]["id"] for s in ev_f["cycles"][0]["spheres"]] == [f"Sphere_{6 - p}" for p in range(1, 6)],
          [s["feature"]["id"] for s in ev_f["cycles"][0]["spheres"]])
    bf = budgets(ev_f)
    print("     largest |features - points| / sqrt(U_points^2 + U_features^2) over the cycles 2-4:")
    ok = True
    for j, name in enumerate(NAMES):
        r = max(abs(bf[c][j]["value"] - bp[c][j]["value"]) / math.hypot(bf[c][j]["U"], bp[c][j]["U"])
                for c in bp if c != 1)
        d = max(abs(bf[c][j]["value"] - bp[c][j]["value"]) for c in bp if c != 1)
        print(f"       {name}: {r:.3f} (largest difference {d:.4f} {bp[2][j]['unit']})")
        ok = ok and r <= 1
    check("free-radius centres: every error within the combined U of the point route's", ok)
    cb = [x for x in ev_f["cycles"][1]["spheres"][0]["centre_budgets"][0]["contributions"]
          if x["input"] == "sphere centre as the feature file states it"][0]
    check("a stated u is the centre's term", abs(cb["u"] - 0.6) < 1e-12 and "u_x_um of the file" in cb["basis"], cb)

    # --- QIF 3.0 MeasuredFeatures only: one MeasurementResults per cycle, the centres, no points
    def qif(ev, drop_location=False):
        out = ['<?xml version="1.0" encoding="UTF-8"?>',
               '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0" idMax="9999">',
               '  <FileUnits><PrimaryUnits><LinearUnit><SIUnitName>millimeter</SIUnitName><UnitName>mm</UnitName>'
               '</LinearUnit></PrimaryUnits></FileUnits>',
               f'  <Results><MeasurementResultsSet n="{len(ev["cycles"])}">']
        i = 100
        for c in ev["cycles"]:
            i += 1
            out.append(f'    <MeasurementResults id="{i}"><MeasuredFeatures n="{len(c["spheres"])}">')
            for s in c["spheres"]:
                i += 1
                loc = "" if drop_location and s["position"] == 2 else "<Location>%r %r %r</Location>" % tuple(s["centre_mm"])
                out.append(f'      <SphereFeatureMeasurement id="{i}"><FeatureName>S{s["position"]}</FeatureName>{loc}'
                           '<Diameter>30</Diameter><Form>0.0004</Form></SphereFeatureMeasurement>')
            out.append('    </MeasuredFeatures></MeasurementResults>')
        out.append('  </MeasurementResultsSet></Results>\n</QIFDocument>')
        return "\n".join(out) + "\n"
    q = write("centres.qif", qif(ev_p))
    code, out, err = run("evaluate", q, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/qif")
    ev_q = json.load(open(f"{W}/qif/evaluation.json")) if code == 0 else {"cycles": []}
    bq = budgets(ev_q)
    check("QIF MeasuredFeatures (spheres, no points): the same errors as the point route (to 1e-9)",
          code == 0 and sorted(bq) == sorted(bp) and
          max(abs(bq[c][j]["value"] - bp[c][j]["value"]) for c in bp for j in range(7)) <= 1e-9, err)
    # A vendor's extension in the file (issue 34 item 4): read with a warning that reaches every
    # output of the evaluation (stdout, evaluation.json's input_warnings, report.md's section);
    # the clean file's outputs carry neither; --strict refuses it.
    clean = open(q).read()
    at = clean.index("</MeasurementResults>")
    ext_line = clean[:at].count("\n") + 1
    v = write("vendor.qif", clean[:at] + '<v:Probe xmlns:v="urn:vendor">T1</v:Probe>' + clean[at:])
    code, out, err = run("evaluate", v, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/vendor")
    what = "MeasurementResults: unknown extension Probe"
    ev_v = json.load(open(f"{W}/vendor/evaluation.json")) if code == 0 else {}
    iw = ev_v.pop("input_warnings", [])
    check(f"QIF with a vendor extension: the warning at line {ext_line} in stdout and in evaluation.json's input_warnings",
          code == 0 and f"warning: {v}:{ext_line}: {what}" in out and len(iw) == 1 and iw[0]["file"] == v
          and iw[0]["line"] == ext_line and iw[0]["what"].startswith(what), (out[-400:], iw, err))
    check("the same evaluation otherwise (every key but input_warnings, the file's name aside)",
          json.dumps(ev_v).replace(v, q) == json.dumps(ev_q), "")
    rep_v = open(f"{W}/vendor/report.md").read() if code == 0 else ""
    rep_q = open(f"{W}/qif/report.md").read() if os.path.exists(f"{W}/qif/report.md") else ""
    check("report.md: an 'Input warnings' section naming the file and line; the clean file's report has none",
          f"## Input warnings" in rep_v and f"- `{v}` line {ext_line}: {what}" in rep_v and "Input warnings" not in rep_q
          and "input_warnings" not in ev_q, rep_v[-500:])
    # ... and the HTML page made from that evaluation.json (probeloop report sphere).
    c1, _, e1 = run("report", "sphere", "--evaluation", f"{W}/vendor/evaluation.json", "--html", f"{W}/vendor.html")
    c2, _, e2 = run("report", "sphere", "--evaluation", f"{W}/qif/evaluation.json", "--html", f"{W}/clean.html")
    page_v = open(f"{W}/vendor.html").read() if c1 == 0 else ""
    page_q = open(f"{W}/clean.html").read() if c2 == 0 else ""
    check("report sphere: the page from the warned evaluation has the 'Input warnings' section with the line; the clean one none",
          f"<h2>Input warnings</h2>" in page_v and f"line {ext_line}: {what}" in page_v and "Input warnings" not in page_q, e1 + e2)
    code, out, err = run("evaluate", v, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/vendor-strict", "--strict")
    check("--strict: refused at that line, nothing written", code != 0 and f"{v}:{ext_line}: {what}" in err
          and not os.path.exists(f"{W}/vendor-strict/evaluation.json"), err)
    q = write("nolocation.qif", qif(ev_p, drop_location=True))
    code, out, err = run("evaluate", q, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/noloc")
    check("refused: a QIF sphere without its measured Location or points, with its line",
          code == 1 and f"{q}:7:" in err and "sphere 'S2' has no measured Location and 0 points" in err, err)

    # --- QIF 3.0 points only (issue 34 item 2): each sphere's centre fitted here to its points ---
    def qif_points(ev, radius=15.0):
        out = ['<?xml version="1.0" encoding="UTF-8"?>',
               '<QIFDocument xmlns="http://qifstandards.org/xsd/qif3" versionQIF="3.0.0" idMax="99999">',
               f'  <Results><MeasurementResultsSet n="{len(ev["cycles"])}">']
        i = 1000
        for c in ev["cycles"]:
            i += 1
            feats, sets = [], []
            for s in c["spheres"]:
                i += 2
                cx, cy, cz = s["centre_mm"]
                pts = []
                for k in range(25):  # a spiral over the upper hemisphere, exactly on a sphere of the radius
                    t = math.acos(1 - (k + 0.5) / 25)
                    a = 2.399963 * k
                    pts += [cx + radius * math.sin(t) * math.cos(a), cy + radius * math.sin(t) * math.sin(a),
                            cz + radius * math.cos(t)]
                feats.append(f'<SphereFeatureMeasurement id="{i}"><FeatureName>S{s["position"]}</FeatureName><PointList n="1">'
                             f'<WholePointSetId>{i + 1}</WholePointSetId></PointList></SphereFeatureMeasurement>')
                sets.append(f'<MeasuredPointSet id="{i + 1}" count="25"><Points>{" ".join(repr(v) for v in pts)}</Points>'
                            '</MeasuredPointSet>')
            out.append(f'    <MeasurementResults id="{i + 1}"><MeasuredFeatures n="{len(feats)}">' + "".join(feats) +
                       f'</MeasuredFeatures><MeasuredPointSets n="{len(sets)}">' + "".join(sets) +
                       '</MeasuredPointSets></MeasurementResults>')
            i += 1
        out.append('  </MeasurementResultsSet></Results>\n</QIFDocument>')
        return "\n".join(out) + "\n"
    q = write("points.qif", qif_points(ev_p))
    code, out, err = run("evaluate", q, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/qifpts")
    ev_qp = json.load(open(f"{W}/qifpts/evaluation.json")) if code == 0 else {"cycles": []}
    bqp = budgets(ev_qp)
    check("QIF points only: each centre fitted here (25 points), the same errors as the point route (to 1e-9)",
          code == 0 and sorted(bqp) == sorted(bp) and
          max(abs(bqp[c][j]["value"] - bp[c][j]["value"]) for c in bp for j in range(7)) <= 1e-9 and
          all(s["feature"]["centre"].startswith("least-squares sphere of the file's points") and s["feature"]["n_points"] == 25
              for c in ev_qp["cycles"] for s in c["spheres"]), err)

    check("QIF points only, by default: the known radius (the plan's 15 mm), said in feature.centre",
          code == 0 and all("(known radius 15 mm, the plan's; --free-radius frees it)" in s["feature"]["centre"]
                            for c in ev_qp["cycles"] for s in c["spheres"]), err)

    # Points on a 14.998 mm sphere (a 2 um pre-travel shrinks what the probe sees) about the point
    # route's centres: --free-radius returns those centres, so the same errors to 1e-9; the known
    # radius (default, as on the point route) stretches the points onto 15 mm and moves each centre
    # away from the cap, down by t = 2 um <cos th> / <cos^2 th> (least squares of 2 um - t cos th_k,
    # first order): 3 um for points spread evenly in cos th over the hemisphere (<cos> = 1/2,
    # <cos^2> = 1/3). The same shift in every cycle: every error within the combined U.
    q2 = write("points_pretravel.qif", qif_points(ev_p, 14.998))
    code, out, err = run("evaluate", q2, "--format", "qif", "--free-radius", "--manifest", PLAN, "--out", f"{W}/qifpts_free")
    ev_free = json.load(open(f"{W}/qifpts_free/evaluation.json")) if code == 0 else {"cycles": []}
    bfree = budgets(ev_free)
    check("QIF points on 14.998 mm, --free-radius: the point route's errors to 1e-9, feature.centre says free radius",
          code == 0 and sorted(bfree) == sorted(bp) and
          max(abs(bfree[c][j]["value"] - bp[c][j]["value"]) for c in bp for j in range(7)) <= 1e-9 and
          all("(free radius, --free-radius)" in s["feature"]["centre"] and abs(s["feature"]["diameter_mm"] - 29.996) < 1e-9
              for c in ev_free["cycles"] for s in c["spheres"]), err)
    code, out, err = run("evaluate", q2, "--format", "qif", "--manifest", PLAN, "--out", f"{W}/qifpts_known")
    ev_known = json.load(open(f"{W}/qifpts_known/evaluation.json")) if code == 0 else {"cycles": []}
    bknown = budgets(ev_known)
    dz = [s["centre_mm"][2] - p["centre_mm"][2] for c, cp in zip(ev_known["cycles"], ev_p["cycles"])
          for s, p in zip(c["spheres"], cp["spheres"])]
    print(f"     QIF points on 14.998 mm, known radius: centre z - point route's {min(dz) * 1e3:.3f} ... {max(dz) * 1e3:.3f} um")
    check("QIF points on 14.998 mm, known radius (default): each centre 3 um down (+-0.05 um), feature.centre says known radius",
          code == 0 and dz and all(abs(d + 3e-3) < 5e-5 for d in dz) and
          all("(known radius 15 mm" in s["feature"]["centre"] and s["feature"]["diameter_mm"] == 30
              for c in ev_known["cycles"] for s in c["spheres"]), err)
    for name, b in (("--free-radius", bfree), ("known radius", bknown)):
        # (The reference cycle's errors are 0 with U 0 on both routes.)
        ratio = max((abs(b[c][j]["value"] - bp[c][j]["value"]) / math.hypot(b[c][j]["U"], bp[c][j]["U"])
                     for c in bp for j in range(7) if c in b and math.hypot(b[c][j]["U"], bp[c][j]["U"]) > 0),
                    default=float("inf"))
        print(f"     QIF points on 14.998 mm, {name}: largest |features - points| / combined U {ratio:.4f}")
        check(f"QIF points on 14.998 mm, {name}: every error within the combined U", ratio <= 1, ratio)

    code, out, err = run("evaluate", same, "--format", "features", "--free-radius", "--manifest", PLAN, "--out", f"{W}/same_free")
    check("refused: --free-radius for centres a file states (no fit of ours), with the row's line",
          code == 1 and f"{same}:2: --free-radius: sphere 'S1' states its centre, which comes from no fit of ours" in err, err)

    code, out, err = run("evaluate", q, "--format", "dmis", "--manifest", PLAN, "--out", f"{W}/dmis")
    check("refused: --format dmis for a sphere artifact (a DMIS output is one run), naming what it takes",
          code == 1 and "features or qif (sphere centres a CMM reports)" in err, err)

    # --- the fallback when no u is stated: the specification through the planned points, 1/sqrt(n)
    def centre_term(ev):
        return [x["u"] for x in ev["cycles"][1]["spheres"][1]["centre_budgets"][2]["contributions"]
                if x["input"] == "sphere centre as the feature file states it"][0]
    quad = write("quad.csv", "\n".join(r if r == HEADER else r.rsplit(",", 1)[0] + "," + str(4 * int(r.rsplit(",", 1)[1]))
                                       for r in open(same).read().splitlines()) + "\n")
    code, out, err = evaluate_features(quad, "quad")
    u5, u20 = centre_term(ev_s), centre_term(json.load(open(f"{W}/quad/evaluation.json"))) if code == 0 else 0
    check("no stated u: the fallback term falls as 1/sqrt(n_points) (4x the points, half the u)",
          code == 0 and u5 > 0 and abs(u20 / u5 - 0.5) < 1e-12, (u5, u20, err))

    # --- 3. refusals and an incomplete cycle ---------------------------------------------------
    def refused(name, text, *needles):
        path = write(name, text)
        code, out, err = evaluate_features(path, name + ".out")
        check(f"refused: {name}", code == 1 and all(n in err for n in needles), f"exit {code}\n{out}{err}")

    body = "\n".join(same_rows := open(same).read().splitlines())
    refused("unknown_kind", body.replace(",S2,sphere,", ",S2,cone,", 1) + "\n", f"{W}/unknown_kind:3", "'cone' is not a feature kind")
    refused("missing_column", "\n".join(r.rsplit(",", 1)[0] for r in same_rows) + "\n",
            f"{W}/missing_column:1", "missing column 'n_points'")
    s1 = same_rows[1].split(",")
    refused("two_on_one_place", "\n".join([HEADER] + [",".join([s1[0], f"P{k}"] + s1[2:]) for k in (1, 2)]) + "\n",
            "two_on_one_place:2", "the rows at lines 2 ('P1') and 3 ('P2') both match S1 and S5")
    far = ",".join(s1[:3] + [str(float(s1[3]) + 20)] + s1[4:])
    refused("far", HEADER + "\n" + far.replace(",S1,", ",X,") + "\n", "mm from the nearest planned centre")
    refused("twice", "\n".join([HEADER, same_rows[1], same_rows[1]]) + "\n", "position 1 is given twice, by the rows at lines 2 ('S1') and 3 ('S1')")
    holed = write("holed.csv", "\n".join(r for r in same_rows if not r.startswith("3,S2,")) + "\n")
    code, out, err = evaluate_features(holed, "holed")
    ev_h = json.load(open(f"{W}/holed/evaluation.json")) if code == 0 else {}
    check("a position without a centre: its cycle listed as incomplete, the others evaluated",
          code == 0 and "Cycle 3 not evaluated: position 2 has no sphere centre in the feature file" in out and
          [c["cycle"] for c in ev_h["cycles"]] == [1, 2, 4] and ev_h["incomplete_cycles"][0]["cycle"] == 3, out + err)
    code, out, err = run("evaluate", same, "--manifest", PLAN, "--out", f"{W}/auto")
    check("--format auto recognises a feature-actuals CSV", code == 0 and out.startswith("Sphere centres from the feature file"), err)
finally:
    shutil.rmtree(W, ignore_errors=True)
check.finish()
