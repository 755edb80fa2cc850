#!/usr/bin/env python3
"""QIF 3.0 and DMIS through the real CLI (issue 15 items 1-3):

- every QIF file probeloop writes validates with xmllint against the QIF 3.0.0 XSD of
  ../shared/refdata/qif3: the CMM plans of the thermal test piece and of the stepped workpiece,
  the sphere artifact's probing plan, and the simulated CMM's results;
- the round trip: plan -> cmm_plan.qif -> the simulated CMM reading it -> cmm_results.qif ->
  evaluate gives the same errors.csv as the CSV route (cmm_export.csv), every printed digit
  (thermal test piece; stepped workpiece W8 with its probe log); the evaluation's results.qif
  carries its errors with their u as characteristics and its measured features;
- other software's samples (refdata/qif3/samples) read with the counts and coordinates that
  `xmllint --xpath` gives for them, computed here, independently of probeloop;
- DMIS: the plans' cmm_plan.dmi (every PTMEAS of cmm_points.csv, lines within 80 characters)
  drives the simulated CMM, which checks every move against the part as cut and answers with
  cmm_results.dmo; evaluate on it gives the CSV route's errors.csv, every printed digit;
- the reader's warnings (issue 34 item 4): a vendor extension in the thermal test piece's QIF and
  a statement after ENDFIL in W8's DMIS output reach stdout, evaluation.json's input_warnings
  and report.md's section (none in the clean files'), the same errors.csv; --strict refuses them;
- a feature stated with its geometry but without points in a QIF of points (issue 34): Z3 warned
  with its line in every output (kept under --strict), its cycle's values not evaluated and the
  others unchanged; the datum CYL without points refused naming it, its line and why;
- bad input: a QIF file of another version, a point set whose count does not match its points,
  a DMIS output with a feature we did not plan, and a DMIS program whose move goes through the
  part are refused naming the file, the line and the field, and nothing is written.

Needs $PROBELOOP, $PROBELOOP_SOURCE_DIR and xmllint (libxml2-utils)."""
import json, os, re, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
QIF = os.path.join(SRC, "..", "shared", "refdata", "qif3")
XSD = os.path.join(QIF, "QIFApplications", "QIFDocument.xsd")
W = tempfile.mkdtemp(prefix="probeloop-qif-")
check = Checks()


