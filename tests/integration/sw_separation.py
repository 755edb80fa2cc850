#!/usr/bin/env python3
"""Truth recovery of the stepped workpiece's error separation (seed 000, one workpiece, W8).

plan W8 -> simulate on the virtual VMC of examples/stepped_workpiece/truth.yaml with the plan's
schedule (3 h off before finishing and before probing) -> evaluate the CMM export with the
probe log -> every separated component against what the simulator injected, from truth.json
and the truth file alone (not from the evaluation's code):

- e_pos per step and axis (CMM - probe): the linear axes' tool-side error at the probe's
  contacts (truth.json events[].axes_um), +X wall minus -X wall; Z: top minus floor;
- k_pos (um per mm of travel): the scale coefficients of truth.yaml (EXX, EYY, EZZ);
- e_proc per step (two walls): the tool's deflection away from the material in the cuts that
  made the two walls (truth.json features[].machine.deflection_um along each wall's normal);
- e_splz per step: the tool's Z drift when the floor was cut minus when the top was
  (features[].machine.tool_um).

Each must agree within its U (k = 2); and the large ones must be resolved (|truth| > U), so
the test could fail. A second seed repeats the recovery.

Needs $PROBELOOP and $PROBELOOP_SOURCE_DIR.
"""
import csv, json, os, re, subprocess, sys, tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
W = tempfile.mkdtemp(prefix="probeloop-swsep-")
PIECE = f"{SRC}/parts/stepped_workpiece.yaml"
VMC = f"{SRC}/parts/machines/vmc3.yaml"
TRUTH = f"{SRC}/examples/stepped_workpiece/truth.yaml"
check = Checks()


