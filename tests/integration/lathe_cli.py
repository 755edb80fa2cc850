#!/usr/bin/env python3
"""The seed 002 turning centre through the real CLI (docs/lathe-seed002.md):
`probeloop lathe` turns a 24 h campaign on the virtual lathe, and the model loop finds the
effect the starting model lacks.

Independent references, never the code's own output: the body temperatures are integrated
again here from inputs.csv (the exact first-order lag), the parametric errors built from the
truth file's numbers, and the volumetric error P = P_tool - P_work evaluated with the notes'
written-out first-order model (notes/seeds001-003.md §2.5, typed in below), which the chain's
exact P must match to second order (< 0.01 um here). Then: the starting model
(examples/lathe/start.yaml) fails on the face, `model diagnose` names lag(feed_z) with the
truth's gain and time constant, `model add` adds it, and every channel's validation error
falls below U.
Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR; python3 with PyYAML (scripts/setup.sh).
"""
import csv, json, math, os, shutil, subprocess, sys, tempfile

import yaml

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.path.abspath(os.environ["PROBELOOP"])
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
TRUTH = os.path.join(SRC, "examples", "lathe", "lathe_truth.yaml")
W = tempfile.mkdtemp(prefix="probeloop-lathe-")
check = Checks()


def run(*args, cwd=W):
    return subprocess.run([PL, *args], capture_output=True, text=True, cwd=cwd)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def qty(text, unit):
    v, u = str(text).split()
    assert u == unit, (text, unit)
    return float(v)


def minutes(text):
    v, u = str(text).split()
    return float(v) * {"min": 60, "h": 3600, "s": 1}[u]


# --- the campaign, twice: byte-identical -------------------------------------------------
p = run("lathe", TRUTH, "--out", "run", "--seed", "3")
check("lathe writes the campaign", p.returncode == 0 and "145 parts" in p.stdout, p.stdout + p.stderr)
q = run("lathe", TRUTH, "--out", "run2", "--seed", "3")
same = all(open(os.path.join(W, "run", f), "rb").read() == open(os.path.join(W, "run2", f), "rb").read()
           for f in ("inputs.csv", "errors.csv", "truth.csv"))
check("same truth and seed -> byte-identical files", q.returncode == 0 and same)

# --- the truth again, independently -------------------------------------------------------
t = yaml.safe_load(open(TRUTH))
g = t["geometry"]
a = {i + 1: g[k][0] for i, k in enumerate(["z_carriage", "x_slide", "turret", "spindle"])}
b = {i + 1: g[k][1] for i, k in enumerate(["z_carriage", "x_slide", "turret", "spindle"])}
c = {i + 1: g[k][2] for i, k in enumerate(["z_carriage", "x_slide", "turret", "spindle"])}
T, Wp = g["tool_tip"], g["workpiece_point"]
Wx, Wy, Wz = Wp
# nominal positions: eq. 24 (with -z) solved for x and z
x = a[4] + Wx - a[1] - a[2] - a[3] - T[0]
z = c[4] + Wz - c[1] - c[2] - c[3] - T[2]
body_no = {"z_carriage": 1, "x_slide": 2, "turret": 3, "spindle": 4}


def twists(theta):
    """errors per body: d[i] = (dx, dy, dz) mm, e[i] = (ex, ey, ez) rad"""
    d = {i: [0.0, 0.0, 0.0] for i in range(1, 5)}
    e = {i: [0.0, 0.0, 0.0] for i in range(1, 5)}
    for s, th in zip(t["sources"], theta):
        i = body_no[s["body"]]
        for k, key in enumerate(("dx", "dy", "dz")):
            if key in s["per_K"]:
                d[i][k] += qty(s["per_K"][key], "um") * 1e-3 * th
        for k, key in enumerate(("ex", "ey", "ez")):
            if key in s["per_K"]:
                e[i][k] += qty(s["per_K"][key], "urad") * 1e-6 * th
        scale = s.get("screw_um_per_m_K", 0) * 1e-6 * th
        if i == 1:
            d[1][2] += scale * z
        if i == 2:
            d[2][0] += scale * x
    return d, e


