#!/usr/bin/env python3
"""Integration tests of `probeloop gum` through the real CLI, on the shipped example models.

The reference values are the published ones (JCGM 100 H.1 and H.2, JCGM 101 9.3), never the
code's own output. Bad models must fail with a message that says where, and write nothing.
Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR; plain python3.
"""
import json, os, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks, run_text_and_json  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
EX = os.path.join(SRC, "examples", "gum")
W = tempfile.mkdtemp(prefix="probeloop-gum-")
check = Checks()




def gum(model, *args):
    out = os.path.join(W, "out.json")
    if os.path.exists(out):
        os.remove(out)
    rc, text, err = run_text_and_json(PL, ["gum", model, "--json", out, *args])
    p = subprocess.CompletedProcess([], rc, text, err)
    j = json.load(open(out)) if rc == 0 else None
    return p, j


# JCGM 100 H.1: l = 50.000 838 mm, u_c = 32 nm, nu_eff ~ 16, k99 = 2.92, U99 = 93 nm.
p, j = gum(os.path.join(EX, "end_gauge_h1.yaml"))
o = j and j["outputs"][0]["guf"]
check("H.1 end gauge from the YAML model", o and round(o["y"], 6) == 50.000838 and round(o["u_c"] * 1e6) == 32
      and int(o["nu_eff"]) == 16 and abs(o["k"] - 2.92) < 0.005 and round(o["U"] * 1e6) == 93, p.stdout + p.stderr)

# JCGM 100 H.2 (Table H.3): R = 127.732(71), X = 219.847(295), Z = 254.260(236) ohm;
# r(R,X) = -0.588, r(R,Z) = -0.485, r(X,Z) = 0.993. The GUM's round-off moves u by <= 0.0015.
p, j = gum(os.path.join(EX, "impedance_h2.yaml"))
if j:
    g = {o["name"]: o["guf"] for o in j["outputs"]}
    want = {"R": (127.732, 0.071), "X": (219.847, 0.295), "Z": (254.260, 0.236)}
    check("H.2 values and uncertainties from observations",
          all(abs(g[k]["y"] - v) < 5e-4 and abs(g[k]["u_c"] - u) < 1.5e-3 for k, (v, u) in want.items()), g)
    r = j["output_correlation"]
    check("H.2 output correlations", abs(r[0][1] + 0.588) < 0.006 and abs(r[0][2] + 0.485) < 0.006 and abs(r[1][2] - 0.993) < 0.002, r)
    check("H.2 nu_eff of correlated type A inputs is n - 1 = 4", g["R"]["nu_eff"] == 4, g["R"])
else:
    check("H.2 runs", False, p.stderr)

# JCGM 101 9.3: GUF u = 0.0539 mg, [1.1285, 1.3395]; MCM u = 0.0754 mg, not validated.
p, j = gum(os.path.join(EX, "mass_calibration_9_3.yaml"), "--mcm", "--trials", "1000000")
if j:
    o = j["outputs"][0]
    check("9.3 GUF", abs(o["guf"]["u_c"] - 0.0539) < 5e-5 and abs(o["guf"]["interval"][0] - 1.1285) < 5e-5, o["guf"])
    check("9.3 MCM u and interval", abs(o["mcm"]["u"] - 0.0754) < 3e-4 and abs(o["mcm"]["shortest_interval"][0] - 1.0834) < 3e-3
          and abs(o["mcm"]["shortest_interval"][1] - 1.3825) < 3e-3 and o["mcm"]["trials"] == 1000000, o["mcm"])
    check("9.3 the GUF is not validated, and the report says so", not o["validation"]["guf_validated"]
          and "NOT validated" in p.stdout, p.stdout)
else:
    check("9.3 runs", False, p.stderr)
p2, j2 = gum(os.path.join(EX, "mass_calibration_9_3.yaml"), "--mcm", "--trials", "50000", "--seed", "7")
p3, j3 = gum(os.path.join(EX, "mass_calibration_9_3.yaml"), "--mcm", "--trials", "50000", "--seed", "7")
check("same seed, byte-identical JSON", j2 is not None and j2 == j3)
p4 = subprocess.run([PL, "gum", os.path.join(EX, "mass_calibration_9_3.yaml"), "--trials", "50"], capture_output=True, text=True)
check("too few trials for p are refused with the file", p4.returncode != 0 and "too few" in p4.stderr
      and "mass_calibration_9_3.yaml" in p4.stderr, p4.stderr)

# --- bad models: where, what, nothing written ---------------------------------------------
base = open(os.path.join(EX, "end_gauge_h1.yaml")).read()
cases = [
    ("unknown name, with expression and file column", base.replace('model: "l_s + d', 'model: "l_s + dd'),
     ["unknown name 'dd'", "column 7", "file column 19", "l_s, d, alpha_s"]),
    ("syntax error, with column", base.replace('l_s*(dalpha', 'l_s*(*dalpha'), ["column 16", "expected a number, a name or '('"]),
    ("unclosed parenthesis", base.replace('alpha_s*dtheta)"', 'alpha_s*dtheta"'), ["expected ')'"]),
    ("negative uncertainty", base.replace("u: 0.41,", "u: -0.41,"), ["inputs[3].u", "must be > 0"]),
    ("zero half-width", base.replace("half_width: 2.0e-6", "half_width: 0"), ["half_width", "must be > 0"]),
    ("unknown key", base.replace("u: 0.41,", "u: 0.41, sigma: 2,"), ["sigma"]),
    ("duplicate input", base.replace("name: dalpha", "name: d"), ["defined twice"]),
    ("correlation not PSD", base + "correlations:\n  - [l_s, d, 0.9]\n  - [l_s, theta, 0.9]\n  - [d, theta, -0.9]\n",
     ["not positive semidefinite"]),
    ("correlation with an unknown input", base + "correlations:\n  - [l_s, q, 0.5]\n", ["unknown input 'q'"]),
    ("undefined derivative at the estimate", base.replace('model: "l_s + d', 'model: "sqrt(dalpha) + l_s + d'),
     ["not defined", "outputs.l.model"]),
    ("correlation given twice", base + "correlations:\n  - [l_s, d, 0.5]\n  - [d, l_s, -0.5]\n", ["given twice"]),
    ("correlation entry of the wrong shape", base + "correlations:\n  - [[l_s], d, 0.5]\n", ["[input, input, r]"]),
    ("output defined twice", base + "  - {name: l, unit: mm, model: \"l_s\"}\n", ["defined twice"]),
    ("error inside a block-scalar model", base.replace('model: "l_s + d - l_s*(dalpha*theta + alpha_s*dtheta)"',
     'model: |\n      l_s + d\n        - l_s*(dalpha*thetta + alpha_s*dtheta)'), ["unknown name 'thetta'", "line 2 of the expression"]),
    ("observations without scatter", base.replace("value: -0.1, unit: K, distribution: normal, u: 0.41",
     "observations: [1, 1, 1, 1], unit: K"), ["all observations are equal"]),
]
for name, text, needles in cases:
    f = os.path.join(W, "bad.yaml")
    open(f, "w").write(text)
    out = os.path.join(W, "bad.json")
    p = subprocess.run([PL, "gum", f, "--json"], capture_output=True, text=True)
    msg = p.stderr + p.stdout
    check("refuses: " + name, p.returncode != 0 and all(n in msg for n in needles) and not p.stdout
          and "bad.yaml" in msg, msg)

check.finish()
