#!/usr/bin/env python3
"""The thermal test piece (seed 004 Ch. 7) through the real CLI.

plan in both dialects -> LinuxCNC's rs274 on the three LinuxCNC programs (canonical calls
against the manifest, Z constant during the test) -> simulate pre-machining, the test and
the on-machine inspection on the virtual NMV 5000 with a known thermal truth, and the CMM ->
the planned cut times against the simulated clock -> evaluate both routes -> against the
injected (as-cut) values: one run with nothing beyond 2U, the routes agreeing, and over 6
seeds U (k = 2) calibrated -> bad inputs (clear errors, nothing written) -> the dial-gauge
route -> the model finds the piece's own expansion -> the HTML report in headless Chromium,
the glTF scene validated. The formulas themselves (shared by the truth and the evaluation,
parts::ttpErrors) are pinned by hand-derived unit tests, not here.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR; rs274, node and chromium from scripts/setup.sh.
$TTP_WAIT shortens the hour between cutting cycles (the ASan build runs a 20 min variant:
the same programs, cycles and checks, less machine time).
"""
import json, math, os, re, shutil, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks, run_text_and_json  # noqa: E402
from compare_ttp import QUANTITIES, coverage, rows as error_rows  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
WAIT = os.environ.get("TTP_WAIT", "")
W = tempfile.mkdtemp(prefix="probeloop-ttp-")
NMV = f"{SRC}/parts/machines/nmv5000.yaml"
MILL = f"{SRC}/parts/machines/linuxcnc_rotary_mill.yaml"
TRUTH = f"{SRC}/examples/truth_thermal_test.yaml"
check = Checks()


def run(*args, cwd=None):
    return run_text_and_json(PL, args, cwd)


def piece():
    """The shipped description, with a shorter wait when asked (TTP_WAIT)."""
    path = f"{W}/ttp.yaml"
    text = open(f"{SRC}/parts/thermal_test_piece.yaml").read()
    if WAIT:
        text = text.replace("  wait: 1 h ", f"  wait: {WAIT} ")
        assert f"wait: {WAIT}" in text
    open(path, "w").write(text)
    return path


PIECE = piece()

# --- plan, both dialects; LinuxCNC's rs274 on the LinuxCNC programs -----------------------
code, out, err = run("plan", PIECE, "--machine", NMV, "--out", f"{W}/fa")
check("plan (Fanuc, NMV 5000)", code == 0, err)
print("\n".join("     " + l for l in out.splitlines()[:12]))
for name, machine in (("lc5", NMV), ("lc", MILL)):
    code, out, err = run("plan", PIECE, "--machine", machine, "--dialect", "linuxcnc", "--out", f"{W}/{name}")
    check(f"plan (LinuxCNC, {os.path.basename(machine)})", code == 0, err)
code, _, _ = run("plan", PIECE, "--machine", NMV, "--out", f"{W}/fa2")
check("plan is byte-identical", code == 0 and all(
    open(f"{W}/fa/{f}", "rb").read() == open(f"{W}/fa2/{f}", "rb").read() for f in os.listdir(f"{W}/fa")))
manifest = json.load(open(f"{W}/fa/plan.json"))
programs = {p["role"]: p for p in manifest["programs"]}
check("three programs: pre-machining, test, inspection", set(programs) == {"pre_machining", "test", "inspection"}, programs)
ids = [f["id"] for f in manifest["features"]]
check("45 finished surfaces (9 Z paths + 36 facets) and 4 datums",
      sum(f["role"] in ("z_path", "facet") for f in manifest["features"]) == 45 and
      {"TOP", "FLANK_P", "FLANK_N", "CYL"} <= set(ids), ids)

