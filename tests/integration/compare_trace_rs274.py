#!/usr/bin/env python3
"""Our interpreter against LinuxCNC's own: the motion trace of `probeloop simulate --trace`
and rs274's canonical calls for the same LinuxCNC program must command the same moves.

rs274 reports STRAIGHT_TRAVERSE / STRAIGHT_FEED / STRAIGHT_PROBE targets in program
coordinates with the tool length offset of the last USE_TOOL_LENGTH_OFFSET removed (its
G53 moves too: G53 Z500 with a 150 mm offset prints Z 350); the trace gives the gauge line
in machine coordinates. Both are compared as program coordinates (the program zeroes its
work offset), to rs274's 4 decimals. rs274 never trips the probe (its probe moves end at
the target), and every move the planner writes after a probe names all the axes it needs,
so the commanded targets agree move for move.
Usage: compare_trace_rs274.py canon.txt trace.csv
"""
import csv
import re
import sys

canon_file, trace_file = sys.argv[1], sys.argv[2]
num = r"(-?\d+\.\d+)"
ours_kinds = {"rapid": "STRAIGHT_TRAVERSE", "feed": "STRAIGHT_FEED", "cut": "STRAIGHT_FEED",
              "probe_contact": "STRAIGHT_PROBE", "probe_no_contact": "STRAIGHT_PROBE"}

# rs274's moves, each with the tool length offset in force when it was commanded.
theirs, tlo = [], 0.0
for line in open(canon_file):
    m = re.search(r"USE_TOOL_LENGTH_OFFSET\(" + num + " " + num + " " + num, line)
    if m:
        tlo = float(m.group(3))
        continue
    m = re.search(r"(STRAIGHT_TRAVERSE|STRAIGHT_FEED|STRAIGHT_PROBE)\(" + ", ".join([num] * 6), line)
    if m:
        x, y, z, a, b, c = map(float, m.groups()[1:])
        theirs.append((m.group(1), x, y, z, c, tlo))

ours = []
for r in csv.DictReader(open(trace_file)):
    if r["kind"] not in ours_kinds:
        continue
    ours.append((ours_kinds[r["kind"]], float(r["x_mm"]), float(r["y_mm"]), float(r["z_mm"]), float(r["c_deg"]), int(r["line"])))

errors = []
if len(ours) != len(theirs):
    errors.append(f"{len(ours)} moves in the trace, {len(theirs)} in rs274's canonical output")
for i, (o, t) in enumerate(zip(ours, theirs)):
    kind, x, y, z, c, line = o
    z_prog = z - t[5]  # our gauge line less the offset rs274 applied
    if kind != t[0] or abs(x - t[1]) > 1e-4 or abs(y - t[2]) > 1e-4 or abs(z_prog - t[3]) > 1e-4 or abs(c - t[4]) > 1e-4:
        errors.append(f"move {i + 1} (program line {line}): ours {kind} X{x:.4f} Y{y:.4f} Z{z_prog:.4f} C{c:.4f}, "
                      f"rs274 {t[0]} X{t[1]:.4f} Y{t[2]:.4f} Z{t[3]:.4f} C{t[4]:.4f}")
    if len(errors) > 10:
        break
if errors:
    print("\n".join(errors))
    sys.exit(1)
print(f"{len(ours)} moves agree with rs274 (kind, X, Y, Z, C to 1e-4 mm)")