def run(*args, cwd=None):
    p = subprocess.run([PL, *args], capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stdout, p.stderr


def valid(path):
    p = subprocess.run(["xmllint", "--noout", "--nonet", "--schema", XSD, path], capture_output=True, text=True)
    return p.returncode == 0, p.stderr[-600:]


def xpath(path, expr):
    p = subprocess.run(["xmllint", "--xpath", expr, path], capture_output=True, text=True)
    return p.stdout.strip()


def L(name):
    return f"*[local-name()='{name}']"


def numbers(errors_csv):
    return [l for l in open(errors_csv) if not l.startswith("#")]


if not os.path.exists(XSD):
    check(f"the QIF 3.0 schemas are at {XSD}", False)
    check.finish()

# --- the thermal test piece: plan, CMM from the QIF plan, both routes ---------------------------
T = f"{W}/ttp"
code, out, err = run("plan", f"{SRC}/parts/thermal_test_piece.yaml", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--out", f"{T}/plan")
check("plan the thermal test piece", code == 0 and "cmm_plan.qif" in out, err)
ok, e = valid(f"{T}/plan/cmm_plan.qif")
check("the thermal test piece's cmm_plan.qif validates against the QIF 3.0 XSD", ok, e)
csv_points = sum(1 for l in open(f"{T}/plan/cmm_points.csv") if l[:1].isalpha() and not l.startswith("feature,"))
n_qif = xpath(f"{T}/plan/cmm_plan.qif", f"count(//{L('NominalPointSet')}/{L('MeasurePoint')})")
check(f"cmm_plan.qif holds the {csv_points} points of cmm_points.csv (xmllint: {n_qif})", n_qif == str(csv_points))
wait = os.environ.get("TTP_WAIT")
piece = f"{SRC}/parts/thermal_test_piece.yaml"
if wait:  # under the sanitizers: shorter waits (the same programs and checks)
    text = open(piece).read()
    piece = f"{W}/ttp.yaml"
    short = text.replace("  wait: 1 h ", f"  wait: {wait} ")  # as ttp_cli.py does
    check(f"the thermal test piece with {wait} waits (TTP_WAIT)", short != text)
    open(piece, "w").write(short)
    run("plan", piece, "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--out", f"{T}/plan")
code, out, err = run("simulate", "pre_machining.nc", "thermal_test.nc", "inspection.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml",
                     "--part", piece, "--truth", f"{SRC}/examples/truth_thermal_test.yaml", "--cmm-points", "cmm_plan.qif",
                     "--out", f"{T}/run", cwd=f"{T}/plan")
check("simulate with the CMM reading cmm_plan.qif: cmm_export.csv and cmm_results.qif", code == 0 and "cmm_results.qif" in out, err)
if code == 0:
    ok, e = valid(f"{T}/run/cmm_results.qif")
    check("the simulated CMM's cmm_results.qif validates against the QIF 3.0 XSD", ok, e)
    pts = xpath(f"{T}/run/cmm_results.qif", f"sum(//{L('MeasuredPointSet')}/@count)")
    check(f"cmm_results.qif holds every measured point ({pts})", pts == str(csv_points))
    c1, _, e1 = run("evaluate", f"{T}/run/cmm_export.csv", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-csv")
    c2, out2, e2 = run("evaluate", f"{T}/run/cmm_results.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-qif")
    check("evaluate the CSV export and the QIF results", c1 == 0 and c2 == 0 and "assigned by labels" in out2, e1 + e2)
    if c1 == 0 and c2 == 0:
        a, b = numbers(f"{T}/ev-csv/errors.csv"), numbers(f"{T}/ev-qif/errors.csv")
        check(f"the QIF route gives the CSV route's errors.csv, every printed digit ({len(a) - 1} cycles)", a == b and len(a) > 2,
              next((f"{x.strip()} | {y.strip()}" for x, y in zip(a, b) if x != y), "row count"))
        # A vendor's extension in the results (issue 34): read with a warning at its line, the same
        # errors.csv; refused under --strict.
        qif = open(f"{T}/run/cmm_results.qif").read()
        at = qif.index("</MeasurementResults>")
        ext_line = qif[:at].count("\n") + 1
        open(f"{W}/vendor.qif", "w").write(qif[:at] + '<v:Probe xmlns:v="urn:vendor">T1</v:Probe>' + qif[at:])
        c4, out4, e4 = run("evaluate", f"{W}/vendor.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-vendor")
        check(f"evaluate: a vendor extension is warned at line {ext_line} in stdout, the same errors.csv",
              c4 == 0 and any(l.startswith(f"warning: {W}/vendor.qif:{ext_line}: MeasurementResults: unknown extension Probe")
                              for l in out4.split("\n"))
              and numbers(f"{T}/ev-vendor/errors.csv") == a, out4[-600:] + e4)
        # ... and in every output that used the file (issue 34 item 4); the clean file's have none.
        if c4 == 0:
            ev4, ev2 = json.load(open(f"{T}/ev-vendor/evaluation.json")), json.load(open(f"{T}/ev-qif/evaluation.json"))
            iw = ev4.pop("input_warnings", [])
            check("evaluation.json: input_warnings [{file, line, what}] with the extension's line; nothing else changed "
                  "(the file's name aside); none in the clean file's",
                  [(w["file"], w["line"]) for w in iw] == [(f"{W}/vendor.qif", ext_line)]
                  and iw[0]["what"].startswith("MeasurementResults: unknown extension Probe") and "input_warnings" not in ev2
                  and json.dumps(ev4).replace(f"{W}/vendor.qif", f"{T}/run/cmm_results.qif") == json.dumps(ev2), iw)
            r4, r2 = open(f"{T}/ev-vendor/report.md").read(), open(f"{T}/ev-qif/report.md").read()
            check("report.md: the 'Input warnings' section with the file and line; none in the clean file's",
                  f"## Input warnings" in r4 and f"- `{W}/vendor.qif` line {ext_line}: MeasurementResults: unknown extension Probe" in r4
                  and "Input warnings" not in r2, r4[-400:])
        c5, _, e5 = run("evaluate", f"{W}/vendor.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-strict", "--strict")
        check("evaluate --strict: refused at that line, nothing written", c5 != 0 and f"vendor.qif:{ext_line}: MeasurementResults: unknown "
              "extension Probe" in e5 and not os.path.exists(f"{T}/ev-strict/errors.csv"), e5)
        # A feature stated with its geometry but without points, in a file of points (issue 34): the
        # point route fits its own features, so it is not used, said as a warning with its line
        # (kept under --strict: the file's meaning is whole); a datum without points is refused,
        # naming it, its line and why.
        def without_points(text, name):
            """The QIF with feature `name`'s point set removed; the line of its FeatureMeasurement."""
            item = re.search(r'<\w+FeatureItem id="(\d+)">\s*(?:<FeatureNominalId>\d+</FeatureNominalId>\s*)?'
                             rf'<FeatureName>{name}</FeatureName>', text).group(1)
            m = re.search(r'(<\w+FeatureMeasurement id="\d+">\s*<FeatureItemId>' + item + r'</FeatureItemId>)'
                          r'\s*<PointList n="1">\s*<WholePointSetId>(\d+)</WholePointSetId>\s*</PointList>', text)
            text = text[:m.start()] + m.group(1) + text[m.end():]
            text = re.sub(rf'\s*<MeasuredPointSet id="{m.group(2)}".*?</MeasuredPointSet>', "", text, flags=re.S)
            n = text.count("<MeasuredPointSet id=")
            return re.sub(r'<MeasuredPointSets n="\d+">', f'<MeasuredPointSets n="{n}">', text), text[:m.start()].count("\n") + 1
        because = ("the point route fits its own features from the points (a file of features only is evaluated from them, "
                   "docs/formats.md#evaluating-from-features)")
        z3, z3_line = without_points(qif, "Z3")
        open(f"{W}/no_z3.qif", "w").write(z3)
        c8, out8, e8 = run("evaluate", f"{W}/no_z3.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-no-z3", "--strict")
        what = f"feature Z3 states its measured geometry but no points, while 48 features of the file carry points: not used; {because}"
        ev8 = json.load(open(f"{T}/ev-no-z3/evaluation.json")) if c8 == 0 else {}
        r8 = open(f"{T}/ev-no-z3/report.md").read() if c8 == 0 else ""
        check(f"Z3 stated without points: warned at its line {z3_line} in stdout, evaluation.json and report.md, kept under "
              "--strict", c8 == 0 and f"warning: {W}/no_z3.qif:{z3_line}: {what}\n" in out8
              and ev8.get("input_warnings") == [{"file": f"{W}/no_z3.qif", "line": z3_line, "what": what}]
              and f"- `{W}/no_z3.qif` line {z3_line}: {what}\n" in r8 and "`--strict` does not refuse it" in r8, out8[-600:] + e8)
        # (Their U moves a little: the pooled type A scatter has Z3's points fewer.)
        b8 = [l.split(",")[:7] for l in numbers(f"{T}/ev-no-z3/errors.csv")] if c8 == 0 else []
        check("Z3 stated without points: its cycle's EZ, EB not evaluated (said), the other cycles' errors the point route's, "
              "every printed digit", "Cycle 3: EZ_um, EB_urad not evaluated: Z3 (cycle 3) has no points" in out8
              and b8 == [l.split(",")[:7] for l in a if l.split(",")[1] != "3"], b8[:3])
        cyl, cyl_line = without_points(qif, "CYL")
        open(f"{W}/no_cyl.qif", "w").write(cyl)
        c9, _, e9 = run("evaluate", f"{W}/no_cyl.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-no-cyl")
        check(f"the datum CYL stated without points: refused at its line {cyl_line}, naming it and why, nothing written",
              c9 != 0 and f"no_cyl.qif:{cyl_line}: feature CYL states its measured geometry but no points, while 48 features of the "
              f"file carry points: the datum CYL needs its points (seed 004 L2055: the part frame), and {because}: export CYL's "
              "points, or no feature's" in e9 and not os.path.exists(f"{T}/ev-no-cyl/errors.csv"), e9)
        # The evaluation's own results.qif: valid, and its characteristics are errors.csv's values.
        ok, e = valid(f"{T}/ev-qif/results.qif")
        check("the evaluation's results.qif validates against the QIF 3.0 XSD", ok, e)
        code, out, err = run("read", f"{T}/ev-qif/results.qif", "--json")
        r = json.loads(out) if code == 0 else {"characteristics": [], "features": []}
        chars = {c["name"]: c for c in r["characteristics"]}
        import csv as _csv  # noqa: E402
        rows = list(_csv.DictReader(l for l in open(f"{T}/ev-qif/errors.csv") if not l.startswith("#")))
        worst, n = 0.0, 0
        for row in rows:
            for col in ("EX_um", "EY_um", "EZ_um", "ETTP_um", "EB_urad"):
                c = chars.get(f"{col.rsplit('_', 1)[0]} cycle {row['cycle']}")
                if c is None:
                    worst = float("inf")
                    continue
                scale = 1e-6 if col.endswith("_urad") else 1e-3
                worst = max(worst, abs(c["value"] - float(row[col]) * scale) / scale,
                            abs(c["u"] - float(row["U_" + col]) / 2 * scale) / scale)
                n += 1
        check(f"results.qif carries E_X ... E_TTP of every cycle with u = U/2 ({n} values, worst difference {worst:.2g} um|urad)",
              n == 5 * len(rows) and worst < 1e-6)
        check(f"results.qif carries the {len(r['features'])} measured features with their points and fitted geometry",
              len(r["features"]) == 49 and sum(len(f["points_mm"]) for f in r["features"]) == csv_points
              and all("measured" in f for f in r["features"]), err)
    # DMIS: the program drives the simulated CMM; its output evaluates like the CSV.
    dmi = open(f"{T}/plan/cmm_plan.dmi").read()
    lines = dmi.splitlines()
    ptmeas = sum(1 for l in lines if l.startswith("PTMEAS/"))
    check(f"cmm_plan.dmi: a PTMEAS per planned point ({ptmeas}), every line within 80 characters, DMISMN ... ENDFIL",
          ptmeas == csv_points and max(len(l) for l in lines) <= 80 and lines[0].startswith("DMISMN/") and lines[-1] == "ENDFIL")
    code, out, err = run("simulate", "pre_machining.nc", "thermal_test.nc", "inspection.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml",
                         "--part", piece, "--truth", f"{SRC}/examples/truth_thermal_test.yaml", "--cmm-points", "cmm_plan.dmi",
                         "--out", f"{T}/run-dmis", cwd=f"{T}/plan")
    check("simulate with the CMM running cmm_plan.dmi (its moves checked against the part): cmm_results.dmo",
          code == 0 and "cmm_results.dmo" in out, err)
    if code == 0:
        c3, out3, e3 = run("evaluate", f"{T}/run-dmis/cmm_results.dmo", "--manifest", f"{T}/plan/plan.json", "--out", f"{T}/ev-dmis")
        check("evaluate the DMIS output", c3 == 0 and "assigned by labels" in out3, e3)
        # fit on an exchange file (issue 34): feature TOP's 12 points from the DMIS output, from the
        # QIF results of the same run and from cmm_export.csv's TOP rows give one plane.
        fits = []
        for f in (f"{T}/run-dmis/cmm_results.dmo", f"{T}/run-dmis/cmm_results.qif", f"{T}/run-dmis/cmm_export.csv"):
            cf, of, ef = run("fit", "plane", f, "--feature", "TOP", "--json")
            fits.append({q["name"]: q["value"] for q in json.loads(of)["parameters"]} if cf == 0 else ef)
        check("fit plane --feature TOP: the DMIS output, the QIF results and the CSV export give one plane (1e-4 mm)",
              all(isinstance(x, dict) for x in fits) and all(abs(fits[i][k] - fits[2][k]) < 1e-4 for i in (0, 1) for k in fits[2]), fits)
        if c3 == 0 and c1 == 0:
            a, b = numbers(f"{T}/ev-csv/errors.csv"), numbers(f"{T}/ev-dmis/errors.csv")
            check(f"the DMIS route gives the CSV route's errors.csv, every printed digit ({len(a) - 1} cycles)", a == b and len(a) > 2,
                  next((f"{x.strip()} | {y.strip()}" for x, y in zip(a, b) if x != y), "row count"))
        # A feature we did not plan, reported beside ours.
        dmo = open(f"{T}/run-dmis/cmm_results.dmo").read().replace("ENDFIL", "FA(EXTRA_P01)=FEAT/POINT,CART,1,2,3,0,0,1\nFA(EXTRA)=FEAT/PLANE,CART,1,2,3,0,0,1\nENDFIL")
        open(f"{W}/extra.dmo", "w").write(dmo)
        line = dmo[: dmo.index("FA(EXTRA_P01)")].count("\n") + 1
        code, _, err = run("evaluate", f"{W}/extra.dmo", "--manifest", f"{T}/plan/plan.json", "--out", f"{W}/bad-extra")
        check(f"a DMIS output with a feature we did not plan is refused at its line {line}, naming it",
              code != 0 and f"extra.dmo:{line}: feature 'EXTRA' is not a feature of the manifest" in err and not os.path.exists(f"{W}/bad-extra"), err)
    # A program whose move goes through the part: the CMM refuses it before measuring.
    # (straight down from the first clearance position, above a TOP point, to 5 mm below the top)
    first_clear = next(i for i, l in enumerate(lines) if l.startswith("GOTO/"))
    x, y, _ = lines[first_clear][5:].split(",")
    crash = lines[: first_clear + 1] + [f"GOTO/{x},{y},-5"] + lines[first_clear + 1:]
    open(f"{T}/plan/crash.dmi", "w").write("\n".join(crash) + "\n")
    # (the pre-machining alone cuts the top: the check runs before any point is measured)
    code, _, err = run("simulate", "pre_machining.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml",
                       "--part", piece, "--truth", f"{SRC}/examples/truth_thermal_test.yaml", "--cmm-points", "crash.dmi",
                       "--out", f"{W}/bad-crash", cwd=f"{T}/plan")
    check(f"a DMIS program that moves through the part is refused at its line {first_clear + 2}, nothing written",
          code != 0 and f"crash.dmi:{first_clear + 2}: GOTO to " in err and "the move enters the part at" in err and not os.path.exists(f"{W}/bad-crash"), err)
    # A program drives the CMM: read strictly by simulate (what read would warn about is refused),
    # leniently by read.
    open(f"{T}/plan/late.dmi", "w").write(dmi + "GOTO/0,0,-50\n")
    code, _, err = run("simulate", "pre_machining.nc", "--machine", f"{SRC}/parts/machines/nmv5000.yaml",
                       "--part", piece, "--truth", f"{SRC}/examples/truth_thermal_test.yaml", "--cmm-points", "late.dmi",
                       "--out", f"{W}/bad-late", cwd=f"{T}/plan")
    check(f"simulate: a program with a move after ENDFIL is refused at its line {len(lines) + 1}, nothing written",
          code != 0 and f"late.dmi:{len(lines) + 1}: statements after ENDFIL" in err and not os.path.exists(f"{W}/bad-late"), err)
    code, out, err = run("read", f"{T}/plan/late.dmi", "--json")
    check("read: the same program read, with the warning at that line",
          code == 0 and [(w["line"], w["what"]) for w in json.loads(out)["warnings"]] == [(len(lines) + 1, "statements after ENDFIL; passed over")],
          out[-300:] + err)
    code, out, err = run("read", f"{T}/run/cmm_results.qif", "--json")
    d = json.loads(out) if code == 0 else {}
    cyl = [f for f in d.get("features", []) if f["name"] == "CYL"]
    check("probeloop read: the datum band CYL as a measured cylinder with its least-squares diameter",
          len(cyl) == 1 and cyl[0]["kind"] == "cylinder" and abs(cyl[0]["measured"]["diameter_mm"] - cyl[0]["nominal"]["diameter_mm"]) < 0.05,
          err or cyl)

    # Bad input: another version; a point set whose count is not its points'.
    text = open(f"{T}/run/cmm_results.qif").read()
    open(f"{W}/v2.qif", "w").write(text.replace('versionQIF="3.0.0"', 'versionQIF="2.1.0"'))
    code, _, err = run("evaluate", f"{W}/v2.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{W}/bad-v2")
    check("a QIF file of another version is refused naming file, line and field, nothing written",
          code != 0 and "v2.qif:2: versionQIF: '2.1.0'" in err and not os.path.exists(f"{W}/bad-v2"), err)
    m = re.search(r'<MeasuredPointSet id="(\d+)" count="(\d+)"', text)
    bad = text.replace(m.group(0), f'<MeasuredPointSet id="{m.group(1)}" count="{int(m.group(2)) + 1}"', 1)
    open(f"{W}/count.qif", "w").write(bad)
    line = bad[: bad.index("<Points>", bad.index(m.group(1) + '" count'))].count("\n") + 1
    code, _, err = run("evaluate", f"{W}/count.qif", "--manifest", f"{T}/plan/plan.json", "--out", f"{W}/bad-count")
    check(f"a point set whose count is not its points' is refused at line {line}",
          code != 0 and f"count.qif:{line}: Points: " in err and not os.path.exists(f"{W}/bad-count"), err)

# --- the stepped workpiece W8: the CMM's QIF results with the probe log ---------------------------
S = f"{W}/w8"
code, out, err = run("plan", f"{SRC}/parts/stepped_workpiece.yaml", "--machine", f"{SRC}/parts/machines/vmc3.yaml", "--out", f"{S}/plan",
                     "--experiment", "W8")
check("plan W8", code == 0, err)
ok, e = valid(f"{S}/plan/cmm_plan.qif")
check("W8's cmm_plan.qif validates against the QIF 3.0 XSD", ok, e)
code, out, err = run("simulate", "roughing.ngc", "finishing.ngc", "probing.ngc", "--machine", f"{SRC}/parts/machines/vmc3.yaml",
                     "--part", f"{SRC}/parts/stepped_workpiece.yaml", "--truth", f"{SRC}/examples/stepped_workpiece/truth.yaml",
                     "--cmm-points", "cmm_plan.qif", "--schedule", "plan.json", "--out", f"{S}/run", cwd=f"{S}/plan")
check("simulate W8 with the CMM reading cmm_plan.qif", code == 0 and "cmm_results.qif" in out, err)
if code == 0:
    ok, e = valid(f"{S}/run/cmm_results.qif")
    check("W8's cmm_results.qif validates against the QIF 3.0 XSD", ok, e)
    args = ["--probe-log", f"{S}/run/sw_probe.log", "--manifest", f"{S}/plan/plan.json"]
    c1, _, e1 = run("evaluate", f"{S}/run/cmm_export.csv", *args, "--out", f"{S}/ev-csv")
    c2, _, e2 = run("evaluate", f"{S}/run/cmm_results.qif", *args, "--out", f"{S}/ev-qif")
    check("evaluate W8 from the CSV export and from the QIF results", c1 == 0 and c2 == 0, e1 + e2)
    if c1 == 0 and c2 == 0:
        a, b = numbers(f"{S}/ev-csv/errors.csv"), numbers(f"{S}/ev-qif/errors.csv")
        check(f"W8: the QIF route gives the CSV route's errors.csv, every printed digit ({len(a) - 1} steps)", a == b and len(a) == 5)
        code, out, err = run("simulate", "roughing.ngc", "finishing.ngc", "probing.ngc", "--machine", f"{SRC}/parts/machines/vmc3.yaml",
                             "--part", f"{SRC}/parts/stepped_workpiece.yaml", "--truth", f"{SRC}/examples/stepped_workpiece/truth.yaml",
                             "--cmm-points", "cmm_plan.dmi", "--schedule", "plan.json", "--out", f"{S}/run-dmis", cwd=f"{S}/plan")
        c3, _, e3 = run("evaluate", f"{S}/run-dmis/cmm_results.dmo", *args, "--out", f"{S}/ev-dmis") if code == 0 else (1, "", err)
        check("W8: the CMM runs cmm_plan.dmi (moves checked) and its DMIS output gives the CSV route's errors.csv",
              c3 == 0 and numbers(f"{S}/ev-dmis/errors.csv") == a, e3)
        if c3 == 0:
            # A statement after ENDFIL (issue 34): passed over with a warning in stdout, evaluation.json
            # and report.md; the same errors.csv; --strict refuses it.
            dmo = open(f"{S}/run-dmis/cmm_results.dmo").read()
            late = dmo.count("\n") + 1
            open(f"{W}/late.dmo", "w").write(dmo + "DISPLY/OFF\n")
            c6, out6, e6 = run("evaluate", f"{W}/late.dmo", *args, "--out", f"{S}/ev-late")
            ev6 = json.load(open(f"{S}/ev-late/evaluation.json")) if c6 == 0 else {}
            r6 = open(f"{S}/ev-late/report.md").read() if c6 == 0 else ""
            what = "statements after ENDFIL; passed over"
            check(f"W8: a statement after ENDFIL warned at line {late} in stdout, evaluation.json and report.md; the same errors.csv",
                  c6 == 0 and f"warning: {W}/late.dmo:{late}: {what}" in out6 and numbers(f"{S}/ev-late/errors.csv") == a
                  and ev6.get("input_warnings") == [{"file": f"{W}/late.dmo", "line": late, "what": what}]
                  and f"- `{W}/late.dmo` line {late}: {what}" in r6
                  and "input_warnings" not in json.load(open(f"{S}/ev-dmis/evaluation.json"))
                  and "Input warnings" not in open(f"{S}/ev-dmis/report.md").read(), (out6[-300:], e6, ev6.get("input_warnings")))
            c7, _, e7 = run("evaluate", f"{W}/late.dmo", *args, "--out", f"{S}/ev-late-strict", "--strict")
            check("W8 --strict: refused at that line, nothing written",
                  c7 != 0 and f"late.dmo:{late}: statements after ENDFIL" in e7 and not os.path.exists(f"{S}/ev-late-strict/errors.csv"), e7)
        ok, e = valid(f"{S}/ev-qif/results.qif")
        check("W8's results.qif (e_pos, e_proc, e_splz per step with u) validates against the QIF 3.0 XSD", ok, e)
        code, out, err = run("read", f"{S}/ev-qif/results.qif", "--json")
        names = {c["name"] for c in json.loads(out)["characteristics"]} if code == 0 else set()
        check("W8's results.qif names e_pos_x, e_proc_y and e_splz of each step",
              all(f"{q} step {k}" in names for q in ("e_pos_x", "e_proc_y", "e_splz") for k in range(1, 5)), sorted(names)[:12])

# A plan from other software with features the simulated CMM does not measure: refused at once,
# naming the feature, before hours of machining are simulated.
widget = os.path.join(QIF, "samples", "WIDGET_QIF_RESULTS_W_QPIDS.QIF")
code, _, err = run("simulate", "roughing.ngc", "finishing.ngc", "probing.ngc", "--machine", f"{SRC}/parts/machines/vmc3.yaml",
                   "--part", f"{SRC}/parts/stepped_workpiece.yaml", "--truth", f"{SRC}/examples/stepped_workpiece/truth.yaml",
                   "--cmm-points", widget, "--schedule", "plan.json", "--out", f"{W}/bad-widget", cwd=f"{S}/plan")
check("a QIF plan with a circle is refused before the simulation, naming it; nothing written",
      code != 0 and ": a Circle; the simulated CMM measures planes, spheres and cylinders" in err and not os.path.exists(f"{W}/bad-widget"), err)

# --- the sphere artifact's probing plan ----------------------------------------------------------
code, out, err = run("plan", f"{SRC}/parts/sphere_artifact.yaml", "--machine", f"{SRC}/parts/machines/nmv5000.yaml", "--out", f"{W}/sa")
ok, e = valid(f"{W}/sa/probe_plan.qif")
check("the sphere artifact's probe_plan.qif validates against the QIF 3.0 XSD", code == 0 and ok, err + e)
if code == 0:
    plan = json.load(open(f"{W}/sa/plan.json"))
    code, out, err = run("read", f"{W}/sa/probe_plan.qif", "--json")
    d = json.loads(out) if code == 0 else {"features": []}
    worst = 0.0
    for f in d["features"]:
        c = f["nominal"]["location_mm"]
        rad = f["nominal"]["diameter_mm"] / 2
        for p in f["points_mm"]:
            worst = max(worst, abs(sum((p[i] - c[i]) ** 2 for i in range(3)) ** 0.5 - rad))
    check(f"every planned point of probe_plan.qif lies on its sphere's surface (worst {worst * 1e3:.4f} um; {len(d['features'])} spheres)",
          len(d["features"]) == len(plan["features"]) and worst < 1e-5, err)

    # The sphere campaign's evaluation: its results.qif (the errors of every cycle, no features).
    code, _, err = run("synth", f"{W}/sa/plan.json", "--truth", f"{SRC}/examples/truth_rigid.yaml", "--out", f"{W}/sa-run", "--seed", "1")
    code2, _, err2 = run("evaluate", f"{W}/sa-run/points.csv", "--manifest", f"{W}/sa/plan.json", "--out", f"{W}/sa-ev")
    ok, e = valid(f"{W}/sa-ev/results.qif") if code == 0 and code2 == 0 else (False, err + err2)
    check("the sphere campaign's results.qif validates against the QIF 3.0 XSD", ok, e)
    n_char = xpath(f"{W}/sa-ev/results.qif", f"count(//{L('CharacteristicMeasurements')}/*)")
    rows = [l for l in open(f"{W}/sa-ev/errors.csv") if l[:1].isdigit()] if ok else []
    check(f"... with the 7 errors of each of its {len(rows)} cycles ({n_char} characteristics)", ok and n_char == str(7 * len(rows)))

# --- other software's samples: counts and coordinates as xmllint --xpath gives them ---------------
S3 = os.path.join(QIF, "samples")
MF = f"//{L('MeasuredFeatures')}/*"
for name in sorted(os.listdir(S3)):
    path = os.path.join(S3, name)
    code, out, err = run("read", path, "--json")
    if code != 0:
        check(f"{name}: probeloop read", False, err)
        continue
    d = json.loads(out)
    if int(float(xpath(path, f"count(//{L('Results')})") or 0)):
        want = int(xpath(path, f"count({MF})"))
        kinds = {}
        for k in ("Plane", "Cylinder", "Circle", "Point", "EdgePoint", "Sphere"):
            kinds[k] = int(xpath(path, f"count({MF}[local-name()='{k}FeatureMeasurement'])"))
        got = {k: sum(1 for f in d["features"] if f["kind"] == k.lower()) for k in ("Plane", "Cylinder", "Circle", "Sphere")}
        got_points = sum(1 for f in d["features"] if f["kind"] == "point")
        pts_want = int(float(xpath(path, f"sum(//{L('MeasuredPointSet')}/@count)") or 0))
        pts_got = sum(len(f["points_mm"]) for f in d["features"])
        check(f"{name}: {len(d['features'])} measured features ({want} by xmllint), by kind {got} + {got_points} points "
              f"(xmllint {kinds}), {pts_got} measured points ({pts_want})",
              len(d["features"]) == want and all(got[k] == kinds[k] for k in got) and got_points == kinds["Point"] + kinds["EdgePoint"]
              and pts_got == pts_want)
        if want:
            first = xpath(path, f"string(({MF})[1]/{L('Location')})")
            item = xpath(path, f"string(({MF})[1]/{L('FeatureItemId')})")
            fname = xpath(path, f"string(//{L('FeatureItems')}/*[@id='{item}']/{L('FeatureName')})")
            loc = d["features"][0].get("measured", {}).get("location_mm")
            check(f"{name}: the first feature is {fname} at {first} (xmllint)",
                  d["features"][0]["name"] == fname and loc is not None
                  and all(abs(a - float(b)) < 1e-9 for a, b in zip(loc, first.split())), d["features"][0])
        if not int(float(xpath(path, f"count(/*/{L('FileUnits')})"))):
            check(f"{name}: no FileUnits: read in mm with a note", "no FileUnits: lengths read in mm" in d["notes"], d["notes"])
    else:
        nominals = int(xpath(path, f"count(//{L('FeatureNominals')}/*)"))
        check(f"{name}: no Results; read as a plan: {len(d['features'])} feature nominals ({nominals} by xmllint)",
              len(d["features"]) == nominals)
        cad = xpath(path, f"count(/*/{L('Product')}/{L('GeometrySet')}/{L('PointSet')}/{L('Point')})")
        if cad != "0":
            check(f"{name}: its {cad} PointSet points (xmllint) are named as CAD geometry, not measurements",
                  any(f"PointSet of {cad} CAD points" in n for n in d["notes"]), d["notes"])
check.finish()