def notes_P(d, e):
    """notes §2.5, Px / Py / Pz as printed there (mm)"""
    dx = {i: d[i][0] for i in d}; dy = {i: d[i][1] for i in d}; dz = {i: d[i][2] for i in d}
    ex = {i: e[i][0] for i in e}; ey = {i: e[i][1] for i in e}; ez = {i: e[i][2] for i in e}
    Px = (dx[1] + dx[2] + dx[3] - dx[4] + ey[1] * (c[4] + Wz - z - c[1]) + ey[2] * (c[4] + Wz - z - c[1] - c[2])
          + ey[3] * (c[4] + Wz - z - c[1] - c[2] - c[3]) - ez[1] * (b[4] + Wy - b[1]) - ez[2] * (b[4] + Wy - b[1] - b[2])
          - ez[3] * (b[4] + Wy - b[1] - b[2] - b[3]) - ey[4] * Wz + ez[4] * Wy)
    Py = (dy[1] + dy[2] + dy[3] - dy[4] + ez[1] * (a[4] + Wx - a[1]) + ez[2] * (a[4] + Wx - a[1] - a[2] - x)
          + ez[3] * (a[4] + Wx - a[1] - a[2] - a[3] - x) - ex[1] * (c[4] + Wz - z - c[1])
          - ex[2] * (c[4] + Wz - z - c[1] - c[2]) - ex[3] * (c[4] + Wz - z - c[1] - c[2] - c[3]) + ex[4] * Wz - ez[4] * Wx)
    Pz = (dz[1] + dz[2] + dz[3] - dz[4] + ex[1] * (b[4] + Wy - b[1]) + ex[2] * (b[4] + Wy - b[1] - b[2])
          + ex[3] * (b[4] + Wy - b[1] - b[2] - b[3]) - ey[1] * (a[4] + Wx - a[1]) - ey[2] * (a[4] + Wx - a[1] - a[2] - x)
          - ey[3] * (a[4] + Wx - a[1] - a[2] - a[3] - x) + ey[4] * Wx - ex[4] * Wy)
    return Px, Py, Pz


inputs = rows(os.path.join(W, "run", "inputs.csv"))
truth = {int(r["cycle"]): r for r in rows(os.path.join(W, "run", "truth.csv"))}
errors = rows(os.path.join(W, "run", "errors.csv"))
# the lags from the logged loads: tau dtheta/dt = K u - theta, u held over each step
theta = [0.0] * len(t["sources"])
at_time = {}
for k, r in enumerate(inputs):
    if k > 0:
        dt = float(r["time_s"]) - float(inputs[k - 1]["time_s"])
        for i, s in enumerate(t["sources"]):
            u = s["K_per_unit"] * float(inputs[k - 1][s["input"]])
            theta[i] = u + (theta[i] - u) * math.exp(-dt / minutes(s["tau"]))
    at_time[round(float(r["time_s"]))] = list(theta)
worst_theta = worst_P = 0.0
for cyc, r in truth.items():
    th = at_time[round(float(r["time_s"]))]
    cols = ["theta_spindle_K", "theta_z_carriage_K", "theta_x_slide_K"]
    worst_theta = max(worst_theta, max(abs(th[i] - float(r[col])) for i, col in enumerate(cols)))
    P = notes_P(*twists(th))
    worst_P = max(worst_P, max(abs(P[k] * 1e3 - float(r[col])) for k, col in enumerate(("Px_um", "Py_um", "Pz_um"))))
check("body temperatures = the lags integrated from inputs.csv (< 1e-3 K)", worst_theta < 1e-3, worst_theta)
check("the chain's exact P = the notes' first-order Px, Py, Pz to second order (< 0.01 um)", worst_P < 0.01, worst_P)
peak = max(float(r["P_um"]) for r in truth.values())
check("the cold start's resultant is of the paper's order (40..65 um)", 40 < peak <= 66, peak)
# measured = true (relative to cycle 1) + noise; diameter = 2 Px and face = Pz at Wy = 0
res_d = [float(e["diameter_um"]) - 2e3 * notes_P(*twists(at_time[round(float(e["time_s"]))]))[0] for e in errors]
res_f = [float(e["face_z_um"]) - 1e3 * notes_P(*twists(at_time[round(float(e["time_s"]))]))[2] for e in errors]
sd = lambda v: math.sqrt(sum((x - sum(v) / len(v)) ** 2 for x in v) / (len(v) - 1))
sigma = qty(t["measurement"]["diameter_noise"], "um")
check("errors.csv: 2 Px and Pz plus the measurement's noise (sigma 0.7 um)",
      0.7 * sigma < sd(res_d) < 1.3 * sigma and 0.7 * sigma < sd(res_f) < 1.3 * sigma, (sd(res_d), sd(res_f)))
