#!/usr/bin/env python3
"""Compare LinuxCNC rs274's canonical output for an emitted program with the plan manifest.

Checks: one STRAIGHT_PROBE per planned point of every cycle, at the planned overtravel end
on the planned approach line (targets to the 4 decimals rs274 prints); one LOG line per
probe with the right cycle/position/point; every C move made at the clearance plane (the
Z of the preceding traverse equals the plane, above the artifact); C positions as planned;
no ABORT reached; the interpreter ran to PROGRAM_END.
Usage: check_rs274.py canon.txt plan.json overtravel_mm clearance_z_mm
"""
import json
import math
import re
import sys

canon_file, plan_file, overtravel, z_clear = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
plan = json.load(open(plan_file))
text = open(canon_file).read()
errors = []

if "PROGRAM_END" not in text:
    errors.append("rs274 did not reach PROGRAM_END")
if "ABORT" in text:
    errors.append("an ABORT was reached")

nums = r"(-?\d+\.\d+)"
probes = [tuple(map(float, m)) for m in re.findall(r"STRAIGHT_PROBE\(" + ", ".join([nums] * 6), text)]
logs = re.findall(r'LOG\("PT ([^"]*)"\)', text)
points = plan["points"]
cycles = plan["schedule"]["cycles"]
# Two probe calls per point: the protected approach (G38.3) and the measuring move (G38.2).
if len(probes) != 2 * len(points) * cycles:
    errors.append(f"{len(probes)} STRAIGHT_PROBE calls, expected {2 * len(points) * cycles}")
if len(logs) != len(points) * cycles:
    errors.append(f"{len(logs)} LOG lines, expected {len(points) * cycles}")

for i, log in enumerate(logs):
    cyc, pos, pt = i // len(points) + 1, points[i % len(points)]["position"], points[i % len(points)]["point"]
    fields = log.split()
    if float(fields[0]) != cyc or int(fields[1]) != pos or int(fields[2]) != pt:
        errors.append(f"LOG {i + 1} is '{log}', expected cycle {cyc} position {pos} point {pt}")
    measuring = probes[2 * i + 1] if 2 * i + 1 < len(probes) else None
    if measuring is None:
        break
    p = points[i % len(points)]
    want = [p["contact_mm"][k] + overtravel * p["approach"][k] for k in range(3)]
    got = measuring[:3]
    if max(abs(g - w) for g, w in zip(got, want)) > 6e-5:
        errors.append(f"probe {i + 1}: target {got}, planned {want}")

# C moves: every traverse that changes C happens at the clearance plane.
traverses = [tuple(map(float, m)) for m in re.findall(r"STRAIGHT_TRAVERSE\(" + ", ".join([nums] * 6), text)]
c_seen = []
prev = None
for t in traverses:
    if prev is not None and abs(t[5] - prev[5]) > 1e-9:
        c_seen.append(t[5])
        if abs(t[2] - z_clear) > 1e-4 or abs(prev[2] - z_clear) > 1e-4:
            errors.append(f"C move to {t[5]} at Z {prev[2]} -> {t[2]}, not at the clearance plane {z_clear}")
    prev = t
planned_c = [s["c_deg"] for s in plan["features"]]
expected_moves = []
last = 0.0
for _ in range(cycles):
    for c in planned_c:
        if abs(c - last) > 1e-9:
            expected_moves.append(c)
        last = c
if [round(c, 3) for c in c_seen] != [round(c, 3) for c in expected_moves]:
    errors.append(f"C moves {c_seen[:8]}..., expected {expected_moves[:8]}...")

if errors:
    print("rs274 check FAILED:")
    for e in errors[:20]:
        print("  " + e)
    sys.exit(1)
print(f"rs274 check ok: {len(probes)} probe calls, {len(logs)} LOG lines, {len(c_seen)} C moves at Z {z_clear}")
