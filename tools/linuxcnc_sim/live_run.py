#!/usr/bin/python3
"""The live TALC loop driving LinuxCNC (issue 31 item 4): campaign run follows the LOG LinuxCNC
writes, its offsets move LinuxCNC's axes through the external offsets, its wait paces the cycle.

Usage: live_run.py --probeloop build/cli/probeloop --work DIR [--cycles 12] [--hours 24]
                   [--cycle-time-scale 10] [--wait-time-scale 900] [--grid-min 30] [--cp-h 3]

1. The hidden truth, thermal this time: probeloop simulate runs the demo's machine (nmv5000,
   examples/truth_campaign.yaml) for --hours with the shipped artifact (a cycle every 7 min) on
   the virtual machine; its truth.json (the apparent location errors of every cycle, relative
   to cycle 1) becomes DIR/trajectory.csv, and its inputs.csv (every 60 s) the recorded inputs.
2. A test variant of linuxcnc_rotary_mill.yaml and the artifact (sphere_run.py's, with
   `cycles: live_interval: true`, --cycles cycles) -> probeloop plan -> the .ngc, which waits on
   HAL analog input 0 and logs each point with the clock of analog input 1.
3. make_config.py --live: sphere_probe.py moves the sphere with the trajectory on a simulated
   clock that runs --wait-time-scale times the wall's while the live loop makes the program wait
   and --cycle-time-scale times otherwise (a cycle of ~26 s is ~4.3 min, as on a real machine); it replays
   the recorded inputs into DIR/lcnc/inputs.csv as that clock passes them (the data logger) and
   publishes the clock on analog input 1. live_offsets.py reads DIR/lcnc/controller.json.
4. probeloop campaign init, then `campaign run --follow --offsets-applied` on the growing LOG and
   inputs (background), LinuxCNC runs the program (run_program.py), then a last
   `campaign run --finished`.
5. DIR/cycles.json: per cycle, the truth applied at its contacts (relative to cycle 1), the
   external offsets in force at its contacts, what the store evaluated, and the loop's
   residual rows; DIR/summary.json. The checks are the caller's (tests/integration/linuxcnc_live.py).
"""
import argparse
import csv
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import run_program  # noqa: E402
import sphere_run  # noqa: E402

NAMES = sphere_run.NAMES
SYS_PY = "/usr/bin/python3"