if shutil.which("rs274"):
    # Standalone rs274 reads tool lengths in inches (docs/sphere-cycle.md).
    table = []
    for n, body in re.findall(r"\{number: (\d+),(.*?)\}", open(PIECE).read(), re.S):
        ln = float(re.search(r"[ ,]length: ([\d.]+) mm", body).group(1))
        table.append(f"T{n} P{n} Z{ln / 25.4:.9f} ;tool {n}")
    table.append(f"T99 P99 Z{150 / 25.4:.9f} ;probe")
    open(f"{W}/tool.tbl", "w").write("\n".join(table) + "\n")
    for name in ("lc5", "lc"):
        d = f"{W}/{name}"
        plan = json.load(open(f"{d}/plan.json"))
        canons = []
        for p in plan["programs"]:
            c = subprocess.run(["rs274", "-t", f"{W}/tool.tbl", "-g", p["file"]], cwd=d, capture_output=True, text=True)
            open(f"{d}/{p['file']}.canon", "w").write(c.stdout + c.stderr)
            canons.append(f"{d}/{p['file']}.canon")
        # The description's probing distances, not the program's own (a program consistently
        # wrong would otherwise pass).
        probing = re.search(r"probing: \{[^}]*approach: ([\d.]+) mm, overtravel: ([\d.]+) mm", open(PIECE).read())
        p = subprocess.run([sys.executable, f"{SRC}/tests/integration/check_ttp_rs274.py", f"{d}/plan.json", *canons,
                            "--approach", probing.group(1), "--overtravel", probing.group(2)], capture_output=True, text=True)
        check(f"rs274 accepts the three programs and matches the manifest ({name})", p.returncode == 0, p.stdout + p.stderr)
        print("\n".join("     " + l for l in p.stdout.splitlines()[-4:]))
else:
    check("rs274 installed (scripts/setup.sh)", False)

# --- simulate the whole test on the virtual machine, then the CMM -------------------------
fa = f"{W}/fa"
progs = [f"{fa}/{programs[r]['file']}" for r in ("pre_machining", "test", "inspection")]
code, out, err = run("simulate", *progs, "--machine", NMV, "--part", PIECE, "--truth", TRUTH,
                     "--cmm-points", f"{fa}/{manifest['thermal_test_piece']['cmm_plan']}", "--out", f"{W}/run", "--seed", "5")
check("simulate pre-machining, the test and the inspection, then the CMM", code == 0, err)
print("     " + out.strip().replace("\n", "\n     "))
truth = json.load(open(f"{W}/run/truth.json")) if code == 0 else {"ttp_cycles": [], "features": []}
injected = {c["cycle"]: c for c in truth.get("ttp_cycles", [])}
check("truth.json holds E_X ... E_TTP per cycle", len(injected) == len(manifest["cycles"]), truth.keys())
# The planner times every op with the simulator's clock model: each finishing cut of the test
# must start when the simulator started it (over 8.4 h of machine time).
cut_start = {t["feature"]: t["start_s"] for t in manifest["cuts"] if t["feature"]}
late = [(f["id"], f["cut_time_s"] - cut_start[f["id"]]) for f in truth.get("features", [])
        if f["id"] in cut_start and f.get("cut_time_s") is not None and f["role"] in ("z_path", "facet")]
worst = max((abs(d) for _, d in late), default=float("inf"))
check(f"the planned cut times are the simulated ones ({len(late)} cuts, worst {worst:.3f} s)", len(late) == 45 and worst < 0.5, late[:5])

routes = {}
for route, src in (("cmm", f"{W}/run/cmm_export.csv"), ("om", f"{W}/run/dprnt.txt")):
    code, out, err = run("evaluate", src, "--manifest", f"{fa}/plan.json", "--out", f"{W}/{route}")
    check(f"evaluate the {route} route", code == 0, err)
    if code == 0:
        routes[route] = error_rows(f"{W}/{route}/errors.csv")


# U for k = 2 covers about 95 % of the values one at a time; every cycle shares the
# reference cut's measurement, so the 40 values of one run move together and "all within U"
# is not what a calibrated U promises (over 12 seeds 454 of 480 CMM values, 94.6 %, lay
# within U). One run: none beyond 2 U, the count printed; several seeds pooled (below): the
# coverage and the spread of z = d / u say whether U is honest.
for route, series in routes.items():
    z, inside = coverage(series, injected)
    far = [f"{x:.2f}" for x in z if abs(x) > 4]
    check(f"{route}: E_X ... E_TTP against the injected values: {inside} of {len(z)} within U (k = 2), none beyond 2U",
          len(z) == 40 and not far, far)

if len(routes) == 2:
    bad, inside, n = [], 0, 0
    for cyc in routes["cmm"]:
        if cyc == 0:
            continue
        for q in QUANTITIES:
            a, b = routes["cmm"][cyc], routes["om"][cyc]
            d, U = abs(float(a[q]) - float(b[q])), math.hypot(float(a["U_" + q]), float(b["U_" + q]))
            n += 1
            inside += d <= U
            if d > 2 * U:
                bad.append(f"cycle {cyc} {q}: CMM {a[q]}, on-machine {b[q]}, |diff| {d:.3f} > 2 x {U:.3f}")
    check(f"CMM and on-machine routes agree within their combined U: {inside} of {n}, none beyond 2x",
          inside >= 0.9 * n and not bad, "\n".join(bad))