def run(*args, cwd=None):
    p = subprocess.run([PL, *args], capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stdout, p.stderr


def coefficient(text, axis, name):
    """The linear term (um/mm) of an axis polynomial in the truth YAML."""
    m = re.search(rf"^\s*{axis}:\s*\{{(.*)\}}\s*$", text, re.M)
    c = re.search(rf"{name}:\s*\[([^\]]*)\]", m.group(1)) if m else None
    return float(c.group(1).split(",")[1]) if c else 0.0


plan_dir = f"{W}/plan"
code, out, err = run("plan", PIECE, "--machine", VMC, "--out", plan_dir, "--experiment", "W8")
check("plan W8", code == 0, err)
manifest = json.load(open(f"{plan_dir}/plan.json"))
feature_of = {p["position"]: p["feature"] for p in manifest["points"]}
truth_text = open(TRUTH).read()
k_truth = {"x": coefficient(truth_text, "X", "EXX_um"), "y": coefficient(truth_text, "Y", "EYY_um"),
           "z": coefficient(truth_text, "Z", "EZZ_um")}
check("the truth file has position errors to find", k_truth["x"] > 0.05 and k_truth["y"] > 0.05, k_truth)

for seed in ("1", "7"):
    run_dir, ev_dir = f"{W}/run{seed}", f"{W}/ev{seed}"
    code, out, err = run("simulate", "roughing.ngc", "finishing.ngc", "probing.ngc", "--machine", VMC, "--part", PIECE,
                         "--truth", TRUTH, "--cmm-points", "cmm_points.csv", "--schedule", "plan.json", "--out", run_dir,
                         "--seed", seed, cwd=plan_dir)
    check(f"seed {seed}: simulate W8 with the plan's schedule", code == 0, err)
    hours = re.search(r"([\d.]+) h of machine time", out)
    # roughing + 3 h off + finishing + 3 h off + probing (plan.json's clock)
    planned_h = (manifest["programs"][-1]["start_s"] + manifest["programs"][-1]["duration_s"]) / 3600
    check(f"seed {seed}: the machine-off waits are simulated ({hours.group(1) if hours else '?'} h, planned {planned_h:.2f} h)",
          hours and abs(float(hours.group(1)) - planned_h) < 0.15, out)
    code, out, err = run("evaluate", f"{run_dir}/cmm_export.csv", "--probe-log", f"{run_dir}/sw_probe.log", "--manifest",
                         f"{plan_dir}/plan.json", "--out", ev_dir)
    check(f"seed {seed}: evaluate CMM export + probe log", code == 0, err)
    if code != 0:
        continue
    ev = json.load(open(f"{ev_dir}/evaluation.json"))
    truth = json.load(open(f"{run_dir}/truth.json"))
    feats = {f["id"]: f for f in truth["features"]}

    # truth per probed feature: mean axis error at its contacts
    axes = {}
    for e in truth["events"]:
        axes.setdefault(feature_of[e["position"]], []).append(e["axes_um"])

    def mean_axis(feature, a):
        v = axes[feature]
        return sum(x[a] for x in v) / len(v)

    def along_normal(f, key):
        n, d = f["as_cut"]["normal"], f["machine"][key]
        return sum(n[i] * d[i] for i in range(3))

    def near(name, b, t, resolved=False):
        ok = abs(b["value"] - t) <= b["U"]
        detail = f"{b['value']:.3f} vs truth {t:.3f}, U {b['U']:.3f}"
        check(f"seed {seed}: {name} {detail}", ok and (not resolved or abs(t) > b["U"]), detail)

    for a, axis in ((0, "x"), (1, "y")):
        near(f"k_pos_{axis}", ev[f"k_pos_{axis}_um_per_mm"], k_truth[axis], resolved=True)
    near("k_pos_z", ev["k_pos_z_um_per_mm"], k_truth["z"])
    for s in ev["separation"]:
        k = s["step"]
        for a, axis, P, N in ((0, "x", "XP", "XN"), (1, "y", "YP", "YN")):
            t = mean_axis(f"S{k}_{P}", a) - mean_axis(f"S{k}_{N}", a)
            near(f"step {k} e_pos_{axis}", s[f"e_pos_{axis}_um"], t, resolved=k >= 3)
            t = along_normal(feats[f"S{k}_{P}"], "deflection_um") + along_normal(feats[f"S{k}_{N}"], "deflection_um")
            near(f"step {k} e_proc_{axis} (F {s['feed_mm_per_min']:.0f})", s[f"e_proc_{axis}_um"], t, resolved=k == 4)
        near(f"step {k} e_pos_z", s["e_pos_z_um"], mean_axis("TOP", 2) - mean_axis(f"S{k}_F", 2))
        t = feats[f"S{k}_F"]["machine"]["tool_um"][2] - feats["TOP"]["machine"]["tool_um"][2]
        near(f"step {k} e_splz (T {s['temp_state_min']:.0f} min)", s["e_splz_um"], t, resolved=k >= 2)
    rows = list(csv.DictReader(line for line in open(f"{ev_dir}/errors.csv") if not line.startswith("#")))
    check(f"seed {seed}: errors.csv has a row per step with U", len(rows) == 4 and all(float(r["U_e_splz_um"]) > 0 for r in rows), rows)

# --- bad input ---------------------------------------------------------------------------------
code, out, err = run("evaluate", f"{W}/run1/cmm_export.csv", "--manifest", f"{plan_dir}/plan.json", "--out", f"{W}/bad")
check("the CMM export alone is refused: the probe log is needed", code != 0 and "--probe-log" in err and not os.path.exists(f"{W}/bad"), err)
code, out, err = run("evaluate", f"{W}/run1/cmm_export.csv", "--probe-log", f"{W}/run1/cmm_export.csv", "--manifest",
                     f"{plan_dir}/plan.json", "--out", f"{W}/bad")
check("a CMM export given as the probe log is refused", code != 0 and "expected the on-machine probe log" in err, err)
code, out, err = run("simulate", "probing.ngc", "--machine", VMC, "--part", PIECE, "--truth", TRUTH, "--schedule",
                     f"{SRC}/parts/stepped_workpiece.yaml", "--out", f"{W}/bad", cwd=plan_dir)
check("a schedule that is not a plan manifest is refused", code != 0 and not os.path.exists(f"{W}/bad"), err)
check.finish()
