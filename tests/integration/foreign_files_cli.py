#!/usr/bin/env python3
"""Files from other producers through the real CLI (issue 34 items 1, 2 and 4), on the corpus
of tests/data/foreign (README.md there has each file's provenance):

- CheckMate's QIF 3.0 results (SolidWorks 2016): `probeloop read` reads 691 measured points in
  12 MeasuredPointSets (counted here from the file's text, independently of probeloop) and
  reports the two producer mistakes as warnings with their lines (the self-referencing
  WholePointSetId of POINT5, the missing PointList of POINT3; their lines found here by
  searching the text); every point is assigned to a feature;
- `--strict` refuses the file at the self-reference's line, with the message of the warning;
- `probeloop fit cylinder FILE --feature CYL_1` fits the 18 tip centres: its radius and axis
  agree with a least-squares cylinder computed here (Gauss-Newton in pure Python) within
  1e-6 mm / 1e-6; with the file's ProbeRadius compensated (a bore: --material outside) the
  diameter agrees with CheckMate's own measured 30.11094 mm within 1 um, and its axis with
  CheckMate's direction within 0.1 mrad; the warnings reach fit's output (text and --json).
- the DMSC's demoQIFout.py results (features only): read with its four features and their
  diameters (from the file's text), no points, no warning; `fit` refuses it for want of points.
- the CheckMate file as KBO Systems' QIF_Import writes it back: CheckMate's 691 points set by
  set, the same two warnings at its own lines, the 12 characteristic values it lost named in a
  note, and CYL_1's cylinder as from the original;
- the DMSC's Exploded_Results1.QIF (characteristics only, items in another document): no
  features, the two values of its text, no warning, the missing FileUnits in a note;
- Mitutoyo's QIF 2.0.0 results sample: refused at its root's line, naming the namespace;
- a DMIS output in a CMM package's manner, written here (no public one was found): its 16 bore
  points read, a re-taken point and the missing ENDFIL warned at their lines, --strict refusing
  the first, and `fit cylinder --feature CYL` against an independent least-squares cylinder.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR."""
import json, math, os, re, subprocess, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
CM = os.path.join(SRC, "tests", "data", "foreign", "qif", "QIF_PTS_SAMPLE.QIF")
check = Checks()


