#!/usr/bin/python3
"""Userspace HAL component: the probed surfaces of a machined part on the C table (LinuxCNC sim).

Usage (loadusr from the HAL file written by piece_run.py):
  surface_probe.py --name pl_surf --patches patches.json --probe-tool 99 --probe-length 150
                   [--seed 1] [--record contacts.jsonl]

patches.json (written by piece_run.py) holds one patch per planned point: the surface it probes
(a plane in machine coordinates at the point's C angle: outward normal n and offset n.p), the
nominal tip-centre contact q, the approach direction a, the tip radius, and the scale error
field (um/mm of X and Y: the machine reads x where the tip is at x (1 + s)) and the probe noise.

Each 1 ms the component finds the active patch: the probe tool in the spindle, C at the
patch's angle, and the tip centre within 0.3 mm of the patch's approach line (from 30 mm
before q to 2 mm past it). It publishes that plane to a chain in the servo thread, after
motion-controller:  mult2 (x kx, y ky, z kz) -> sum2 -> sum2 -> sum2 (+ off) = signed
distance of the tip centre from the plane -> comp (contact-radius > distance) ->
motion.probe-input. kx = nx (1 + sx), ky = ny (1 + sy), kz = nz, off = -n.p - nz L (z-fb is
the gauge line, the tip centre is L below it). Without an active patch nothing touches
(k = 0, off = 1e6). The contact radius is the tip radius minus a normal draw of the probe
noise, drawn at each activation. Only the probed patches exist: a collision elsewhere on the
part is not seen (the verifier, `probeloop check`, is what guards the program's moves).
Every activation and contact goes to --record (JSON lines, CLOCK_MONOTONIC times).
"""
import argparse
import json
import math
import random
import signal
import sys
import time

import hal

FAR = 1.0e6
LATERAL_MM = 0.3
BEFORE_MM = 30.0
PAST_MM = 2.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--name", default="pl_surf")
    ap.add_argument("--patches", required=True)
    ap.add_argument("--probe-tool", type=int, required=True)
    ap.add_argument("--probe-length", type=float, required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--record", default="")
    a = ap.parse_args()
    with open(a.patches) as f:
        doc = json.load(f)
    patches = doc["patches"]
    sx, sy = (v * 1e-3 for v in doc.get("scale_um_per_mm", [0.0, 0.0]))
    noise_mm = doc.get("noise_um", 0.0) * 1e-3
    rng = random.Random(a.seed)
    rec = open(a.record, "a", buffering=1) if a.record else None

    def record(ev):
        if rec:
            ev["t"] = time.clock_gettime(time.CLOCK_MONOTONIC)
            rec.write(json.dumps(ev) + "\n")

    c = hal.component(a.name)
    for p in ("x-fb", "y-fb", "z-fb", "c-fb"):
        c.newpin(p, hal.HAL_FLOAT, hal.HAL_IN)
    c.newpin("tool-number", hal.HAL_S32, hal.HAL_IN)
    c.newpin("motion-type", hal.HAL_S32, hal.HAL_IN)
    c.newpin("probe-in", hal.HAL_BIT, hal.HAL_IN)
    for p in ("kx", "ky", "kz", "off", "contact-radius"):
        c.newpin(p, hal.HAL_FLOAT, hal.HAL_OUT)
    c.newpin("active", hal.HAL_S32, hal.HAL_OUT)
    c["off"], c["active"] = FAR, -1
    c.ready()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    active, radius, last_probe = -1, 0.0, False
    L = a.probe_length
    try:
        while not stop:
            x, y, zg = c["x-fb"], c["y-fb"], c["z-fb"]
            t = (x, y, zg - L)
            cdeg = c["c-fb"] % 360.0
            best, best_lat = -1, LATERAL_MM
            if c["tool-number"] == a.probe_tool:
                for i, p in enumerate(patches):
                    dc = abs((cdeg - p["c_deg"] + 180.0) % 360.0 - 180.0)
                    if dc > 1e-3:
                        continue
                    q, ap_ = p["q"], p["a"]
                    d = [t[k] - q[k] for k in range(3)]
                    s = sum(d[k] * ap_[k] for k in range(3))
                    if s < -BEFORE_MM or s > PAST_MM:
                        continue
                    lat = math.sqrt(max(sum(v * v for v in d) - s * s, 0.0))
                    if lat < best_lat:
                        best, best_lat = i, lat
            if best != active:
                if best >= 0:
                    p = patches[best]
                    n = p["n"]
                    draw = rng.gauss(0.0, 1.0) * noise_mm if noise_mm > 0 else 0.0
                    radius = p["r"] - draw
                    # the servo thread may read between two pin writes: the plane is moved far away
                    # first (no contact), then given its normal and radius, then its offset
                    c["off"] = FAR
                    c["kx"], c["ky"], c["kz"] = n[0] * (1 + sx), n[1] * (1 + sy), n[2]
                    c["contact-radius"] = radius
                    c["off"] = -p["d"] - n[2] * L
                    record({"event": "activate", "patch": best, "feature": p["feature"], "position": p["position"],
                            "point": p["point"], "radius": radius, "noise_um": draw * 1e3})
                else:
                    c["off"] = FAR
                    c["kx"] = c["ky"] = c["kz"] = 0.0
                    c["contact-radius"] = 0.0
                active = best
                c["active"] = active
            probe = c["probe-in"]
            if probe and not last_probe:
                record({"event": "contact", "patch": active, "tip": list(t), "c_deg": cdeg,
                        "motion_type": c["motion-type"], "radius": radius})
            last_probe = probe
            time.sleep(0.001)
    finally:
        if rec:
            rec.close()


if __name__ == "__main__":
    sys.exit(main())
