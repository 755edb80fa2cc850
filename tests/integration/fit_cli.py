#!/usr/bin/env python3
"""Integration tests of `probeloop fit` through the real CLI.

Every reference value is built here, independently of the C++ code: points are generated on
elements whose parameters are known, so the expected fit is known by construction. Needs
$PROBELOOP (the binary) and $PROBELOOP_SOURCE_DIR; plain python3, no numpy.
"""
import json, math, os, random, struct, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-fit-")
check = Checks()


def run(*args):
    p = subprocess.run([PL, "fit", *args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr




def fit_json(*args):
    rc, out, err = run(*args, "--json")
    if rc != 0:
        return None, err
    return json.loads(out), ""


def params(j):
    return {p["name"]: (p["value"], p["u"]) for p in j["parameters"]}


def refuses(name, pattern, *args):
    rc, out, err = run(*args)
    check(name, rc != 0 and pattern in err, f"rc={rc} err={err.strip()} out={out.strip()[:200]}")


def write(name, text):
    path = os.path.join(W, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def add(a, b, s=1.0):
    return [a[i] + s * b[i] for i in range(3)]


def angle(a, b):  # sign-insensitive angle between directions, atan2 form
    c = cross(a, b)
    return math.atan2(math.sqrt(sum(x * x for x in c)), abs(sum(a[i] * b[i] for i in range(3))))


# --- 1. a bore probed with a 1.5 mm tip; approach directions in the canonical CSV ----------
axis = unit([0.02, -0.01, 1.0])
u = unit(cross(axis, [1, 0, 0]))
v = cross(axis, u)
base = [812.5, -431.25, 150.0]
R, tip = 20.0, 1.5
rows = ["time_s,cycle,c_deg,feature,point,x_mm,y_mm,z_mm,nx,ny,nz"]
k = 0
for level in (-12.0, 0.0, 12.0):
    for i in range(8):
        phi = 2 * math.pi * i / 8 + 0.1 * level
        radial = [math.cos(phi) * u[j] + math.sin(phi) * v[j] for j in range(3)]
        surface = add(add(base, axis, level), radial, R)
        centre = add(surface, radial, -tip)  # tip centre inside the bore
        k += 1
        rows.append(f"{k},1,0,bore,{k},{centre[0]:.9f},{centre[1]:.9f},{centre[2]:.9f},"
                    f"{radial[0]:.12f},{radial[1]:.12f},{radial[2]:.12f}")
rows.append("99,1,0,face,1,0,0,0,0,0,-1")
bore = write("bore.csv", "\n".join(rows) + "\n")
j, err = fit_json("cylinder", bore, "--feature", "bore", "--tip-radius", "1.5")
ok = j is not None
if ok:
    p = params(j)
    n = [p["nx"][0], p["ny"][0], p["nz"][0]]
    pos = [p["x_mm"][0], p["y_mm"][0], p["z_mm"][0]]
    off = add(pos, base, -1.0)
    dist = math.sqrt(sum(x * x for x in cross(off, axis)))  # distance of the fitted point from the true axis
    ok = (abs(p["r_mm"][0] - 20.0) < 1e-6 and abs(p["d_mm"][0] - 40.0) < 2e-6 and
          angle(n, axis) < 1e-8 and dist < 1e-6 and j["tip_compensation"]["material"] == "outside"
          and j["input"]["used"] == 24)
check("cylinder bore: tip compensation from approach directions, r = 20 mm", ok, j or err)

# --- 2. a sphere in binary PLY ----------------------------------------------------------
c0, r0 = [500.0, -300.0, 200.0], 12.5
pts = []
for i in range(40):
    th = math.acos(1 - (i + 0.5) / 40)  # upper hemisphere
    ph = 2.399963229728653 * i
    pts.append(add(c0, [math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)], r0))
hdr = ("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty double x\n"
       "property double y\nproperty double z\nend_header\n" % len(pts)).encode()
with open(os.path.join(W, "ball.ply"), "wb") as f:
    f.write(hdr + b"".join(struct.pack("<3d", *q) for q in pts))
j, err = fit_json("sphere", os.path.join(W, "ball.ply"))
ok = j is not None
if ok:
    p = params(j)
    ok = (abs(p["x_mm"][0] - 500) < 1e-9 and abs(p["y_mm"][0] + 300) < 1e-9 and
          abs(p["z_mm"][0] - 200) < 1e-9 and abs(p["d_mm"][0] - 25) < 1e-9 and j["form_um"] < 1e-6)
check("sphere from binary PLY: centre and d = 25 mm", ok, j or err)

# --- 3. flatness: a tilted plane with +-h alternating on a grid (XYZ) -------------------
h = 0.003
nrm = unit([0.01, -0.02, 1.0])
e1 = unit(cross(nrm, [0, 1, 0]))
e2 = cross(nrm, e1)
lines = []
for a in range(7):
    for b in range(7):
        s = h if (a + b) % 2 == 0 else -h
        q = add(add(add([100, 200, 50], e1, 20 * a), e2, 20 * b), nrm, s)
        lines.append("%.12f %.12f %.12f" % tuple(q))
plane = write("plane.xyz", "# grid\n" + "\n".join(lines) + "\n")
j, err = fit_json("plane", plane, "--method", "mz")
check("flatness (mz) of +-3 um alternating grid = 6 um",
      j is not None and abs(j["form_um"] - 6.0) < 1e-6, j or err)
j, err = fit_json("plane", plane)
check("LS plane normal and form", j is not None and abs(j["form_um"] - 6.0) < 1e-6 and
      angle([params(j)[x][0] for x in ("nx", "ny", "nz")], nrm) < 1e-9, j or err)

# --- 4. roundness, MI and MC on an alternating 12-gon ------------------------------------
lines = []
for i in range(12):
    r = 10.0 if i % 2 == 0 else 10.2
    a = math.pi * i / 6
    lines.append("%.12f,%.12f,0" % (-50 + r * math.cos(a), 75 + r * math.sin(a)))
gon = write("gon.xyz", "\n".join(lines) + "\n")
for method, want_r, what in (("mz", 10.1, "roundness zone 0.2 mm"), ("mi", 10.0, "inscribed r 10"),
                             ("mc", 10.2, "circumscribed r 10.2")):
    j, err = fit_json("circle2d", gon, "--method", method)
    ok = j is not None
    if ok:
        p = params(j)
        ok = (abs(p["r_mm"][0] - want_r) < 1e-9 and abs(p["x_mm"][0] + 50) < 1e-9 and
              abs(p["y_mm"][0] - 75) < 1e-9 and p["r_mm"][1] is None)
        if method == "mz":
            ok = ok and abs(j["form_um"] - 200.0) < 1e-6
    check(f"circle2d {method}: {what}", ok, j or err)

# --- 5. outliers: two chips on a circle --------------------------------------------------
rnd = random.Random(5)
rows = ["x_mm,y_mm,z_mm"]
for i in range(90):
    a = 2 * math.pi * i / 90
    r = 25 + rnd.uniform(-0.0015, 0.0015) + (0.05 if i in (10, 47) else 0)
    rows.append("%.7f,%.7f,3" % (r * math.cos(a), r * math.sin(a)))
dirty = write("dirty.csv", "\n".join(rows) + "\n")
j, err = fit_json("circle2d", dirty, "--outliers", "3")
check("outliers at 3 sigma drop points 11 and 48 (1-based) with their lines",
      j is not None and [d["point"] for d in j["outliers"]["dropped"]] == [11, 48] and
      [d["line"] for d in j["outliers"]["dropped"]] == [12, 49] and j["input"]["used"] == 88, j or err)
rc, out, err = run("circle2d", dirty, "--outliers", "3")
check("text summary lists the dropped points", rc == 0 and "point 11 (line 12)" in out, out + err)

# --- 6. uncertainties: type A scales with the residual scatter, type B with u_point -------
j, err = fit_json("circle2d", dirty, "--outliers", "3", "--point-u", "1")
jA, _ = fit_json("circle2d", dirty, "--outliers", "3")
if j and jA:
    uB, uA = params(j)["r_mm"][1], params(jA)["r_mm"][1]
    s_um = jA["residuals_um"]["s"]
    # For n points evenly on a full circle u(r) = u_point / sqrt(n) (independent derivation).
    check("type B u(r) = u_point / sqrt(n) on a full circle", abs(uB - 0.001 / math.sqrt(88)) < 0.001 / math.sqrt(88) * 0.05, (uB,))
    check("type A u(r) / type B u(r) = s / u_point", abs(uA / uB - s_um / 1.0) < 1e-9, (uA, uB, s_um))
else:
    check("uncertainty runs", False, err)

# --- 7. NIST reference pair through the CLI (skipped when the data is absent) -----------
nist = os.environ.get("PROBELOOP_NIST_LS", os.path.join(SRC, "..", "shared", "refdata", "nist-ls"))
if os.path.isdir(nist):
    for kind, folder, name in (("sphere", "Sphere", "sph1"), ("cylinder", "Cylinder", "cyl1"), ("plane", "Plane", "pla1")):
        ds, ref = os.path.join(nist, folder, name + ".ds"), [float(x) for x in open(os.path.join(nist, folder, name + ".fit")).read().split()]
        j, err = fit_json(kind, ds)
        ok = j is not None
        if ok:
            p = params(j)
            if kind == "sphere":
                ok = max(abs(p["x_mm"][0] - ref[0]), abs(p["y_mm"][0] - ref[1]), abs(p["z_mm"][0] - ref[2]), abs(p["d_mm"][0] - ref[3])) < 1e-7
            else:
                n = [p["nx"][0], p["ny"][0], p["nz"][0]]
                pos = [p["x_mm"][0], p["y_mm"][0], p["z_mm"][0]]
                ok = angle(n, ref[3:6]) < 1e-7
                if kind == "plane":
                    ok = ok and abs(sum((pos[i] - ref[i]) * ref[3 + i] for i in range(3))) < 1e-7
                else:
                    d = math.sqrt(sum(x * x for x in cross(add(pos, ref[:3], -1), unit(ref[3:6]))))
                    ok = ok and d < 1e-7 and abs(p["d_mm"][0] - ref[6]) < 1e-7
        check(f"NIST {name}.ds through the CLI", ok, j or err)
else:
    print("skip NIST reference pairs (folder absent)")

# --- 8. bad input: clear messages, exit != 0, nothing half-written ----------------------
line3 = write("line.xyz", "0 0 0\n1 1 1\n2 2 2\n3 3 3\n")
refuses("collinear points for a plane", "collinear", "plane", line3)
refuses("too few points for a sphere", "sphere needs", "sphere", write("three.xyz", "0 0 0\n1 0 0\n0 1 0\n"))
refuses("NaN coordinate names file and line", "nan.xyz:2", "plane", write("nan.xyz", "0 0 0\nnan 1 0\n0 1 0\n1 1 1\n"))
refuses("inscribed plane is not defined", "supported kinds: circle2d, sphere, cylinder", "plane", plane, "--method", "mi")
refuses("tip compensation without a material side", "--material", "circle2d", gon, "--tip-radius", "1")
refuses("tip compensation of a 3D line", "line3d", "line3d", line3, "--tip-radius", "1", "--material", "inside")
refuses("known radius with minimum zone", "least-squares", "circle2d", gon, "--method", "mz", "--radius", "10")
rc, out, err = run("plane", line3, "--json")
check("a failed fit prints no JSON", rc != 0 and out == "", out)
rc, out, _ = run("plane", plane, "--json")
check("--json prints the JSON report", rc == 0 and json.loads(out)["element"] == "plane")

check.finish()
