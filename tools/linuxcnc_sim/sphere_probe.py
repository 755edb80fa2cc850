#!/usr/bin/python3
"""A touch probe that touches a drifting virtual sphere: a userspace HAL component.

It reads the joint feedback (x-fb, y-fb, z-fb: gauge line, mm; c-fb: deg) and the tool in the
spindle, and publishes the centre of the virtual sphere in the gauge-line frame (sphere-x/y/z:
the centre plus the probe length in Z, so the servo-thread chain |joint - sphere| compares the
stylus-tip centre with the sphere centre) and the contact radius R_sphere + r_tip - noise.

The sphere: the artifact's nominal centre on the C table from the plan manifest, at the angle
angle_at_c0 -/+ C (clockwise / counterclockwise positive C), moved by the rigid location errors
of the C axis (docs/location-errors.md section 3, the first-order rigid motion):
    dx = EX0C + ER0T cos t + EC0C R sin t,  dy = EY0C + ER0T sin t - EC0C R cos t,
    dz = EZ0T + R (EA0C sin t - EB0C cos t)
taken from a rigid_location_truth YAML (examples/truth_rigid.yaml), piecewise linear in time and
extrapolated with its last slope, on a clock that runs --time-scale times faster than the wall
(60: one hour in one minute). The errors are sampled when the probe is loaded (the cycle's
T<probe> M6) and held for the cycle ("per_cycle"). The truth's probe_noise (1 sigma along the
approach) is a new normal draw of the contact radius after each contact (seeded).

--trigger rt: the contact itself is decided in the servo thread (sum2, hypot, comp; see sim.hal);
this component only moves the sphere. --trigger python: this component also decides the contact
in its own poll loop (--poll-ms) and drives probe-out; motion sees it late (the latency measured
in docs/linuxcnc.md).

--record FILE: one JSON line per probe load (cycle, clock, the errors applied), per contact
(the feedback at the rising edge of probe-in, the centre and radius in force, motion's
motion-type) and per intrusion: the stylus-tip ball deeper than --intrusion-mm inside the sphere
(the contact radius R_sphere + r_tip, no noise), from the poll where it went in to the poll where
it came out: its deepest point, the depth and every motion.motion-type seen meanwhile (5 =
probing; 1 traverse, 2 feed, 3 arc, 4 tool change, 6 indexing rotary). A probing move stops
within micrometres of the contact; an intrusion during any other move is a collision the
controller did not see. Only the tip ball is modelled, not the stylus shaft or the probe body.
Every event carries "t", CLOCK_MONOTONIC in s (the display's per-program times use the same clock).
A contact also carries the simulated clock, the errors in force and the external offsets in force
(x/y/z-eoffset, fed from axis.L.eoffset).

For the live loop (make_config.py --live, live_run.py): --truth may be a .csv trajectory (time_s
and the seven errors, from a virtual-machine run); --clock-from start runs the simulated clock
from this component's start, at --wait-time-scale while the live loop makes the program wait
(the wait-s pin, live_offsets.py's, is > 0) and at --time-scale otherwise (a cycle), and
publishes it on clock-s (-> motion.analog-in-01, which the live program logs with each point);
--sample per_point moves the sphere with the clock at every moment; --inputs-source replays a
recorded inputs CSV into --inputs-out as the clock passes each row's time_s (the data logger).
"""
import argparse
import bisect
import csv
import json
import math
import random
import re
import signal
import sys
import time

import hal
import yaml

NAMES = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]
TIME = {"s": 1.0, "min": 60.0, "h": 3600.0}


def seconds(v):
    if isinstance(v, (int, float)):
        return float(v)
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*(s|min|h)?\s*", str(v))
    if not m:
        raise SystemExit(f"sphere_probe: cannot read the time '{v}'")
    return float(m.group(1)) * TIME[m.group(2) or "s"]


def small_length_um(v):
    if isinstance(v, (int, float)):
        return float(v)
    m = re.fullmatch(r"\s*([-+0-9.eE]+)\s*(um|mm)?\s*", str(v))
    if not m:
        raise SystemExit(f"sphere_probe: cannot read the length '{v}'")
    return float(m.group(1)) * (1000.0 if m.group(2) == "mm" else 1.0)