def run(*args):
    p = subprocess.run([PL, *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


text = open(CM, encoding="utf-8").read()
lines = text.split("\n")

# The file's point sets, from its text: ids, counts and the numbers between <Points> tags.
sets = re.findall(r'<MeasuredPointSet id="(\d+)" count="(\d+)">(.*?)</MeasuredPointSet>', text, re.S)
points_by_set = {}
for sid, count, body in sets:
    nums = [float(x) for x in re.sub(r"<!--.*?-->", "", re.search(r"<Points>(.*?)</Points>", body, re.S).group(1), flags=re.S).split()]
    points_by_set[sid] = [nums[i:i + 3] for i in range(0, len(nums), 3)]
n_points = sum(len(p) for p in points_by_set.values())
check(f"the file holds {len(sets)} point sets with {n_points} points (counted from its text)", len(sets) == 12 and n_points == 691,
      (len(sets), n_points))
self_ref = next(i + 1 for i, l in enumerate(lines) if "<WholePointSetId>828</WholePointSetId>" in l)
no_list = next(i + 1 for i, l in enumerate(lines) if '<PointFeatureMeasurement id="776">' in l)

# read: text and JSON.
rc, out, err = run("read", CM)
check("read: exit 0 (the strict reader refused the whole file)", rc == 0, err)
# Assigned: every set whole, but DATUMA's RangePointSetId takes points 3..8 of its 8.
rng = re.search(r'<RangePointSetId range="(\d+) (\d+)">', text)
assigned = n_points - len(points_by_set["12"]) + int(rng.group(2)) - int(rng.group(1)) + 1
check(f"read: '12 with 691 points, {assigned} of them assigned to features'",
      f"measured point sets: 12 with 691 points, {assigned} of them assigned to features" in out, out[-1500:])
w_self = f"{CM}:{self_ref}: warning: WholePointSetId: no MeasuredPointSet with id 828 in this MeasurementResults (it is the feature " \
         f"measurement's own id); assigned MeasuredPointSet 829"
check(f"read: the self-reference warned at line {self_ref} with what was done", w_self in out, out[-1500:])
check(f"read: the missing PointList warned at line {no_list}",
      f"{CM}:{no_list}: warning: PointFeatureMeasurement 776 has no PointList, but MeasuredPointSet 777" in out, out[-1500:])
rc, js, err = run("read", CM, "--json")
d = json.loads(js) if rc == 0 else {}
ws = d.get("warnings", [])
check("read --json: 2 warnings at the two lines", sorted(w["line"] for w in ws) == sorted([self_ref, no_list]), ws)
check("read --json: point_sets 12, points 691", d.get("point_sets") == {"count": 12, "points": 691}, d.get("point_sets"))
feats = {f["name"]: f for f in d.get("features", [])}
check(f"read --json: 14 features with {assigned} points",
      len(feats) == 14 and sum(len(f["points_mm"]) for f in feats.values()) == assigned, len(feats))
p5 = feats.get("POINT5", {}).get("points_mm", [])
check("read --json: POINT5 got set 829's point", len(p5) == 1 and all(abs(a - b) < 1e-12 for a, b in zip(p5[0], points_by_set["829"][0])), p5)

# --strict: refused at the first warned line (POINT3's, before POINT5's), with the warning's problem.
first = min(self_ref, no_list)
rc, out, err = run("read", CM, "--strict")
check(f"read --strict: refused at line {first}", rc != 0 and
      f"{CM}:{first}: PointFeatureMeasurement 776 has no PointList, but MeasuredPointSet 777" in err, (rc, err))
rc, out, err = run("fit", "cylinder", CM, "--feature", "CYL_1", "--strict")
check("fit --strict: refused the same way", rc != 0 and f"{CM}:{first}: PointFeatureMeasurement 776" in err, (rc, err))


# An independent least-squares cylinder: axis through (x0, y0, 0) along (a, b, 1)/|.|, radius r;
# Gauss-Newton on the radial residuals with a numerical Jacobian (5 x 5 normal equations).
def residuals(q, pts):
    x0, y0, a, b, r = q
    n = math.sqrt(a * a + b * b + 1)
    d = (a / n, b / n, 1 / n)
    out = []
    for x, y, z in pts:
        v = (x - x0, y - y0, z)
        t = v[0] * d[0] + v[1] * d[1] + v[2] * d[2]
        out.append(math.sqrt(sum((v[k] - t * d[k]) ** 2 for k in range(3))) - r)
    return out


def solve(A, y):
    n = len(y)
    M = [row[:] + [y[i]] for i, row in enumerate(A)]
    for c in range(n):
        p = max(range(c, n), key=lambda i: abs(M[i][c]))
        M[c], M[p] = M[p], M[c]
        for i in range(n):
            if i != c:
                f = M[i][c] / M[c][c]
                M[i] = [M[i][k] - f * M[c][k] for k in range(n + 1)]
    return [M[i][n] / M[i][i] for i in range(n)]


def ls_cylinder(pts):
    cx = sum(p[0] for p in pts) / len(pts)
    cy = sum(p[1] for p in pts) / len(pts)
    q = [cx, cy, 0.0, 0.0, sum(math.hypot(p[0] - cx, p[1] - cy) for p in pts) / len(pts)]
    for _ in range(50):
        r0 = residuals(q, pts)
        J = []
        for k in range(5):
            h = 1e-7
            qk = q[:]
            qk[k] += h
            J.append([(a - b) / h for a, b in zip(residuals(qk, pts), r0)])
        A = [[sum(J[i][m] * J[j][m] for m in range(len(pts))) for j in range(5)] for i in range(5)]
        g = [-sum(J[i][m] * r0[m] for m in range(len(pts))) for i in range(5)]
        step = solve(A, g)
        q = [a + b for a, b in zip(q, step)]
        if max(abs(s) for s in step) < 1e-13:
            break
    n = math.sqrt(q[2] ** 2 + q[3] ** 2 + 1)
    return q[4], (q[2] / n, q[3] / n, 1 / n), residuals(q, pts)


cyl = points_by_set["797"]
r_ls, d_ls, res = ls_cylinder(cyl)
print(f"independent LS cylinder on set 797 ({len(cyl)} tip centres): r = {r_ls:.6f} mm, axis = "
      f"({d_ls[0]:.7f}, {d_ls[1]:.7f}, {d_ls[2]:.7f}), max |residual| = {max(abs(x) for x in res) * 1000:.3f} um")


def param(j, name):
    return next((p["value"] for p in j.get("parameters", []) if p["name"] == name), None)


def axis_of(j):
    v = [param(j, k) for k in ("nx", "ny", "nz")]
    return None if None in v else v


def angle(u, v):
    c = abs(sum(a * b for a, b in zip(u, v))) / math.sqrt(sum(a * a for a in u) * sum(b * b for b in v))
    return math.acos(min(1.0, c))


rc, js, err = run("fit", "cylinder", CM, "--feature", "CYL_1", "--json")
check("fit cylinder --feature CYL_1 --json: exit 0", rc == 0, err)
j = json.loads(js) if rc == 0 else {}
el = j
r_fit = param(j, "r_mm")
ax = axis_of(el)
check("fit: the cylinder of CYL_1's 18 points", j.get("element") == "cylinder" and j.get("input", {}).get("points") == 18, j.get("input"))
print(f"fit cylinder CYL_1: r = {r_fit} mm, axis = {ax}, form = {j.get('form_um')} um")
check(f"fit: radius {r_fit} mm = independent LS {r_ls:.6f} mm within 1e-6 mm", r_fit is not None and abs(r_fit - r_ls) < 1e-6,
      (r_fit, r_ls))
check("fit: axis = independent LS axis within 1e-6 rad", ax is not None and angle(ax, d_ls) < 1e-6, (ax, d_ls))
check("fit --json: the two warnings in warnings[] and on stderr",
      sum(1 for w in j.get("warnings", []) if f"{CM}:{self_ref}:" in w or f"{CM}:{no_list}:" in w) == 2
      and f"{CM}:{self_ref}:" in err, (j.get("warnings"), err))

# With the probe radius the file states (2.49978271104 mm, uncompensated tip centres of a bore).
probe = float(re.search(r"<ProbeRadius>([0-9.]+)</ProbeRadius>", text).group(1))
dia_cm = float(re.search(r'<CylinderFeatureMeasurement id="796">.*?<Diameter>([0-9.]+)</Diameter>', text, re.S).group(1))
dir_cm = [float(x) for x in re.search(r'<CylinderFeatureMeasurement id="796">.*?<Direction>([^<]+)</Direction>', text, re.S).group(1).split()]
rc, js, err = run("fit", "cylinder", CM, "--feature", "CYL_1", "--tip-radius", repr(probe), "--material", "outside", "--json")
j = json.loads(js) if rc == 0 else {}
el = j
r_c = param(j, "r_mm")
print(f"fit cylinder CYL_1, tip compensated: d = {None if r_c is None else 2 * r_c} mm, form = {j.get('form_um')} um")
check(f"fit --tip-radius {probe} --material outside: diameter {None if r_c is None else 2 * r_c} mm = CheckMate's {dia_cm} mm within 1 um",
      r_c is not None and abs(2 * r_c - dia_cm) < 0.001, (r_c, dia_cm, err))
check("fit: axis = CheckMate's measured direction within 0.1 mrad", axis_of(el) is not None and angle(axis_of(el), dir_cm) < 1e-4,
      (axis_of(el), dir_cm))

rc, out, err = run("fit", "cylinder", CM, "--feature", "CYL_1")
check("fit (text): exit 0, the warnings with their lines in the report", rc == 0 and f"{CM}:{self_ref}:" in out and f"{CM}:{no_list}:" in out,
      out + err)
print(out)
rc, out, err = run("fit", "cylinder", CM)
check("fit without --feature: refused, naming the features with points", rc != 0 and "give --feature NAME" in err and "CYL_1" in err, err)
rc, out, err = run("fit", "cylinder", CM, "--feature", "NOPE")
check("fit --feature NOPE: refused, listing the names", rc != 0 and "no feature named 'NOPE'" in err and "CYL_1" in err, err)

# The DMSC's demoQIFout.py file: measured features only, no points.
PY = os.path.join(SRC, "tests", "data", "foreign", "qif", "testPython30.qif")
py = open(PY, encoding="utf-8").read()
meas = re.findall(r"<(\w+)FeatureMeasurement id=", py)
dias = [float(x) for x in re.findall(r"<Diameter>([0-9.]+)</Diameter>", py.split("<Results>")[1])]
rc, js, err = run("read", PY, "--json")
d = json.loads(js) if rc == 0 else {}
got = [(f["kind"], f.get("measured", {}).get("diameter_mm")) for f in d.get("features", [])]
check(f"testPython30: {len(meas)} measured features ({', '.join(meas)}; diameters {dias} from the text), no points, no warning",
      rc == 0 and [k for k, _ in got] == [m.lower() for m in meas] and [x for _, x in got if x is not None] == dias
      and all(not f["points_mm"] for f in d["features"]) and d["warnings"] == [] and "point_sets" not in d, (got, err))
rc, out, err = run("fit", "cylinder", PY, "--feature", "DAT_B")
check("testPython30: fit refuses a file without points", rc != 0 and f"no measured features with points in the file ({len(meas)} features)" in err, err)

# The same CheckMate file as KBO Systems' QIF_Import (a .NET QIF library) writes it back: another
# producer's serialization (attributes reordered, points tab-indented, E-notation), its mistakes
# kept, and 12 characteristic values lost (measurements with a status only).
KB = os.path.join(SRC, "tests", "data", "foreign", "qif", "kbo", "QIF_PTS_SAMPLE.conv.qif")
kb = open(KB, encoding="utf-8").read()
kb_lines = kb.split("\n")
kb_sets = {}
for m in re.finditer(r"<MeasuredPointSet ([^>]*)>(.*?)</MeasuredPointSet>", kb, re.S):
    sid = re.search(r'id="(\d+)"', m.group(1)).group(1)
    nums = [float(x) for x in re.search(r"<Points>(.*?)</Points>", m.group(2), re.S).group(1).split()]
    kb_sets[sid] = [nums[i:i + 3] for i in range(0, len(nums), 3)]
check("KBO: the 12 point sets hold CheckMate's 691 points, set by set, every digit (both texts parsed here)",
      kb_sets == points_by_set, sorted(kb_sets))
kb_self = next(i + 1 for i, l in enumerate(kb_lines) if "<WholePointSetId>828</WholePointSetId>" in l)
kb_nolist = next(i + 1 for i, l in enumerate(kb_lines) if '<PointFeatureMeasurement id="776">' in l)
no_value = [b for b in re.findall(r"<(\w+CharacteristicMeasurement) id=\"\d+\">(.*?)</\1>", kb, re.S) if "<Value>" not in b[1]]
rc, js, err = run("read", KB, "--json")
d = json.loads(js) if rc == 0 else {}
ws = sorted((w["line"], w["what"].split(";")[0]) for w in d.get("warnings", []))
check(f"KBO: read gives 14 features, 12 sets with 691 points ({assigned} assigned), the two mistakes warned at its own lines "
      f"{kb_nolist} and {kb_self}",
      rc == 0 and len(d["features"]) == 14 and d["point_sets"] == {"count": 12, "points": 691}
      and sum(len(f["points_mm"]) for f in d["features"]) == assigned
      and [x[0] for x in ws] == sorted([kb_self, kb_nolist]), (ws, err))
check(f"KBO: the {len(no_value)} characteristic measurements without a Value named in a note, the others read "
      f"({len(re.findall('<Value>', kb.split('<MeasuredCharacteristics>')[1]))})",
      rc == 0 and len(no_value) == 12 and any(n.startswith("12 characteristic measurements without a Value") for n in d["notes"])
      and len(d["characteristics"]) == len(re.findall("<Value>", kb.split("<MeasuredCharacteristics>")[1])), (d.get("notes"), err))
rc, _, err = run("read", KB, "--strict")
check(f"KBO --strict: refused at line {min(kb_self, kb_nolist)}", rc != 0 and f"{KB}:{min(kb_self, kb_nolist)}: " in err, err)
rc, js, err = run("fit", "cylinder", KB, "--feature", "CYL_1", "--json")
j = json.loads(js) if rc == 0 else {}
print(f"KBO fit cylinder CYL_1: r = {param(j, 'r_mm')} mm, form {j.get('form_um')} um")
check(f"KBO: fit cylinder --feature CYL_1 = the independent LS cylinder of CheckMate's points ({r_ls:.6f} mm) within 1e-6 mm",
      rc == 0 and abs(param(j, "r_mm") - r_ls) < 1e-6 and angle(axis_of(j), d_ls) < 1e-6, err)

# The DMSC's Exploded_Results1.QIF: characteristic measurements only, referring to their items in
# another document (xId), no features, no FileUnits.
EX = os.path.join(SRC, "tests", "data", "foreign", "qif", "Exploded_Results1.QIF")
ex = open(EX, encoding="utf-8").read()
vals = [(m.group(1), float(m.group(2))) for m in re.finditer(r"<(\w+CharacteristicMeasurement) id=\"\d+\">.*?<Value>([0-9.]+)</Value>", ex, re.S)]
rc, js, err = run("read", EX, "--json")
d = json.loads(js) if rc == 0 else {}
got = [(c["name"], c["value"]) for c in d.get("characteristics", [])]
print(f"Exploded_Results1: {got}")
check(f"Exploded_Results1: no features, the {len(vals)} characteristic values of the text ({vals}), no warning, "
      "the missing FileUnits in a note (mm)",
      rc == 0 and d["features"] == [] and len(got) == len(vals) == 2 and all(a == b and abs(x - y) < 1e-12 for (a, x), (b, y) in zip(got, vals))
      and d["warnings"] == [] and d["length_unit"] == "mm" and any("no FileUnits" in n for n in d["notes"]), (got, err))
rc2, js2, _ = run("read", EX, "--json", "--strict")
check("Exploded_Results1 --strict: the same (nothing was read leniently)", rc2 == 0 and js2 == js)

# Mitutoyo's QIF 2.0.0 results sample (the QIF community's legacy folder): another version of the
# standard changes the meaning of every element: refused at the line where its root's start tag
# ends (libxml2's line of the element), naming the namespace.
MI = os.path.join(SRC, "tests", "data", "foreign", "qif", "qif2", "mitutoyo_results_serialized_pass_fail_sample.QIF")
mi = open(MI, encoding="utf-8").read()
root_end = mi[: mi.index(">", mi.index("<QIFDocument"))].count("\n") + 1
rc, out, err = run("read", MI)
check(f"Mitutoyo QIF 2.0.0: refused at line {root_end}, naming the qif2 namespace and what is read",
      rc == 1 and f"{MI}:{root_end}: QIFDocument: namespace 'http://qifstandards.org/xsd/qif2'" in err and "reads QIF 3" in err, err)


# A DMIS output in the manner of a CMM package's (no public one was found, tests/data/foreign/README.md):
# lower case, blanks, a vendor statement, a continuation, a comment inside a continued statement,
# tolerances and OUTPUT, one point re-taken (reported twice) and no ENDFIL. A bore of 16 points.
def bore_points():
    pts = []
    for h, z in enumerate((-2.0, -6.0, -10.0, -14.0)):
        for a in range(4):
            t = math.radians(90 * a + 22.5 * h)
            r = 6.0 + 0.002 * ((h * 4 + a) % 5 - 2)  # a form of a few um
            pts.append([round(10 + r * math.cos(t) + 0.001 * z, 6), round(-5 + r * math.sin(t) - 0.0005 * z, 6), z])
    return pts


bore = bore_points()
lines_dmo = ["FILNAM/'BORE 12',05.2", "DMESWV/'some vendor 7.1'", "UNITS/MM,ANGDEC", "F(CYL)=FEAT/CYLNDR,INNER,CART,10,-5,0,0,0,1,12"]
for k, p in enumerate(bore, start=1):
    if k == 5:  # first taken elsewhere, then re-taken: the later report is the point
        lines_dmo.append(f"fa(cyl_p05) = feat/point, cart, {p[0] + 0.5}, {p[1]}, {p[2]}, 0, 0, 1")
        retaken = len(lines_dmo) + 1
    if k == 9:
        lines_dmo += [f"FA(CYL_P09)=FEAT/POINT,CART,{p[0]},$", "$$ a comment between the parts", f"{p[1]},{p[2]},0,0,1"]
    else:
        lines_dmo.append(f"fa(cyl_p{k:02d}) = feat/point, cart, {p[0]}, {p[1]}, {p[2]}, 0, 0, 1")
lines_dmo += ["FA(CYL)=FEAT/CYLNDR,INNER,CART,10,-5,0,0,0,1,12.004", "T(DIA)=TOL/DIAM,-0.05,0.05", "TA(DIA)=TOL/DIAM,12.004,INTOL",
              "OUTPUT/FA(CYL),TA(DIA)"]
first5 = next(i + 1 for i, l in enumerate(lines_dmo) if l.startswith("fa(cyl_p05)"))
DMO = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"probeloop-foreign-{os.getpid()}.dmo")
open(DMO, "w").write("\r\n".join(lines_dmo) + "\r\n")
rc, js, err = run("read", DMO, "--json")
d = json.loads(js) if rc == 0 else {}
ws = [(w["line"], w["what"]) for w in d.get("warnings", [])]
check(f"DMIS output: 1 feature CYL with the 16 points, warned: the re-taken point at line {retaken}, no ENDFIL at line {len(lines_dmo)}",
      rc == 0 and [f["name"] for f in d["features"]] == ["CYL"] and len(d["features"][0]["points_mm"]) == 16
      and ws == [(retaken, f"FA(CYL_P05) reported again (first at line {first5}); the later one read"),
                 (len(lines_dmo), "no ENDFIL after the last statement (the file may be cut short); what is there was read")], (ws, err))
check("DMIS output: the points as the text states them (the later P05, P09 joined across its comment)",
      rc == 0 and all(abs(a - b) < 1e-12 for p, q in zip(d["features"][0]["points_mm"], bore) for a, b in zip(p, q)))
rc, _, err = run("read", DMO, "--strict")
check(f"DMIS output --strict: refused at line {retaken}", rc != 0 and f"{DMO}:{retaken}: FA(CYL_P05) reported again" in err, err)
r_b, d_b, res_b = ls_cylinder(bore)
rc, js, err = run("fit", "cylinder", DMO, "--feature", "CYL", "--json")
j = json.loads(js) if rc == 0 else {}
print(f"DMIS bore: fit r = {param(j, 'r_mm')} mm, independent LS r = {r_b:.7f} mm, form {j.get('form_um')} um")
check(f"fit cylinder --feature CYL on the DMIS output: r = independent LS {r_b:.7f} mm within 1e-6 mm, axis within 1e-6 rad, "
      "the two warnings carried",
      rc == 0 and abs(param(j, "r_mm") - r_b) < 1e-6 and angle(axis_of(j), d_b) < 1e-6 and len(j.get("warnings", [])) >= 2, (j.get("parameters"), err))
rc, js2, err = run("fit", "cylinder", DMO, "--feature", "cyl", "--json")
check("fit --feature cyl: DMIS labels are case-insensitive (the same cylinder)",
      rc == 0 and param(json.loads(js2), "r_mm") == param(j, "r_mm"), err)
os.remove(DMO)
check.finish()
