#!/usr/bin/python3
"""The sphere cycle end to end on LinuxCNC in simulation, against a drifting virtual sphere.

Usage: sphere_run.py --probeloop build/cli/probeloop --work DIR [--cycles 3] [--trigger rt|python]
                     [--servo-period-ns 100000] [--time-scale 60] [--seed 1] [--no-noise] [--as-shipped]

1. A test variant of parts/machines/linuxcnc_rotary_mill.yaml and parts/sphere_artifact.yaml
   (DIR/machine.yaml, DIR/artifact.yaml): --cycles cycles 5 s apart, rapids and axis feeds
   20 m/min, C at 60 rpm, positioning feed 5 m/min, approach 1.5 mm, so that three cycles take
   about 1.5 min of wall time; the probing feed stays the artifact's (200 mm/min).
   --as-shipped keeps both files as shipped (only the cycle count and gap change).
2. probeloop plan -> DIR/plan/sphere_cycle.ngc, plan.json.
3. make_config.py -> DIR/lcnc (INI, HAL, tool table); run_program.py runs the program there:
   LinuxCNC writes DIR/lcnc/sphere_probe.log, sphere_probe.py writes DIR/lcnc/contacts.jsonl.
4. DIR/truth.json: the errors the component applied per cycle, relative to cycle 1 (what
   evaluate reports); probeloop evaluate -> DIR/eval/errors.csv.
5. Per contact, the overshoot: how far beyond the contact (R_sphere + r_tip - noise from the
   centre in force) LinuxCNC recorded #5061-#5063, in um and in ms at the probing feed.
Prints a summary and writes DIR/summary.json. Exit status 0 if LinuxCNC ran the program;
the comparison with the truth is left to the caller (tests/integration/linuxcnc_sim.py).
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import run_program  # noqa: E402

NAMES = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]


def test_inputs(src, work, cycles, as_shipped):
    with open(os.path.join(src, "parts/machines/linuxcnc_rotary_mill.yaml")) as f:
        machine = yaml.safe_load(f)
    with open(os.path.join(src, "parts/sphere_artifact.yaml")) as f:
        art = yaml.safe_load(f)
    art["cycles"]["count"] = cycles
    art["cycles"]["gap"] = "5 s"
    if not as_shipped:
        for n in "XYZ":
            machine["axes"][n]["max_feed"] = "20000 mm/min"
        machine["rapid_feed"] = "20000 mm/min"
        machine["axes"]["C"]["max_speed"] = "60 rpm"
        art["probing"]["positioning_feed"] = "5000 mm/min"
        art["probing"]["approach"] = "1.5 mm"
    paths = os.path.join(work, "machine.yaml"), os.path.join(work, "artifact.yaml")
    for p, doc in zip(paths, (machine, art)):
        with open(p, "w") as f:
            f.write("# test variant written by tools/linuxcnc_sim/sphere_run.py\n")
            yaml.safe_dump(doc, f, sort_keys=False)
    return paths


def read_log(path):
    rows = []
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "PT":
                rows.append({"cycle": int(float(t[1])), "position": int(float(t[2])), "point": int(float(t[3])),
                             "xyz": [float(v) for v in t[4:7]]})
    return rows


def overshoots(log_rows, contacts, feed_mm_min):
    """Distance beyond the contact at which LinuxCNC recorded each point, um (the n-th contact
    event of the component is the n-th PT line)."""
    out = []
    for row, c in zip(log_rows, contacts):
        d = math.dist(row["xyz"], c["centre_tip_frame"])
        um = (c["radius"] - d) * 1000.0
        out.append({"cycle": row["cycle"], "position": row["position"], "point": row["point"],
                    "overshoot_um": um, "latency_ms": um / (feed_mm_min / 60.0)})
    return out


def stats(v):
    if not v:
        return {}
    m = sum(v) / len(v)
    sd = math.sqrt(sum((x - m) ** 2 for x in v) / max(len(v) - 1, 1))
    return {"n": len(v), "mean": m, "sd": sd, "min": min(v), "max": max(v)}


def main(argv=None):
    ap = argparse.ArgumentParser(description="The sphere cycle on LinuxCNC in simulation.")
    ap.add_argument("--probeloop", required=True)
    ap.add_argument("--source-dir", default=os.path.dirname(os.path.dirname(HERE)))
    ap.add_argument("--work", required=True)
    ap.add_argument("--cycles", type=int, default=3)
    ap.add_argument("--trigger", choices=["rt", "python"], default="rt")
    ap.add_argument("--servo-period-ns", type=int, default=100000)
    ap.add_argument("--time-scale", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--truth", default="")
    ap.add_argument("--no-noise", action="store_true")
    ap.add_argument("--as-shipped", action="store_true")
    ap.add_argument("--timeout", type=float, default=400.0)
    a = ap.parse_args(argv)
    src, work = os.path.abspath(a.source_dir), os.path.abspath(a.work)
    truth = a.truth or os.path.join(src, "examples/truth_rigid.yaml")
    os.makedirs(work, exist_ok=True)
    os.chmod(work, 0o755)   # LinuxCNC's user (run_program.py) works in work/lcnc
    machine, artifact = test_inputs(src, work, a.cycles, a.as_shipped)
    plan, lc, ev = os.path.join(work, "plan"), os.path.join(work, "lcnc"), os.path.join(work, "eval")
    subprocess.run([a.probeloop, "plan", artifact, "--machine", machine, "--out", plan], check=True,
                   stdout=subprocess.DEVNULL)
    if os.path.exists(lc):
        for n in os.listdir(lc):
            os.remove(os.path.join(lc, n))
    cfg = [sys.executable if sys.executable.startswith("/usr/bin/") else "/usr/bin/python3",
           os.path.join(HERE, "make_config.py"), "--machine", machine, "--manifest", os.path.join(plan, "plan.json"),
           "--truth", truth, "--out", lc, "--trigger", a.trigger, "--servo-period-ns", str(a.servo_period_ns),
           "--time-scale", str(a.time_scale), "--seed", str(a.seed)]
    if not a.as_shipped:
        cfg += ["--linear-accel", "5000", "--angular-accel", "3600"]
    subprocess.run(cfg, check=True, stdout=subprocess.DEVNULL)
    if a.no_noise:
        with open(os.path.join(lc, "sim.hal")) as f:
            hal_text = f.read()
        with open(os.path.join(lc, "sim.hal"), "w") as f:
            f.write(hal_text.replace("--record contacts.jsonl", "--record contacts.jsonl --no-noise"))
    t0 = time.monotonic()
    ok, result = run_program.run(lc, os.path.join(plan, "sphere_cycle.ngc"), timeout=a.timeout)
    wall = time.monotonic() - t0
    summary = {"ok": ok, "linuxcnc_wall_s": wall, "program_s": result.get("run_s"), "messages": result.get("messages"),
               "trigger": a.trigger, "servo_period_ns": a.servo_period_ns}
    log = os.path.join(lc, "sphere_probe.log")
    if ok and os.path.exists(log):
        events = [json.loads(line) for line in open(os.path.join(lc, "contacts.jsonl"))]
        loads = {e["cycle"]: e for e in events if e["event"] == "load"}
        contacts = [e for e in events if e["event"] == "contact"]
        ref = loads[1]["errors"]
        cycles = [{"cycle": k, "sim_time_s": e["sim_s"], **{n: e["errors"][n] - ref[n] for n in NAMES},
                   "absolute": e["errors"]} for k, e in sorted(loads.items())]
        with open(os.path.join(work, "truth.json"), "w") as f:
            json.dump({"note": "errors applied by sphere_probe.py per cycle, relative to cycle 1", "cycles": cycles}, f,
                      indent=1)
        rows = read_log(log)
        with open(artifact) as f:
            feed = float(str(yaml.safe_load(f)["probing"]["feed"]).split()[0])
        ov = overshoots(rows, contacts, feed)
        summary.update({"points_logged": len(rows), "contacts": len(contacts), "probing_feed_mm_min": feed,
                        "overshoot_um": stats([o["overshoot_um"] for o in ov]),
                        "latency_ms": stats([o["latency_ms"] for o in ov])})
        with open(os.path.join(work, "overshoot.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(ov[0]) if ov else ["cycle"])
            w.writeheader()
            w.writerows(ov)
        r = subprocess.run([a.probeloop, "evaluate", log, "--format", "linuxcnc", "--manifest",
                            os.path.join(plan, "plan.json"), "--out", ev], capture_output=True, text=True)
        summary["evaluate_rc"] = r.returncode
        if r.returncode != 0:
            summary["evaluate_error"] = r.stderr.strip()
    with open(os.path.join(work, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    o, lat = summary.get("overshoot_um", {}), summary.get("latency_ms", {})
    print(f"LinuxCNC ({a.trigger} trigger, servo period {a.servo_period_ns / 1000:.0f} us): "
          f"{'ran' if ok else 'FAILED'} in {wall:.1f} s wall, {summary.get('points_logged', 0)} points logged")
    if o:
        print(f"  overshoot at {summary['probing_feed_mm_min']:.0f} mm/min: mean {o['mean']:.3f} um, sd {o['sd']:.3f} um, "
              f"range {o['min']:.3f} .. {o['max']:.3f} um (latency mean {lat['mean']:.3f} ms, max {lat['max']:.3f} ms)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