class Truth:
    """rigid_location_truth: piecewise-linear location errors, extrapolated with the last slope.
    A .csv file is a trajectory instead (live_run.py writes one from a virtual-machine run):
    time_s and the seven errors per row, linear between rows and held beyond the last (its probe
    noise: --trajectory-noise-um)."""

    def __init__(self, path, trajectory_noise_um=0.25):
        if path.endswith(".csv"):
            with open(path) as f:
                rows = [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]
            self.knots = [(float(r["time_s"]), [float(r[n]) for n in NAMES]) for r in rows]
            self.knots.append((self.knots[-1][0] + 1.0, self.knots[-1][1]))   # held, not extrapolated
            self.noise_um = trajectory_noise_um
            return
        with open(path) as f:
            doc = yaml.safe_load(f)
        if doc.get("kind") != "rigid_location_truth":
            raise SystemExit(f"sphere_probe: {path}: kind must be rigid_location_truth (examples/truth_rigid.yaml)")
        self.knots = sorted((seconds(k["time"]), [float(k.get(n, 0.0)) for n in NAMES]) for k in doc["location_errors"])
        self.noise_um = small_length_um(doc.get("probe_noise", 0))

    def at(self, t):
        k = self.knots
        if len(k) == 1:
            return dict(zip(NAMES, k[0][1]))
        i = bisect.bisect_left(self.times(), t) - 1
        i = min(max(i, 0), len(k) - 2)
        (t0, v0), (t1, v1) = k[i], k[i + 1]
        w = (t - t0) / (t1 - t0)
        return {n: a + w * (b - a) for n, a, b in zip(NAMES, v0, v1)}

    def times(self):
        if not hasattr(self, "_times"):
            self._times = [t for t, _ in self.knots]
        return self._times


class InputsLogger:
    """The data logger of the live loop: the rows of a recorded inputs CSV (a virtual-machine
    run's inputs.csv), appended to the output as the simulated clock passes their time_s."""

    def __init__(self, source, out):
        with open(source) as f:
            lines = f.read().splitlines()
        head = 0
        while head < len(lines) and (lines[head].startswith("#") or not lines[head].strip()):
            head += 1
        self.rows = [(float(line.split(",", 1)[0]), line) for line in lines[head + 1:] if line.strip()]
        self.next = 0
        self.f = open(out, "w", buffering=1)
        self.f.write("\n".join(lines[:head + 1]) + "\n")

    def advance(self, sim_s):
        chunk = []
        while self.next < len(self.rows) and self.rows[self.next][0] <= sim_s:
            chunk.append(self.rows[self.next][1])
            self.next += 1
        if chunk:
            self.f.write("\n".join(chunk) + "\n")   # whole lines: a reader never sees a torn row