# --- is U honest? several seeds pooled (Release only: the ASan run skips it) --------------
if not WAIT:
    pooled = {"cmm": [], "om": []}
    for seed in range(11, 17):
        out = f"{W}/seed{seed}"
        code, _, err = run("simulate", *progs, "--machine", NMV, "--part", PIECE, "--truth", TRUTH,
                           "--cmm-points", f"{fa}/cmm_points.csv", "--out", out, "--seed", str(seed))
        inj = {c["cycle"]: c for c in json.load(open(f"{out}/truth.json"))["ttp_cycles"]} if code == 0 else {}
        for route, src in (("cmm", f"{out}/cmm_export.csv"), ("om", f"{out}/dprnt.txt")):
            if code == 0 and run("evaluate", src, "--manifest", f"{fa}/plan.json", "--out", f"{out}/{route}")[0] == 0:
                pooled[route] += coverage(error_rows(f"{out}/{route}/errors.csv"), inj)[0]
    for route, z in pooled.items():
        n = len(z)
        inside = sum(abs(x) <= 2 for x in z)
        sd = math.sqrt(sum(x * x for x in z) / n) if n else 0
        print(f"     {route}: {inside} of {n} within U ({100.0 * inside / max(n, 1):.1f} %), rms of d/u = {sd:.2f}")
        if route == "cmm":
            # The simulated CMM's noise is its MPE model, which the budget states: U should be
            # calibrated (rms of d/u near 1, coverage near 95 %).
            # Bands for 240 values that come in 6 correlated groups (each seed's reference).
            check("CMM route over 6 seeds: U (k = 2) is calibrated (coverage 85-99 %, rms of d/u 0.75-1.3)",
                  n == 240 and 0.85 <= inside / n <= 0.99 and 0.75 <= sd <= 1.3, f"{inside}/{n}, {sd:.2f}")
        else:
            # The on-machine budget adds the thesis's 1 um machine repeatability (L2145), which
            # this truth does not inject: U is conservative here.
            check("on-machine route over 6 seeds: U (k = 2) covers >= 95 % (conservative: rms of d/u < 1)",
                  n == 240 and inside / n >= 0.95 and sd < 1, f"{inside}/{n}, {sd:.2f}")

# --- determinism ---------------------------------------------------------------------------
code, _, _ = run("simulate", *progs, "--machine", NMV, "--part", PIECE, "--truth", TRUTH,
                 "--cmm-points", f"{fa}/cmm_points.csv", "--out", f"{W}/run2", "--seed", "5")
check("simulate: same seed, byte-identical outputs", code == 0 and all(
    open(f"{W}/run/{f}", "rb").read() == open(f"{W}/run2/{f}", "rb").read()
    for f in ("dprnt.txt", "cmm_export.csv", "truth.json", "inputs.csv", "points.csv", "cuts.json")))
check("evaluate: byte-identical outputs", run("evaluate", f"{W}/run2/cmm_export.csv", "--manifest", f"{fa}/plan.json",
                                               "--out", f"{W}/cmm2")[0] == 0 and
      open(f"{W}/cmm/evaluation.json").read().replace("run/", "") == open(f"{W}/cmm2/evaluation.json").read().replace("run2/", ""))

# --- the dial-gauge route (Eqs. 7.7-7.9) gives Eqs. 7.1 and 7.9 of the same surfaces -------
ev = json.load(open(f"{W}/cmm/evaluation.json"))
d = {f["id"]: f["d_mm"] for f in ev["features"] if f.get("d_mm") is not None}
ref = {f["group"]: f["id"] for f in ev["features"] if f["cycle"] == 0 and f["group"] in ("X1", "X2", "Y1", "Y2")}
with open(f"{W}/gauge.csv", "w") as g:
    g.write("facet,g_um\n")
    for fid, v in sorted(d.items()):
        g.write(f"{fid},{(v - d[ref[fid.split('_')[0]]]) * 1e3:.4f}\n")
code, _, err = run("evaluate", f"{W}/gauge.csv", "--manifest", f"{fa}/plan.json", "--out", f"{W}/gauge")
if code == 0:
    gauge = error_rows(f"{W}/gauge/errors.csv")
    worst = max(abs(float(gauge[c][q]) - float(routes["cmm"][c][q])) for c in gauge for q in ("EX_um", "EY_um", "ETTP_um"))
    check("gauge readings g = d(ti) - d(t0) give the CMM's E_X, E_Y (Eqs. 7.7, 7.8) and E_TTP (Eq. 7.3 = 2 x Eq. 7.9), "
          "to the 0.1 nm of the readings", worst < 4e-4, worst)
