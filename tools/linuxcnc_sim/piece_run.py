#!/usr/bin/python3
"""The thermal test piece's inspection and the stepped workpiece's probing on LinuxCNC in simulation.

Usage: piece_run.py --probeloop build/cli/probeloop --work DIR --piece ttp|sw [--seed 1]
                    [--servo-period-ns 100000] [--no-noise] [--scale-um-per-mm SX SY]

1. A test variant (DIR/machine.yaml, DIR/part.yaml) of parts/machines/linuxcnc_rotary_mill.yaml
   (rapids and axis feeds 20 m/min, C 60 rpm) and of the piece, shortened so that LinuxCNC runs
   its probing program in about a minute: positioning feed 10 m/min, a short approach; the
   thermal test piece with 3 cutting cycles (reference, 1 h warm-up, 1 h hold: 3 Z paths, 3 facets
   per segment), 4 points per facet and Z path, 6 on the datum circle (94 points); the stepped
   workpiece (W8) with 2 positions x 2 levels per wall (125 points). The probing feed stays the
   piece's (200 / 100 mm/min).
2. probeloop plan, then probeloop simulate of the machining programs and the probing program on
   the virtual machine (the same variant machine, examples/truth_thermal_test.yaml or
   examples/stepped_workpiece/truth.yaml): DIR/run/truth.json holds the part as cut
   (features[].as_cut: planes and the datum cylinder, part frame), DIR/run the VM's own log and
   CMM export; probeloop evaluate of the VM's log -> DIR/vm_eval.
3. The surfaces for LinuxCNC (DIR/lcnc/patches.json): per planned point, the as-cut surface it
   probes, in machine coordinates at the point's C angle (part frame -> machine: the plan's part
   origin, C positive clockwise; checked against the nominal features and the planned contacts).
   The stepped workpiece's also carry a position error field: linear scale errors of X and Y
   (default the truth YAML's EXX/EYY, 0.15 / 0.25 um/mm: the machine reads x where the tip is at
   x (1 + s)), which the evaluation's e_pos / k_pos must recover. Probe noise: the truth YAML's.
4. The configuration (make_config.py's write_ini; the HAL here: surface_probe.py and its
   servo-thread chain), run_program.py runs the program; probeloop evaluate of LinuxCNC's log
   (the stepped workpiece with the VM's CMM export) -> DIR/eval.
5. Per contact the overshoot beyond the surface (um, along the normal); the comparison of the
   evaluation with the truth and with the VM's evaluation -> DIR/summary.json (the test asserts).
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import make_config  # noqa: E402
import run_program  # noqa: E402
from sphere_run import read_log, stats  # noqa: E402

PIECES = {
    "ttp": {"part": "parts/thermal_test_piece.yaml", "truth": "examples/truth_thermal_test.yaml",
            "programs": ["pre_machining.ngc", "thermal_test.ngc", "inspection.ngc"], "probe_program": "inspection.ngc",
            "log": "ttp_probe.log"},
    "sw": {"part": "parts/stepped_workpiece.yaml", "truth": "examples/stepped_workpiece/truth.yaml",
           "programs": ["roughing.ngc", "finishing.ngc", "probing.ngc"], "probe_program": "probing.ngc",
           "log": "sw_probe.log"},
}
TTP_NAMES = ["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"]


def test_inputs(src, work, piece):
    with open(os.path.join(src, "parts/machines/linuxcnc_rotary_mill.yaml")) as f:
        machine = yaml.safe_load(f)
    with open(os.path.join(src, PIECES[piece]["part"])) as f:
        part = yaml.safe_load(f)
    for n in "XYZ":
        machine["axes"][n]["max_feed"] = "20000 mm/min"
    machine["rapid_feed"] = "20000 mm/min"
    machine["axes"]["C"]["max_speed"] = "60 rpm"
    if piece == "ttp":
        insp = part["inspection"]
        # approach 2 mm: with 1 mm, simulate refuses the C index beside the datum band (the tip 0.18 mm
        # inside its 0.5 mm clearance), although plan accepted it
        insp["probing"].update({"positioning_feed": "10000 mm/min", "approach": "2 mm"})
        insp["facet_points"] = {"across": ["-3 mm", "3 mm"], "heights": ["-3 mm", "-9 mm"]}
        insp["z_path_points"] = {"along": ["-60 mm", "60 mm"], "across": ["-3 mm", "3 mm"]}
        insp["datum_circle"]["points"] = 6
        part["pre_machining"]["facets"]["per_segment"] = 3
        part["test"]["z_paths"]["count"] = 3
        part["test"]["order"] = [2, 1, 3]
        part["test"]["load"] = [{"phase": "warm_up", "cycles": 1, "c_axis_speed": "1200 rpm"},
                                {"phase": "hold", "cycles": 1, "c_axis_speed": "0 rpm"}]
    else:
        part["probing"].update({"positioning_feed": "10000 mm/min", "approach": "0.5 mm", "clearance": "3 mm",
                                "wall_positions": [-0.6, 0.6]})
        machine["probe"]["tip_diameter"] = part["probing"]["tip_diameter"]   # the piece's stylus (tool table D)
    paths = os.path.join(work, "machine.yaml"), os.path.join(work, "part.yaml")
    for p, doc in zip(paths, (machine, part)):
        with open(p, "w") as f:
            f.write("# test variant written by tools/linuxcnc_sim/piece_run.py\n")
            yaml.safe_dump(doc, f, sort_keys=False)
    return paths


# part frame -> machine at C (C positive clockwise seen from +Z: the part turns by -C)
def to_machine(v, c_deg, origin=None):
    c, s = math.cos(math.radians(c_deg)), math.sin(math.radians(c_deg))
    out = [c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]]
    return [out[k] + origin[k] for k in range(3)] if origin else out


def to_part(m, c_deg, origin):
    v = [m[k] - origin[k] for k in range(3)]
    c, s = math.cos(math.radians(c_deg)), math.sin(math.radians(c_deg))
    return [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def build_patches(plan, truth, scale, noise_um):
    """Per planned point: the as-cut surface it probes, machine frame at its C. Also checks the
    transform: each planned tip contact lies r off the nominal feature."""
    origin = plan["part"]["origin_mm"]
    nominal = {f["id"]: f for f in plan["features"]}
    cut = {f["id"]: f for f in truth["features"]}
    patches, worst = [], 0.0
    for p in plan["points"]:
        fid, c, r = p["feature"], p["c_deg"], p["tip_radius_mm"]
        tip = to_part(p["contact_mm"], c, origin)
        f = nominal[fid]
        if f["kind"] == "cylinder":
            ax = f["point_mm"]
            err = math.hypot(tip[0] - ax[0], tip[1] - ax[1]) - (f["radius_mm"] + r)
        else:
            err = dot([tip[k] - f["point_mm"][k] for k in range(3)], f["direction"]) - r
        worst = max(worst, abs(err))
        ac = cut[fid]["as_cut"]
        if cut[fid]["kind"] == "cylinder":
            ctr = ac["centre_mm"]
            u = [tip[0] - ctr[0], tip[1] - ctr[1], 0.0]
            nu = math.hypot(u[0], u[1])
            n_part = [u[0] / nu, u[1] / nu, 0.0]
            p_part = [ctr[0] + ac["radius_mm"] * n_part[0], ctr[1] + ac["radius_mm"] * n_part[1], tip[2]]
        else:
            n_part = list(ac["normal"])
            if dot(n_part, f["direction"]) < 0:
                n_part = [-v for v in n_part]
            p_part = ac["point_mm"]
        n = to_machine(n_part, c)
        P = to_machine(p_part, c, origin)
        patches.append({"feature": fid, "position": p["position"], "point": p["point"], "c_deg": c % 360.0,
                        "q": p["contact_mm"], "a": p["approach"], "r": r, "n": n, "P": P, "d": dot(n, P)})
    if worst > 1e-3:
        sys.exit(f"piece_run: the part frame -> machine transform does not put the planned contacts on the nominal "
                 f"features (worst {worst * 1e3:.1f} um)")
    return {"scale_um_per_mm": scale, "noise_um": noise_um, "transform_check_um": worst * 1e3, "patches": patches}


def write_hal(path, out, probe, seed):
    comp = os.path.join(out, "surface_probe.py")
    lines = [
        "# Generated by tools/linuxcnc_sim/piece_run.py - do not edit.",
        "# XYZC trivkins; the drives are ideal (motor-pos-fb = motor-pos-cmd).",
        "loadrt trivkins coordinates=XYZC",
        "loadrt [EMCMOT]EMCMOT servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS",
        "addf motion-command-handler servo-thread",
        "addf motion-controller servo-thread",
    ]
    lines += [f"net j{j}-pos joint.{j}.motor-pos-cmd => joint.{j}.motor-pos-fb" for j in range(4)]
    lines += [
        "net estop-loop iocontrol.0.user-enable-out => iocontrol.0.emc-enable-in",
        "net tool-prep-loop iocontrol.0.tool-prepare => iocontrol.0.tool-prepared",
        "net tool-change-loop iocontrol.0.tool-change => iocontrol.0.tool-changed",
        "",
        "# Contact in the servo thread, after motion: kx x + ky y + kz z + off (the tip centre's signed",
        "# distance from the active plane) < contact radius. surface_probe.py sets k, off and the radius.",
        "loadrt mult2 names=pl_mx,pl_my,pl_mz",
        "loadrt sum2 names=pl_s1,pl_s2,pl_s3",
        "loadrt comp names=pl_touch",
    ]
    lines += [f"addf {n} servo-thread" for n in ("pl_mx", "pl_my", "pl_mz", "pl_s1", "pl_s2", "pl_s3", "pl_touch")]
    lines += [
        f"loadusr -Wn pl_surf /usr/bin/python3 {comp} --name pl_surf --patches {os.path.join(out, 'patches.json')}"
        f" --probe-tool {probe['tool']} --probe-length {probe['length']:.6f} --seed {seed} --record contacts.jsonl",
        "net x-fb joint.0.pos-fb => pl_surf.x-fb pl_mx.in0",
        "net y-fb joint.1.pos-fb => pl_surf.y-fb pl_my.in0",
        "net z-fb joint.2.pos-fb => pl_surf.z-fb pl_mz.in0",
        "net c-fb joint.3.pos-fb => pl_surf.c-fb",
        "net tool-in-spindle iocontrol.0.tool-number => pl_surf.tool-number",
        "net motion-type motion.motion-type => pl_surf.motion-type",
        "net kx pl_surf.kx => pl_mx.in1", "net ky pl_surf.ky => pl_my.in1", "net kz pl_surf.kz => pl_mz.in1",
        "net mx pl_mx.out => pl_s1.in0", "net my pl_my.out => pl_s1.in1",
        "net s1 pl_s1.out => pl_s2.in0", "net mz pl_mz.out => pl_s2.in1",
        "net s2 pl_s2.out => pl_s3.in0", "net off pl_surf.off => pl_s3.in1",
        "net dist pl_s3.out => pl_touch.in0",
        "net contact-radius pl_surf.contact-radius => pl_touch.in1",
        "net probe pl_touch.out => motion.probe-input pl_surf.probe-in",
        "",
        "# External offsets enabled (1 count = 1 um), as make_config.py; nothing drives them here.",
    ]
    lines += [f"setp axis.{n}.eoffset-scale 0.001" for n in "xyzc"]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_config(out, machine_path, servo_ns, seed):
    with open(machine_path) as f:
        machine = yaml.safe_load(f)
    axes = make_config.machine_axes(machine, 5000.0, 3600.0)
    p = machine["probe"]
    probe = {"tool": int(p["tool"]), "length": make_config.quantity(p["length"], make_config.LENGTH, "probe.length"),
             "diameter": make_config.quantity(p["tip_diameter"], make_config.LENGTH, "probe.tip_diameter")}
    for script in ("surface_probe.py", "headless_display.py"):
        shutil.copyfile(os.path.join(HERE, script), os.path.join(out, script))
        os.chmod(os.path.join(out, script), 0o755)
    make_config.write_ini(os.path.join(out, "linuxcnc.ini"), machine, axes, servo_ns,
                          os.path.join(out, "headless_display.py"))
    write_hal(os.path.join(out, "sim.hal"), out, probe, seed)
    with open(os.path.join(out, "tool.tbl"), "w") as f:
        f.write(f"T{probe['tool']} P{probe['tool']} Z{probe['length']:.6f} D{probe['diameter']:.6f} ;touch probe\n")
    open(os.path.join(out, "linuxcnc.var"), "w").close()


def read_errors_csv(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
    return {int(r["cycle"]): {k: float(v) for k, v in r.items() if k != "cycle"} for r in rows}


def compare_ttp(lc_csv, vm_csv, truth):
    lc, vm = read_errors_csv(lc_csv), read_errors_csv(vm_csv)
    tr = {c["cycle"]: c for c in truth["ttp_cycles"]}
    out = []
    for cyc in sorted(tr):
        if cyc == 0:
            continue
        for n in TTP_NAMES:
            U = lc[cyc]["U_" + n]
            Uvm = vm[cyc]["U_" + n]
            out.append({"cycle": cyc, "name": n, "truth": tr[cyc][n], "linuxcnc": lc[cyc][n], "vm": vm[cyc][n],
                        "U": U, "U_vm": Uvm, "lc_minus_truth": lc[cyc][n] - tr[cyc][n],
                        "vm_minus_truth": vm[cyc][n] - tr[cyc][n], "lc_minus_vm": lc[cyc][n] - vm[cyc][n],
                        "lc_within_U": abs(lc[cyc][n] - tr[cyc][n]) <= U,
                        "vm_within_U": abs(vm[cyc][n] - tr[cyc][n]) <= Uvm,
                        "lc_vm_within_U": abs(lc[cyc][n] - vm[cyc][n]) <= math.hypot(U, Uvm)})
    return out


def compare_sw(lc_eval, vm_eval, truth, plan, scale):
    """The probe's planes against the as-cut planes seen through the scale field, and k_pos against it."""
    origin = plan["part"]["origin_mm"]
    cut = {f["id"]: f["as_cut"] for f in truth["features"]}
    s = [scale[0] * 1e-3, scale[1] * 1e-3, 0.0]
    planes = []
    for pl in lc_eval["on_machine"]["planes"]:
        ac = cut[pl["id"]]
        n = list(ac["normal"])
        if dot(n, pl["normal"]) < 0:
            n = [-v for v in n]
        m_read = [pl["point_mm"][k] + origin[k] for k in range(3)]           # sw: C = 0
        m_phys = [m_read[k] * (1 + s[k]) for k in range(3)]
        P = [ac["point_mm"][k] + origin[k] for k in range(3)]
        dev_um = dot(n, [m_phys[k] - P[k] for k in range(3)]) * 1e3
        no_field_um = dot(n, [m_read[k] - P[k] for k in range(3)]) * 1e3   # as if nothing had been injected
        planes.append({"id": pl["id"], "points": pl["points"], "deviation_um": dev_um, "deviation_no_field_um": no_field_um})
    k = {}
    for ax, sv in zip("xy", scale):
        q = lc_eval[f"k_pos_{ax}_um_per_mm"]
        qv = vm_eval[f"k_pos_{ax}_um_per_mm"]
        k[ax] = {"injected": sv, "linuxcnc": q["value"], "U": q["U"], "vm": qv["value"], "U_vm": qv["U"],
                 "within_U": abs(q["value"] - sv) <= q["U"]}
    return planes, k


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--probeloop", required=True)
    ap.add_argument("--source-dir", default=os.path.dirname(os.path.dirname(HERE)))
    ap.add_argument("--work", required=True)
    ap.add_argument("--piece", choices=sorted(PIECES), required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--servo-period-ns", type=int, default=100000)
    ap.add_argument("--no-noise", action="store_true")
    ap.add_argument("--scale-um-per-mm", type=float, nargs=2, default=None,
                    help="X and Y scale errors applied by the probe component (sw default: the truth's 0.15 0.25; ttp 0 0)")
    ap.add_argument("--timeout", type=float, default=400.0)
    a = ap.parse_args(argv)
    src, work = os.path.abspath(a.source_dir), os.path.abspath(a.work)
    pc = PIECES[a.piece]
    truth_yaml = os.path.join(src, pc["truth"])
    os.makedirs(work, exist_ok=True)
    os.chmod(work, 0o755)   # LinuxCNC's user (run_program.py) works in work/lcnc
    machine, part = test_inputs(src, work, a.piece)
    plan_dir, run_dir, lc = (os.path.join(work, n) for n in ("plan", "run", "lcnc"))
    plan_cmd = [a.probeloop, "plan", part, "--machine", machine, "--out", plan_dir]
    if a.piece == "sw":
        plan_cmd += ["--experiment", "W8"]
    subprocess.run(plan_cmd, check=True, stdout=subprocess.DEVNULL)
    progs = [os.path.join(plan_dir, n) for n in pc["programs"]]
    sim = [a.probeloop, "simulate", *progs, "--machine", machine, "--part", part, "--truth", truth_yaml,
           "--out", run_dir, "--seed", str(a.seed)]
    if a.piece == "ttp":
        sim += ["--cmm-points", os.path.join(plan_dir, "cmm_plan.qif")]
    else:
        sim += ["--cmm-points", os.path.join(plan_dir, "cmm_points.csv"), "--schedule", os.path.join(plan_dir, "plan.json")]
    subprocess.run(sim, check=True, stdout=subprocess.DEVNULL)
    manifest = os.path.join(plan_dir, "plan.json")

    def evaluate(log, out):
        if a.piece == "ttp":
            cmd = [a.probeloop, "evaluate", log, "--format", "linuxcnc", "--manifest", manifest, "--out", out]
        else:
            cmd = [a.probeloop, "evaluate", os.path.join(run_dir, "cmm_export.csv"), "--probe-log", log,
                   "--manifest", manifest, "--out", out]
        return subprocess.run(cmd, capture_output=True, text=True)

    r = evaluate(os.path.join(run_dir, pc["log"]), os.path.join(work, "vm_eval"))
    if r.returncode != 0:
        sys.exit(f"piece_run: evaluate of the VM's log failed: {r.stderr.strip()}")
    with open(manifest) as f:
        plan = json.load(f)
    with open(os.path.join(run_dir, "truth.json")) as f:
        truth = json.load(f)
    with open(truth_yaml) as f:
        ty = yaml.safe_load(f)
    noise_um = 0.0 if a.no_noise else 1e3 * make_config.quantity(ty.get("probe", {}).get("noise", 0),
                                                                 make_config.LENGTH, "probe.noise")
    if a.scale_um_per_mm is not None:
        scale = list(a.scale_um_per_mm)
    elif a.piece == "sw":
        scale = [ty["axes"]["X"]["EXX_um"][1], ty["axes"]["Y"]["EYY_um"][1]]
    else:
        scale = [0.0, 0.0]

    if os.path.exists(lc):
        shutil.rmtree(lc)
    os.makedirs(lc)
    os.chmod(lc, 0o777)
    patches = build_patches(plan, truth, scale, noise_um)
    with open(os.path.join(lc, "patches.json"), "w") as f:
        json.dump(patches, f, indent=1)
    write_config(lc, machine, a.servo_period_ns, a.seed)
    t0 = time.monotonic()
    ok, result = run_program.run(lc, os.path.join(plan_dir, pc["probe_program"]), timeout=a.timeout)
    wall = time.monotonic() - t0
    summary = {"piece": a.piece, "ok": ok, "linuxcnc_wall_s": wall, "program_s": result.get("run_s"),
               "messages": result.get("messages"), "servo_period_ns": a.servo_period_ns,
               "points_planned": len(plan["points"]), "scale_um_per_mm": scale, "noise_um": noise_um,
               "transform_check_um": patches["transform_check_um"]}
    log = os.path.join(lc, pc["log"])
    if ok and os.path.exists(log):
        rows = read_log(log)
        events = [json.loads(line) for line in open(os.path.join(lc, "contacts.jsonl"))]
        contacts = [e for e in events if e["event"] == "contact"]
        summary.update({"points_logged": len(rows), "contacts": len(contacts),
                        "contacts_without_patch": sum(1 for e in contacts if e["patch"] < 0),
                        # motion-type as the 1 ms poll saw it: 5 probing, 0 when the probing move had already
                        # stopped; 1-3 (rapid, feed, arc) would be a contact outside a probing move
                        "contacts_in_other_moves": sum(1 for e in contacts if e["motion_type"] not in (0, 5))})
        planned = {(p["position"], p["point"]) for p in plan["points"]}
        summary["planned_points_missing"] = len(planned - {(r_["position"], r_["point"]) for r_ in rows})
        # overshoot: how far beyond the surface (along its normal) the logged tip centre is
        pt = patches["patches"]
        s = [v * 1e-3 for v in scale] + [0.0]
        ov = []
        by_id = {(q["position"], q["point"]): q for q in pt}
        for row, c in zip(rows, contacts):
            p = pt[c["patch"]]
            phys = [row["xyz"][k] * (1 + s[k]) for k in range(3)]
            um = (c["radius"] - (dot(p["n"], phys) - p["d"])) * 1e3
            feed = 200.0 if a.piece == "ttp" else 100.0
            cosang = abs(dot(p["n"], p["a"]))
            # the planned point of the log line (a repeated pass probes the same place: the same patch geometry)
            want = by_id.get((row["position"], row["point"]))
            same = want is not None and want["c_deg"] == p["c_deg"] and math.dist(want["q"], p["q"]) < 1e-6 \
                and math.dist(want["a"], p["a"]) < 1e-9
            ov.append({"position": row["position"], "point": row["point"], "feature": p["feature"], "same_point": same,
                       "overshoot_um": um, "latency_ms": um / cosang / (feed / 60.0)})
        summary["contact_order_matches_log"] = all(o["same_point"] for o in ov) and len(ov) == len(rows)
        summary["overshoot_um"] = stats([o["overshoot_um"] for o in ov])
        summary["latency_ms"] = stats([o["latency_ms"] for o in ov])
        summary["probing_feed_mm_min"] = 200.0 if a.piece == "ttp" else 100.0
        with open(os.path.join(work, "overshoot.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(ov[0]) if ov else ["position"])
            w.writeheader()
            w.writerows(ov)
        r = evaluate(log, os.path.join(work, "eval"))
        summary["evaluate_rc"] = r.returncode
        summary["evaluate_stdout"] = r.stdout
        if r.returncode != 0:
            summary["evaluate_error"] = r.stderr.strip()
        elif a.piece == "ttp":
            summary["comparison"] = compare_ttp(os.path.join(work, "eval", "errors.csv"),
                                                os.path.join(work, "vm_eval", "errors.csv"), truth)
        else:
            with open(os.path.join(work, "eval", "evaluation.json")) as f:
                lce = json.load(f)
            with open(os.path.join(work, "vm_eval", "evaluation.json")) as f:
                vme = json.load(f)
            planes, k = compare_sw(lce, vme, truth, plan, scale)
            summary["planes"], summary["k_pos"] = planes, k
            summary["repeatability_um"] = lce.get("probe_repeatability_um")
    with open(os.path.join(work, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(f"LinuxCNC ({a.piece}, servo period {a.servo_period_ns / 1000:.0f} us): {'ran' if ok else 'FAILED'} in "
          f"{wall:.1f} s wall, {summary.get('points_logged', 0)} of {len(plan['points'])} points logged")
    o = summary.get("overshoot_um")
    if o:
        print(f"  overshoot at {summary['probing_feed_mm_min']:.0f} mm/min: mean {o['mean']:.3f} um, sd {o['sd']:.3f} um, "
              f"range {o['min']:.3f} .. {o['max']:.3f} um")
    for c in summary.get("comparison", []):
        print(f"  cycle {c['cycle']} {c['name']:8s} truth {c['truth']:8.3f}  LinuxCNC {c['linuxcnc']:8.3f}  "
              f"VM {c['vm']:8.3f}  U {c['U']:.3f}  LinuxCNC-truth {c['lc_minus_truth']:+.3f}")
    if "planes" in summary:
        d = [p["deviation_um"] for p in summary["planes"]]
        print(f"  probed planes - as cut (through the scale field): {len(d)} planes, "
              f"{min(d):+.3f} .. {max(d):+.3f} um; repeatability {summary.get('repeatability_um', 0):.3f} um")
        for ax, q in summary["k_pos"].items():
            print(f"  k_pos_{ax}: injected {q['injected']:.4f}, LinuxCNC {q['linuxcnc']:.4f} +- {q['U']:.4f}, "
                  f"VM {q['vm']:.4f} +- {q['U_vm']:.4f} um/mm")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