def trajectory(pl, src, work, hours):
    """The demo machine's thermal truth on the virtual machine -> trajectory.csv, inputs_recorded.csv."""
    vm = os.path.join(work, "vm")
    os.makedirs(vm, exist_ok=True)
    with open(os.path.join(src, "parts/sphere_artifact.yaml")) as f:
        text = f.read()
    art = os.path.join(vm, "artifact.yaml")
    with open(art, "w") as f:
        f.write(text.replace("\n  count: 12\n", f"\n  duration: {hours:g} h\n"))
    machine = os.path.join(src, "parts/machines/nmv5000.yaml")
    subprocess.run([pl, "plan", art, "--machine", machine, "--out", os.path.join(vm, "plan")], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([pl, "simulate", os.path.join(vm, "plan", "sphere_cycle.nc"), "--machine", machine, "--part", art,
                    "--truth", os.path.join(src, "examples/truth_campaign.yaml"), "--out", os.path.join(vm, "run"),
                    "--seed", "1"], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(vm, "run", "truth.json")) as f:
        cycles = json.load(f)["cycles"]
    path = os.path.join(work, "trajectory.csv")
    with open(path, "w", newline="") as f:
        f.write("# the apparent location errors of a virtual-machine run (vm/run/truth.json), relative to its cycle 1\n")
        w = csv.writer(f)
        w.writerow(["time_s"] + NAMES)
        for c in cycles:
            w.writerow([f"{c['time_s']:.3f}"] + [f"{c[n]:.6f}" for n in NAMES])
    return path, os.path.join(vm, "run", "inputs.csv")


def test_variant(src, work, cycles):
    machine, artifact = sphere_run.test_inputs(src, work, cycles, False)
    with open(artifact) as f:
        art = yaml.safe_load(f)
    art["cycles"]["live_interval"] = True
    art["probing"]["approach"] = "0.5 mm"     # the drift stays far below it; each point 0.3 s shorter
    with open(artifact, "w") as f:
        f.write("# test variant written by tools/linuxcnc_sim/live_run.py\n")
        yaml.safe_dump(art, f, sort_keys=False)
    return machine, artifact


def store_rows(store, query):
    db = sqlite3.connect(store)
    try:
        return [dict(zip([d[0] for d in cur.description], r)) for cur in [db.execute(query)] for r in cur.fetchall()]
    finally:
        db.close()


def main(argv=None):
    ap = argparse.ArgumentParser(description="The live TALC loop driving LinuxCNC in simulation.")
    ap.add_argument("--probeloop", required=True)
    ap.add_argument("--source-dir", default=os.path.dirname(os.path.dirname(HERE)))
    ap.add_argument("--work", required=True)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--hours", type=float, default=24.0, help="the truth's trajectory, h of the virtual machine")
    ap.add_argument("--cycle-time-scale", type=float, default=10.0)
    ap.add_argument("--wait-time-scale", type=float, default=900.0)
    ap.add_argument("--grid-min", type=float, default=30.0, help="the prediction grid = the CP's interval, min")
    ap.add_argument("--cp-h", type=float, default=2.5)
    ap.add_argument("--post-interval-h", type=float, default=1.0)
    ap.add_argument("--model-inputs", default="T_caxis_C,T_table_C")
    ap.add_argument("--na", type=int, default=0)
    ap.add_argument("--nb", type=int, default=1)
    ap.add_argument("--ng-measurements", type=int, default=3)
    ap.add_argument("--ng-interval-min", type=float, default=20.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=900.0)
    a = ap.parse_args(argv)
    src, work, pl = os.path.abspath(a.source_dir), os.path.abspath(a.work), os.path.abspath(a.probeloop)
    os.makedirs(work, exist_ok=True)
    os.chmod(work, 0o755)
    traj, recorded_inputs = trajectory(pl, src, work, a.hours)
    machine, artifact = test_variant(src, work, a.cycles)
    plan, lc = os.path.join(work, "plan"), os.path.join(work, "lcnc")
    subprocess.run([pl, "plan", artifact, "--machine", machine, "--out", plan], check=True, stdout=subprocess.DEVNULL)
    if os.path.exists(lc):
        for n in os.listdir(lc):
            os.remove(os.path.join(lc, n))
    controller = os.path.join(lc, "controller.json")
    subprocess.run([SYS_PY, os.path.join(HERE, "make_config.py"), "--machine", machine,
                    "--manifest", os.path.join(plan, "plan.json"), "--truth", traj, "--out", lc,
                    "--time-scale", str(a.cycle_time_scale), "--wait-time-scale", str(a.wait_time_scale),
                    "--live", controller, "--inputs-source", recorded_inputs, "--seed", str(a.seed),
                    "--linear-accel", "5000", "--angular-accel", "3600"], check=True, stdout=subprocess.DEVNULL)
    store = os.path.join(work, "live.campaign")
    if os.path.exists(store):
        os.remove(store)
    subprocess.run([pl, "campaign", "init", store, "--manifest", os.path.join(plan, "plan.json")], check=True,
                   stdout=subprocess.DEVNULL)
    log, inputs = os.path.join(lc, "sphere_probe.log"), os.path.join(lc, "inputs.csv")
    for p in (log, inputs):          # campaign run wants them to exist; LinuxCNC and the logger truncate them
        open(p, "w").close()
    talc = ["--cp-h", str(a.cp_h), "--post-interval-h", str(a.post_interval_h), "--grid-s", str(a.grid_min * 60),
            "--model-inputs", a.model_inputs, "--na", str(a.na), "--nb", str(a.nb),
            "--ng-measurements", str(a.ng_measurements), "--ng-interval-min", str(a.ng_interval_min),
            "--update-interval-h", "0"]
    # Not --offsets-applied: LinuxCNC's #5061-#5063 (motion's probed position) include the external
    # offsets in force, so the LOG holds the uncompensated error (docs/linuxcnc.md, "The live loop").
    follow_out = open(os.path.join(work, "campaign_run.out"), "w")
    follower = subprocess.Popen([pl, "campaign", "run", store, "--log", log, "--inputs", inputs, "--follow",
                                 "--poll-s", "0.1", "--controller-file", controller,
                                 "--html", os.path.join(work, "dashboard.html")] + talc,
                                stdout=follow_out, stderr=subprocess.STDOUT)
    t0 = time.monotonic()
    try:
        ok, result = run_program.run(lc, os.path.join(plan, "sphere_cycle.ngc"), timeout=a.timeout)
    finally:
        follower.send_signal(signal.SIGTERM)
        try:
            follower.wait(timeout=60)
        except subprocess.TimeoutExpired:
            follower.kill()
            follower.wait()
        follow_out.close()
    wall = time.monotonic() - t0
    fin = subprocess.run([pl, "campaign", "run", store, "--log", log, "--inputs", inputs, "--finished",
                          "--controller-file", controller] + talc, capture_output=True, text=True)
    with open(os.path.join(work, "campaign_run.out"), "a") as f:
        f.write("\n--- campaign run --finished ---\n" + fin.stdout + fin.stderr)

    # What each cycle met at its contacts, and what the store made of it.
    events = [json.loads(line) for line in open(os.path.join(lc, "contacts.jsonl"))]
    contacts = [e for e in events if e["event"] == "contact"]
    per_cycle = {}
    for e in contacts:
        per_cycle.setdefault(e["cycle"], []).append(e)
    ref = None
    cycles = []
    for k in sorted(per_cycle):
        cs = per_cycle[k]
        mean = {n: sum(c["errors"][n] for c in cs) / len(cs) for n in NAMES}
        if ref is None:
            ref = mean
        cycles.append({"cycle": k, "contacts": len(cs), "sim_s": sum(c["sim_s"] for c in cs) / len(cs),
                       "truth": {n: mean[n] - ref[n] for n in NAMES},
                       "truth_span": {n: max(c["errors"][n] for c in cs) - min(c["errors"][n] for c in cs) for n in NAMES},
                       "eoffset_um": [[v * 1000.0 for v in c["eoffset_mm"]] for c in cs]})
    # The program's frame: each logged point minus the external offset in force at its contact (the
    # n-th contact is the n-th PT line), i.e. what the program commanded when the probe touched:
    # evaluated, the error the compensated machine makes, measured.
    pf_log, pf_eval = os.path.join(work, "program_frame.log"), os.path.join(work, "eval_program_frame")
    with open(log) as f:
        lines = [line for line in f if line.startswith("PT ")]
    with open(pf_log, "w") as f:
        # n-th contact = n-th PT line; the caller checks that the counts agree (summary.json)
        for line, c in zip(lines, contacts):
            t = line.split()
            xyz = [float(v) - o for v, o in zip(t[4:7], c["eoffset_mm"])]
            f.write(" ".join(t[:4] + [f"{v:.6f}" for v in xyz] + t[7:]) + "\n")
    pf = subprocess.run([pl, "evaluate", pf_log, "--format", "linuxcnc", "--manifest", os.path.join(plan, "plan.json"),
                         "--out", pf_eval], capture_output=True, text=True)
    raw = subprocess.run([pl, "evaluate", log, "--format", "linuxcnc", "--manifest", os.path.join(plan, "plan.json"),
                          "--out", os.path.join(work, "eval")], capture_output=True, text=True)
    stored = store_rows(store, "SELECT * FROM cycles ORDER BY cycle")
    errors = {}
    exp = subprocess.run([pl, "campaign", "export", store, "--out", os.path.join(work, "export")],
                         capture_output=True, text=True)
    ep = os.path.join(work, "export", "errors.csv")
    if exp.returncode == 0 and os.path.exists(ep):
        with open(ep) as f:
            for r in csv.DictReader(line for line in f if not line.startswith("#")):
                errors[int(r["cycle"])] = r
    residuals = store_rows(store, "SELECT * FROM residuals ORDER BY rowid")
    talc_events = store_rows(store, "SELECT * FROM talc_events ORDER BY seq")
    ticks = store_rows(store, "SELECT k, applies_s FROM talc_ticks ORDER BY k")
    predictions = store_rows(store, "SELECT k, channel, value FROM predictions")
    cycle_time = {r["cycle"]: r["time_s"] for r in stored}
    for c in cycles:
        c["evaluated"] = errors.get(c["cycle"])
        c["residuals"] = [r for r in residuals if r.get("cycle") == c["cycle"]]
        # The prediction the loop had issued by the cycle's time (its points' mean): the offsets
        # LinuxCNC should have applied while it ran.
        t = cycle_time.get(c["cycle"])
        ks = [tk["k"] for tk in ticks if t is not None and tk["applies_s"] <= t
              and any(p["k"] == tk["k"] for p in predictions)]
        c["in_effect"] = {"k": ks[-1], "values": {p["channel"]: p["value"] for p in predictions if p["k"] == ks[-1]}} \
            if ks else None
    summary = {"ok": ok, "linuxcnc_wall_s": wall, "messages": result.get("messages"), "cycles_run": len(cycles),
               "contacts": len(contacts), "campaign_run_follow_rc": follower.returncode,
               "stored_cycles": stored, "talc_events": talc_events, "campaign_run_finished_rc": fin.returncode,
               "export_rc": exp.returncode, "export_error": exp.stderr.strip(), "points_logged": len(lines),
               "evaluate_rc": raw.returncode, "evaluate_error": raw.stderr.strip(),
               "evaluate_program_frame_rc": pf.returncode, "evaluate_program_frame_error": pf.stderr.strip()}
    with open(os.path.join(work, "cycles.json"), "w") as f:
        json.dump(cycles, f, indent=1)
    with open(os.path.join(work, "summary.json"), "w") as f:
        json.dump(summary, f, indent=1)
    print(f"LinuxCNC live loop: {'ran' if ok else 'FAILED'} {len(cycles)} cycles in {wall:.1f} s wall; "
          f"{len(talc_events)} TALC events; campaign run --finished exit {fin.returncode}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
