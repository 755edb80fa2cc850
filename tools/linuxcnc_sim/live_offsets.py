#!/usr/bin/python3
"""The controller side of the live loop on LinuxCNC: a userspace HAL component (pl_live).

`probeloop campaign run --controller-file F.json` replaces F.json atomically after every pass
(docs/live_loop.md, "The controller interface"):
    {"time_s": ..., "phase": ..., "wait_s": ..., "compensation": {"EX0C_um": ..., ...} | null}
This component reads it whenever it changes and drives LinuxCNC with it:

- external offsets (axis.L.eoffset-counts, L = x, y, z; eoffset-scale --scale-mm per count):
  the offsets of seed 004 Eqs. 6.3-6.5 as derived in geometry/compensation_offsets.hpp (B = 0),
  evaluated at the stylus tip's commanded position r from the C axis at the height where the
  errors were measured (the sphere centres'):
      X = EX0C + ER0T r_x/(d/2) + EB0C r_z + EC0C r_y
      Y = EY0C + ER0T r_y/(d/2) - EA0C r_z - EC0C r_x
      Z = EZ0T + EA0C r_y - EB0C r_x            (um; angles in urad times r in mm give nm)
  so that the tool follows the displaced table. The tip is the gauge line (axis.L.pos-cmd minus
  the external offset in force) minus the probe length in Z. Refreshed every --period-ms, so the
  offset follows the tool across the table; C is not offset (as in the thesis).
- the wait: motion.analog-in-00 = the seconds the cycle program should still wait, on LinuxCNC's
  clock: (time_s + wait_s - now) / --wait-time-scale, where now is the clock-s pin (the inputs
  logger's clock; in the simulation sphere_probe.py's simulated clock, which runs
  --wait-time-scale times the wall's between cycles). 0 when nothing is due or nothing was read.

--record FILE: one JSON line per controller-file change (what was read, with the clock) and
one per change of the counts written.
On a real machine: the same component, with clock-s fed from a HAL clock of the inputs logger's
time base and --wait-time-scale 1 (docs/linuxcnc.md, "On a real LinuxCNC machine").
"""
import argparse
import json
import math
import os
import signal
import sys
import time

import hal

NAMES = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]


def offsets_um(comp, r, half_d):
    """geometry/compensation_offsets.hpp at B = 0: the displacement of the table point r (mm from
    the C axis, z from the sphere centres' height) under the location errors, um."""
    ex, ey, ez, er, ea, eb, ec = (comp.get(n, 0.0) for n in NAMES)
    rx, ry, rz = r
    return (ex + er * rx / half_d + (eb * rz + ec * ry) * 1e-3,
            ey + er * ry / half_d + (-ea * rz - ec * rx) * 1e-3,
            ez + (ea * ry - eb * rx) * 1e-3)


def main():
    ap = argparse.ArgumentParser(fromfile_prefix_chars="@")   # make_config.py passes an @file
    ap.add_argument("--name", default="pl_live")
    ap.add_argument("--manifest", required=True, help="the sphere-artifact plan.json (C axis, sphere height, d/2)")
    ap.add_argument("--controller-file", required=True)
    ap.add_argument("--probe-length", type=float, required=True, help="gauge line to stylus-tip centre, mm")
    ap.add_argument("--scale-mm", type=float, default=0.0001, help="axis.L.eoffset-scale: mm per count")
    ap.add_argument("--wait-time-scale", type=float, default=1.0, help="clock s per LinuxCNC s between cycles")
    ap.add_argument("--period-ms", type=float, default=5.0)
    ap.add_argument("--record", default="")
    a = ap.parse_args()
    with open(a.manifest) as f:
        man = json.load(f)
    if man.get("kind") != "sphere_artifact":
        raise SystemExit(f"live_offsets: {a.manifest} is not a sphere-artifact plan")
    cx, cy = man["machine"]["c_axis_centre_mm"]
    zc = man["artifact"]["sphere_centre_height_mm"]
    half_d = man["artifact"]["radius_from_axis_mm"]

    c = hal.component(a.name)
    c.newpin("clock-s", hal.HAL_FLOAT, hal.HAL_IN)
    for n in "xyz":
        c.newpin(f"{n}-cmd", hal.HAL_FLOAT, hal.HAL_IN)       # axis.L.pos-cmd (with the offset in force)
        c.newpin(f"{n}-eoffset", hal.HAL_FLOAT, hal.HAL_IN)   # axis.L.eoffset
        c.newpin(f"{n}-counts", hal.HAL_S32, hal.HAL_OUT)     # -> axis.L.eoffset-counts
    c.newpin("wait-s", hal.HAL_FLOAT, hal.HAL_OUT)            # -> motion.analog-in-00
    c.newpin("compensating", hal.HAL_BIT, hal.HAL_OUT)
    c.ready()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    rec = open(a.record, "a", buffering=1) if a.record else None
    stamp, doc = None, None
    counts_prev = None
    period = a.period_ms * 1e-3
    while not stop:
        try:
            st = os.stat(a.controller_file)
            if (st.st_mtime_ns, st.st_size, st.st_ino) != stamp:
                with open(a.controller_file) as f:
                    doc = json.load(f)           # replaced atomically by campaign run: never torn
                stamp = (st.st_mtime_ns, st.st_size, st.st_ino)
                if rec:
                    rec.write(json.dumps({"event": "controller_file", "t": time.monotonic(), "clock_s": c["clock-s"],
                                          **doc}) + "\n")
        except FileNotFoundError:
            pass
        except (OSError, ValueError) as ex:      # a file that is not the loop's: say so, keep the last one
            if rec:
                rec.write(json.dumps({"event": "unreadable", "t": time.monotonic(), "error": str(ex)}) + "\n")
            stamp = None
        comp = (doc or {}).get("compensation")
        if comp:
            tip = [c[f"{n}-cmd"] - c[f"{n}-eoffset"] for n in "xyz"]
            r = (tip[0] - cx, tip[1] - cy, tip[2] - a.probe_length - zc)
            counts = [int(round(v * 1e-3 / a.scale_mm)) for v in offsets_um(comp, r, half_d)]
        else:
            counts = [0, 0, 0]
        for n, v in zip("xyz", counts):
            c[f"{n}-counts"] = v
        c["compensating"] = bool(comp)
        if rec and counts != counts_prev:
            rec.write(json.dumps({"event": "counts", "t": time.monotonic(), "clock_s": c["clock-s"],
                                  "counts": counts}) + "\n")
        counts_prev = counts
        wait = 0.0
        if doc and doc.get("wait_s") is not None:
            wait = max(0.0, doc["time_s"] + doc["wait_s"] - c["clock-s"]) / a.wait_time_scale
        c["wait-s"] = wait if math.isfinite(wait) else 0.0
        time.sleep(period)
    if rec:
        rec.close()


if __name__ == "__main__":
    try:
        main()
    except KeyboardInterrupt:
        pass
    except Exception:  # noqa: BLE001 - LinuxCNC drops a userspace component's stderr: keep why it died
        import traceback
        with open("live_offsets.crash", "w") as f:
            traceback.print_exc(file=f)
        raise
    sys.exit(0)