def main():
    ap = argparse.ArgumentParser(fromfile_prefix_chars="@")   # make_config.py passes an @file
    ap.add_argument("--name", default="pl_sphere")
    ap.add_argument("--manifest", required=True)
    ap.add_argument("--truth", required=True)
    ap.add_argument("--probe-tool", type=int, required=True)
    ap.add_argument("--probe-length", type=float, required=True, help="gauge line to stylus-tip centre, mm")
    ap.add_argument("--time-scale", type=float, default=60.0, help="simulated s per wall s")
    ap.add_argument("--wait-time-scale", type=float, default=0.0,
                    help="simulated s per wall s while the live loop makes the program wait (the wait-s pin > 0); "
                         "0: --time-scale always")
    ap.add_argument("--sample", choices=["per_cycle", "per_point"], default="per_cycle",
                    help="per_cycle: the errors sampled at the probe load and held; per_point: at every moment")
    ap.add_argument("--clock-from", choices=["first-load", "start"], default="first-load",
                    help="the simulated clock's zero: the first probe load, or this component's start")
    ap.add_argument("--trajectory-noise-um", type=float, default=0.25,
                    help="probe noise (1 sigma) with a .csv trajectory as the truth")
    ap.add_argument("--inputs-source", default="", help="recorded inputs CSV, replayed on the simulated clock")
    ap.add_argument("--inputs-out", default="", help="where the replayed inputs are appended (the data logger's file)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--trigger", choices=["rt", "python"], default="rt")
    ap.add_argument("--poll-ms", type=float, default=1.0)
    ap.add_argument("--no-noise", action="store_true")
    ap.add_argument("--record", default="")
    ap.add_argument("--intrusion-mm", type=float, default=0.05,
                    help="depth inside the contact radius recorded as an intrusion (a probing stop is ~0.01 mm)")
    a = ap.parse_args()

    with open(a.manifest) as f:
        man = json.load(f)
    if man.get("kind") != "sphere_artifact":
        raise SystemExit(f"sphere_probe: {a.manifest} is not a sphere-artifact plan")
    m, art, probe = man["machine"], man["artifact"], man["probe"]
    cw = bool(m["c_positive_is_clockwise"])
    f0 = man["features"][0]
    angle_at_c0 = f0["angle_deg"] + (f0["c_deg"] if cw else -f0["c_deg"])
    R = art["radius_from_axis_mm"]
    cx0, cy0 = m["c_axis_centre_mm"]
    zc = art["sphere_centre_height_mm"]
    contact_r = art["sphere_radius_mm"] + probe["tip_radius_mm"]
    truth = Truth(a.truth, a.trajectory_noise_um)
    noise_mm = 0.0 if a.no_noise else truth.noise_um * 1e-3
    rng = random.Random(a.seed)
    FAR = 1.0e6

    c = hal.component(a.name)
    for p in ("x-fb", "y-fb", "z-fb", "c-fb"):
        c.newpin(p, hal.HAL_FLOAT, hal.HAL_IN)
    c.newpin("tool-number", hal.HAL_S32, hal.HAL_IN)
    c.newpin("probe-in", hal.HAL_BIT, hal.HAL_IN)
    c.newpin("motion-type", hal.HAL_S32, hal.HAL_IN)
    for p in ("sphere-x", "sphere-y", "sphere-z", "contact-radius"):
        c.newpin(p, hal.HAL_FLOAT, hal.HAL_OUT)
    c.newpin("probe-out", hal.HAL_BIT, hal.HAL_OUT)
    c.newpin("cycle", hal.HAL_S32, hal.HAL_OUT)
    c.newpin("clock-s", hal.HAL_FLOAT, hal.HAL_OUT)      # the simulated clock (the inputs' time_s)
    c.newpin("wait-s", hal.HAL_FLOAT, hal.HAL_IN)        # the wait the live loop asks for (live_offsets.py)
    for p in ("x-eoffset", "y-eoffset", "z-eoffset"):    # the external offsets in force (recorded)
        c.newpin(p, hal.HAL_FLOAT, hal.HAL_IN)
    c["sphere-z"] = FAR
    c["contact-radius"] = contact_r
    c.ready()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    rec = open(a.record, "a", buffering=1) if a.record else None

    t_first = time.monotonic() if a.clock_from == "start" else None
    sim_clock, t_prev = 0.0, None              # integrated: the rate differs with and without the probe
    logger = InputsLogger(a.inputs_source, a.inputs_out) if a.inputs_source else None
    cycle = 0
    err = dict.fromkeys(NAMES, 0.0)
    radius = contact_r - noise_mm * rng.gauss(0.0, 1.0)
    loaded_prev = False
    probe_prev = False
    redraw = False
    intrusion = None                             # the tip ball inside the sphere, being tracked
    period = a.poll_ms * 1e-3
    next_t = time.monotonic()
    while not stop:
        loaded = c["tool-number"] == a.probe_tool
        now = time.monotonic()
        if t_first is None and loaded:
            t_first = now
        if t_first is not None:
            if t_prev is not None:
                waiting = a.wait_time_scale > 0 and c["wait-s"] > 0
                rate = a.wait_time_scale if waiting else a.time_scale
                sim_clock += (now - t_prev) * rate
            t_prev = now
        c["clock-s"] = sim_clock
        if logger:
            logger.advance(sim_clock)
        if a.sample == "per_point" and t_first is not None:
            err = truth.at(sim_clock)
        if loaded and not loaded_prev:           # the cycle's probe load: sample the truth and hold it
            cycle += 1
            sim_s = sim_clock
            err = truth.at(sim_s)
            c["cycle"] = cycle
            if rec:
                rec.write(json.dumps({"event": "load", "t": now, "cycle": cycle, "wall_s": now - t_first, "sim_s": sim_s,
                                      "errors": err}) + "\n")
        loaded_prev = loaded
        cdeg = c["c-fb"]
        t = math.radians(angle_at_c0 - cdeg if cw else angle_at_c0 + cdeg)
        ct, st = math.cos(t), math.sin(t)
        ea, eb, ec = err["EA0C_urad"] * 1e-6, err["EB0C_urad"] * 1e-6, err["EC0C_urad"] * 1e-6
        dx = (err["EX0C_um"] + err["ER0T_um"] * ct) * 1e-3 + ec * R * st
        dy = (err["EY0C_um"] + err["ER0T_um"] * st) * 1e-3 - ec * R * ct
        dz = err["EZ0T_um"] * 1e-3 + R * (ea * st - eb * ct)
        sx, sy = cx0 + R * ct + dx, cy0 + R * st + dy
        sz = zc + dz + a.probe_length if loaded else FAR   # gauge-line frame; no probe, no contact
        c["sphere-x"], c["sphere-y"], c["sphere-z"] = sx, sy, sz
        c["contact-radius"] = radius
        x, y, z = c["x-fb"], c["y-fb"], c["z-fb"]
        if a.trigger == "python":
            c["probe-out"] = math.sqrt((x - sx) ** 2 + (y - sy) ** 2 + (z - sz) ** 2) < radius
        pin = c["probe-in"]
        if pin and not probe_prev and rec:
            rec.write(json.dumps({"event": "contact", "t": time.monotonic(), "cycle": cycle, "fb": [x, y, z, cdeg],
                                  "centre_tip_frame": [sx, sy, sz - a.probe_length], "radius": radius,
                                  "motion_type": c["motion-type"], "sim_s": sim_clock, "errors": err,
                                  "eoffset_mm": [c["x-eoffset"], c["y-eoffset"], c["z-eoffset"]]}) + "\n")
        depth = contact_r - math.sqrt((x - sx) ** 2 + (y - sy) ** 2 + (z - sz) ** 2) if loaded else -FAR
        if depth > a.intrusion_mm:
            if intrusion is None:
                intrusion = {"event": "intrusion", "t": time.monotonic(), "cycle": cycle, "depth_mm": depth,
                             "deepest_fb": [x, y, z, cdeg], "motion_types": []}
            if depth > intrusion["depth_mm"]:
                intrusion["depth_mm"], intrusion["deepest_fb"] = depth, [x, y, z, cdeg]
            if c["motion-type"] not in intrusion["motion_types"]:
                intrusion["motion_types"].append(c["motion-type"])
        elif intrusion is not None:
            intrusion["t_end"] = time.monotonic()
            if rec:
                rec.write(json.dumps(intrusion) + "\n")
            intrusion = None
        if probe_prev and not pin:              # released: the next contact gets a new noise draw
            redraw = True
        if redraw and math.sqrt((x - sx) ** 2 + (y - sy) ** 2 + (z - sz) ** 2) > contact_r + 0.05:
            radius = contact_r - noise_mm * rng.gauss(0.0, 1.0)   # drawn once the tip is clear
            redraw = False
        probe_prev = pin
        next_t += period
        delay = next_t - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        else:
            next_t = time.monotonic()
    if rec:
        if intrusion is not None:                # still inside when stopped
            intrusion["t_end"] = time.monotonic()
            rec.write(json.dumps(intrusion) + "\n")
        rec.close()


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        pass
    sys.exit(0)