else:
    check("evaluate the dial-gauge route", False, err)

# --- bad input: clear errors naming the feature and the line, nothing written --------------
lines = open(f"{W}/run/cmm_export.csv").read().splitlines()
head = [l for l in lines if l.startswith("#") or l.startswith("feature")]
body = [l for l in lines if l not in head]


def refuses(name, pattern, content, *extra):
    path = f"{W}/bad-{len(os.listdir(W))}.csv"
    open(path, "w").write(content)
    out = f"{W}/never-{len(os.listdir(W))}"
    code, o, e = run("evaluate", path, "--manifest", f"{fa}/plan.json", "--out", out, *extra)
    check(name, code != 0 and re.search(pattern, e) is not None and not os.path.exists(out), (code, e[:600]))


x13 = [l for l in body if l.startswith("X1_3,")]
refuses("a facet with too few points names it and its lines", r"X1_3.*2 point.*line",
        "\n".join(head + [l for l in body if not l.startswith("X1_3,")] + x13[:2]) + "\n")
refuses("a missing reference cut names the facet", r"X1_5.*reference|reference.*X1_5",
        "\n".join(head + [l for l in body if not l.startswith("X1_5,")]) + "\n")
# Without our labels, in the part frame: assigned by the nominal geometry; one stray point.
plain = ["x_mm,y_mm,z_mm"] + [",".join(l.split(",")[2:5]) for l in body]
refuses("a point that fits no feature names its line", r"bad-\d+\.csv:%d:.*no feature|bad-\d+\.csv:%d:.*fits" % (len(plain) + 1, len(plain) + 1),
        "\n".join(plain + ["0,0,5"]) + "\n")
# The same points turned by 30 deg and moved: not in the part frame, and no labels to align by.
c30, s30 = math.cos(math.radians(30)), math.sin(math.radians(30))
moved = ["x_mm,y_mm,z_mm"]
for l in body:
    x, y, z = (float(v) for v in l.split(",")[2:5])
    moved.append(f"{c30 * x - s30 * y + 200:.4f},{s30 * x + c30 * y + 50:.4f},{z + 10:.4f}")
refuses("a CMM file in another frame says so and how to fix it", r"not in the part frame.*feature ids", "\n".join(moved) + "\n")
code, _, err = run("plan", PIECE, "--machine", f"{SRC}/parts/machines/vmc3.yaml", "--out", f"{W}/nope")
check("a machine without a C axis is refused, nothing written",
      code != 0 and "needs a rotary table (C axis)" in err and not os.path.exists(f"{W}/nope"), err)
narrow = open(PIECE).read().replace("width: 110 mm, depth: 12 mm", "width: 106 mm, depth: 12 mm")
open(f"{W}/narrow.yaml", "w").write(narrow)
code, _, err = run("plan", f"{W}/narrow.yaml", "--machine", NMV, "--out", f"{W}/nope")
check("the thesis's 106 mm notch is refused with the reason and the line", code != 0 and
      re.search(r"narrow\.yaml:\d+: test\.z_paths\.pitch.*108 mm", err) and not os.path.exists(f"{W}/nope"), err)

# --- the model: what a table-side model misses on the piece (seed 004 L2226) ---------------
# The simulator grows the piece with its own node (examples/truth_thermal_test.yaml: part,
# 23.4 um/(m K)); a model with only the C axis's temperature on E_Y and E_Z must be told that
# E_TTP follows the piece (its own or the table's temperature: the piece lags the table by
# ~10 min, and E_TTP's residual correlates with T_table_C at r = -0.98, with T_part_C at -1). Which of the two sensors ranks first is noise:
# over 30 seeds the top candidate was on E_TTP and read T_part_C (22) or T_table_C (8), the
# zero-parameter expansion(T_part_C) itself first in 12 (docs/model.md). So the checks are
# the robust ones: the top candidate, the piece's expansion offered with the piece's lever
# (-2 x 97.5 mm from the part file, nothing fitted), and adding it leaving only measurement noise.
# With $TTP_WAIT (the ASan run) the piece heats a third as much and the rank is not checked.
open(f"{W}/model.yaml", "w").write(
    "kind: error_model\ndata: {inputs: run/inputs.csv, errors: cmm/errors.csv}\nchannels:\n"
    "  EY_um: [{effect: static, input: T_caxis_C}]\n  EZ_um: [{effect: static, input: T_caxis_C}]\n  ETTP_um: []\n")