U = float(errors[1]["U_face_z_um"])
check("U = 2 sqrt(2) sigma (the difference of two measured parts)", abs(U - 2 * math.sqrt(2) * sigma) < 1e-3, U)

# --- the model loop ------------------------------------------------------------------------
with open(os.path.join(W, "model.yaml"), "w") as f:
    f.write("data: {inputs: run/inputs.csv, errors: run/errors.csv}\n")
    f.write(open(os.path.join(SRC, "examples", "lathe", "start.yaml")).read())
p = run("model", "diagnose", "model.yaml", "--json")
d = json.loads(p.stdout) if p.returncode == 0 else {}
face = next((ch for ch in d.get("channels", []) if ch["channel"] == "face_z_um"), None)
check("the starting model fails on the face: residual beyond U and not white",
      face and face["rms_residual"]["validation"] > U and not face["white"], p.stdout[:400] + p.stderr)
top = d.get("candidates", [{}])[0]
check("diagnose ranks lag(feed_z_mm_per_min) first, on face_z_um",
      d.get("verdict") == "missing" and top.get("id") == "lag(feed_z_mm_per_min)"
      and [ch["channel"] for ch in top.get("channels", [])][:1] == ["face_z_um"], top)
# the truth's gain on the face: Pz per K of the Z carriage (notes §2.5) x K per mm/min
zs = next(i for i, s in enumerate(t["sources"]) if s["body"] == "z_carriage")
unit = [0.0] * len(t["sources"]); unit[zs] = 1.0
k_true = notes_P(*twists(unit))[2] * 1e3 * t["sources"][zs]["K_per_unit"]
tau_true = minutes(t["sources"][zs]["tau"])
pars = {q["name"]: q for q in (top.get("channels") or [{}])[0].get("parameters", [])}
k_fit, tau_fit = pars.get("k", {}).get("value", 0), pars.get("tau", {}).get("value", 0)
check(f"its gain and lag are the Z carriage's ({k_true:.5f} um/(mm/min), {tau_true / 60:.0f} min) within 5 %",
      abs(k_fit - k_true) < 0.05 * abs(k_true) and abs(tau_fit - tau_true) < 0.05 * tau_true, (k_fit, tau_fit))
cmd = top.get("command", "").split()
p = run(*cmd[1:]) if cmd[:1] == ["probeloop"] else None
check("model add the proposed effect", p is not None and p.returncode == 0, p and p.stdout + p.stderr)
p = run("model", "fit", "model.yaml", "--json")
fit = json.loads(p.stdout) if p.returncode == 0 else {"channels": []}
after = {ch["channel"]: ch["indicators"]["validation"]["rmse"] for ch in fit["channels"]}
before = {ch["channel"]: ch["before"]["indicators"]["validation"]["rmse"] for ch in fit["channels"] if ch.get("before")}
check("after it, every channel's validation RMSE is below U",
      len(after) == 2 and all(v < U for v in after.values()) and before.get("face_z_um", 0) > U, (before, after))
p = run("model", "diagnose", "model.yaml", "--json")
check("and nothing is missing any more", p.returncode == 0 and json.loads(p.stdout)["verdict"] == "nothing_missing",
      p.stdout[:300])

# --- refusals ------------------------------------------------------------------------------
bad = open(TRUTH).read().replace("tool_tip: [-150, 0, -100]", "tool_tip: [-150, 2, -100]")
open(os.path.join(W, "bad.yaml"), "w").write(bad)
p = run("lathe", "bad.yaml", "--out", "bad")
check("a tool off centre height is refused with the file, line and eq. 24",
      p.returncode == 1 and "bad.yaml:" in p.stderr and "tool_tip" in p.stderr and "eq. 24" in p.stderr
      and not os.path.exists(os.path.join(W, "bad")), p.stderr)

shutil.rmtree(W, ignore_errors=True)
check.finish()