code, out, err = run("model", "diagnose", f"{W}/model.yaml", "--part", PIECE, "--json", f"{W}/diag.json")
cands = json.load(open(f"{W}/diag.json"))["candidates"] if code == 0 else []
top = cands[0] if cands else {}
if not WAIT:  # the 30-seed rates are for the description's hour between cycles
    check("model diagnose: the top candidate is on E_TTP and reads the piece's or the table's temperature",
          code == 0 and "ETTP_um" in [c["channel"] for c in top.get("channels", [])] and
          re.fullmatch(r"\w+\((T_part_C|T_table_C)\)", top.get("id", "")), (err, top.get("id")))
else:  # a third of the heating: the ranking is not what docs/model.md measured; the rest holds
    check("model diagnose runs", code == 0, err)
    print(f"     (waits of {WAIT}: top candidate {top.get('id')}, not checked)")
exp = next((c for c in cands if c["id"] == "expansion(T_part_C)"), {})
cmd = exp.get("command", "")
check("model diagnose offers the piece's own expansion on E_TTP with its lever from the part file (L = -195 mm)",
      "ETTP_um" in [c["channel"] for c in exp.get("channels", [])] and "--part" in cmd and "--input T_part_C" in cmd,
      [c.get("id") for c in cands])
if cmd:
    code, _, err = run(*cmd.split()[1:])
    text = open(f"{W}/model.yaml").read()
    check("model add writes alpha and L from the part file", code == 0 and
          re.search(r"expansion, input: \"?T_part_C\"?, alpha_um_per_m_K: 23\.4, length: -195 mm", text), err + text)
    code, _, err = run("model", "fit", f"{W}/model.yaml", "--json", f"{W}/fit.json")
    ch = {c["channel"]: c for c in json.load(open(f"{W}/fit.json"))["channels"]} if code == 0 else {}
    e = ch.get("ETTP_um", {})
    sigma, u = e.get("sigma", float("inf")), e.get("u_measurement", 0)
    before = e.get("before", {}).get("indicators", {}).get("validation", {}).get("rmse", 0)
    after = e.get("indicators", {}).get("validation", {}).get("rmse", float("inf"))
    # Only an offset is fitted: with the right physics the residual scatter is the
    # measurement's own (u of E_TTP, the median U/2), not what was missing.
    check(f"with it, E_TTP's residual sigma is the measurement's ({sigma:.2f} um, u {u:.2f}); "
          f"validation RMSE {before:.2f} -> {after:.2f} um", code == 0 and sigma < 1.5 * u and before > 3 * u and after < before, err)

# --- the HTML report in headless Chromium, the glTF scene validated -------------------------
code, out, err = run("report", "ttp", "--evaluation", f"{W}/cmm/evaluation.json", "--second", f"{W}/om/evaluation.json",
                     "--inputs", f"{W}/run/inputs.csv", "--html", f"{W}/report.html", "--scene", f"{W}/scene.gltf",
                     "--manifest", f"{fa}/plan.json")
check("probeloop report ttp writes the page and the scene", code == 0, err)
if code == 0:
    from ttp_report_check import check as report_check  # noqa: E402
    ok, text = report_check(f"{W}/report.html", quantities=["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um", "dT_K"],
                            n_plots=8, inputs=f"{W}/run/inputs.csv")
    check("the report renders every plot in headless Chromium, the temperatures and C load from inputs.csv drawn, "
          "no notes paths or line numbers, the misprinted Eqs. 7.1/7.2 only in the appendix", ok, text)
    if os.path.isdir(f"{SRC}/tests/tools/node_modules/gltf-validator"):
        p = subprocess.run(["node", f"{SRC}/tests/tools/validate_gltf.mjs", f"{W}/scene.gltf"], capture_output=True, text=True)
        check("the test piece's scene passes the Khronos validator", p.returncode == 0, p.stdout + p.stderr)
    else:
        check("gltf-validator installed (scripts/setup.sh)", False)
    p = subprocess.run([sys.executable, f"{SRC}/tests/integration/scene_legend_check.py", f"{W}/scene.gltf"],
                       capture_output=True, text=True)
    check("report ttp --scene also writes the scene's legend page (scene.html), checked in Chromium against the scene",
          p.returncode == 0, p.stdout[-1500:] + p.stderr[-500:])

shutil.rmtree(W, ignore_errors=True) if check.failed == 0 else print(f"     (outputs kept in {W})")
check.finish()
