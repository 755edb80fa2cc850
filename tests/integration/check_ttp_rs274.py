#!/usr/bin/env python3
"""Compare LinuxCNC rs274's canonical output of the three thermal-test-piece programs with plan.json.

rs274 (standalone, Debian linuxcnc-uspace) prints canonical positions in program units (mm
after G21) to 4 decimals, as X Y Z A B C of the controlled point without the tool length,
i.e. program = machine tip coordinates here (the programs zero their work offset).

Checks:
  every program: reaches PROGRAM_END, no ABORT reached, no interpreter error;
  pre-machining and test: every finishing cut of the manifest (cuts[] of that program) appears
    as a STRAIGHT_FEED ending at the planned point and C, in the planned order (a cut whose
    from = to is a turn of C: a STRAIGHT_FEED at that point turning C by one full turn);
  test: Z is constant (1e-4 mm) on every motion from the first cutting feed to the last, and
    equals the cuts' Z; the feeds of C alone (the load) come in pairs that leave C where it was
    (incremental +N and -N turns, docs/thermal-test-piece.md §5);
  inspection: every STRAIGHT_PROBE is either a measuring move (a LOG follows) whose target is
    the planned overtravel end on the approach line (contact + overtravel * approach) at the
    planned C, or a protected move that ends at the next measuring move's start (contact -
    approach_mm * approach); every measuring move starts there; one LOG per point in the
    manifest's order with cycle 1 and the right position/point.

The probing distances are not in the manifest: give them (the description's
inspection.probing.overtravel / approach, e.g. --overtravel 2 --approach 3) or they are read off
the first point and every other point must agree.

Usage: check_ttp_rs274.py plan.json CANON CANON CANON [--overtravel MM] [--approach MM]
  (the canonical outputs of the manifest's programs, in its order: pre-machining, test, inspection)
"""
import argparse
import json
import re
import sys

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("plan", help="plan.json of the thermal test piece")
ap.add_argument("canons", nargs=3, metavar="CANON", help="rs274 output of pre-machining, test, inspection")
ap.add_argument("--overtravel", type=float, metavar="MM", help="inspection.probing.overtravel of the description")
ap.add_argument("--approach", type=float, metavar="MM", help="inspection.probing.approach of the description")
args = ap.parse_args()
for name in ("overtravel", "approach"):
    v = getattr(args, name)
    if v is not None and not v > 0:
        ap.error(f"--{name} must be a positive distance in mm (got {v})")
plan = json.load(open(args.plan))
roles = [p.get("role") for p in plan["programs"]]
if roles != ["pre_machining", "test", "inspection"]:
    sys.exit(f"check_ttp_rs274.py: the manifest's programs are {roles}, expected pre_machining, test, inspection")
pre_file, test_file, insp_file = args.canons
overtravel, approach_mm = args.overtravel, args.approach
errors = []
TOL = 6e-5  # rs274 prints 4 decimals; the plan's program coordinates are rounded to 4 as written
CTOL = 6e-4  # C is written with 3 decimals

NUM = r"(-?\d+(?:\.\d+)?)"
MOTION = re.compile(r"\b(STRAIGHT_TRAVERSE|STRAIGHT_FEED|STRAIGHT_PROBE)\(" + ", ".join([NUM] * 6) + r"\)")
LOG = re.compile(r'LOG\("PT ([^"]*)"\)')


def events(path, name):
    """The canonical calls in order: (kind, (x, y, z, a, b, c)) or ('LOG', text)."""
    text = open(path).read()
    if "PROGRAM_END" not in text:
        errors.append(f"{name}: rs274 did not reach PROGRAM_END")
    if "ABORT" in text:
        errors.append(f"{name}: an ABORT was reached")
    for line in text.splitlines():
        if re.search(r"\berror\b|near line", line, re.IGNORECASE) and "COMMENT" not in line:
            errors.append(f"{name}: interpreter error: {line.strip()}")
    out = []
    for line in text.splitlines():
        m = MOTION.search(line)
        if m:
            out.append((m.group(1), tuple(float(v) for v in m.groups()[1:])))
            continue
        m = LOG.search(line)
        if m:
            out.append(("LOG", m.group(1)))
    return out


def close(p, q, tol=TOL):
    return all(abs(a - b) <= tol for a, b in zip(p, q))


def check_cuts(ev, role, name):
    cuts = sorted((c for c in plan["cuts"] if c["program"] == role), key=lambda c: c["start_s"])
    if not cuts:
        errors.append(f"{name}: the manifest lists no cut of program role '{role}'")
        return []
    motions = [(k, v) for k, v in ev if k != "LOG"]
    found, j, prev = [], 0, None
    for cut in cuts:
        to = cut["to_mm"]
        turn = close(cut["from_mm"], to)
        hit = None
        while j < len(motions):
            kind, v = motions[j]
            before = prev
            prev = v
            j += 1
            if kind != "STRAIGHT_FEED" or not close(v[:3], to):
                continue
            if turn:
                if before is not None and abs(abs(v[5] - before[5]) - 360.0) <= CTOL and abs(before[5] - cut["c_deg"]) <= CTOL:
                    hit = j - 1
                    break
            elif abs(v[5] - cut["c_deg"]) <= CTOL:
                hit = j - 1
                break
        if hit is None:
            errors.append(f"{name}: cut {cut['id']} (feature {cut['feature']}) not found as a STRAIGHT_FEED to {to} at C {cut['c_deg']} "
                          f"after the previous cut (planned order)")
            return found
        found.append(hit)
    return found


pre = events(pre_file, "pre-machining")
check_cuts(pre, "pre_machining", "pre-machining")

test = events(test_file, "test")
hits = check_cuts(test, "test", "test")
z_value, n_test_cuts = None, len(hits)
motions = [(k, v) for k, v in test if k != "LOG"]
first_cut = next((i for i, (k, v) in enumerate(motions) if k == "STRAIGHT_FEED" and any(
    c["program"] == "test" and close(v[:3], c["to_mm"]) for c in plan["cuts"])), None)
last_feed = max((i for i, (k, v) in enumerate(motions) if k == "STRAIGHT_FEED"), default=None)
if first_cut is None:
    errors.append("test: no STRAIGHT_FEED ends where a planned cut ends")
else:
    # From the first cutting feed to the last feed of the program (the way back to the waiting
    # position after the last cut), including every traverse of C and the load's C moves.
    z_value = motions[first_cut][1][2]
    for k, v in motions[first_cut:last_feed + 1]:
        if abs(v[2] - z_value) > 1e-4:
            errors.append(f"test: Z {v[2]} on a {k} after the first cut (the cutting height is {z_value})")
            break
    for c in plan["cuts"]:
        if c["program"] == "test" and (abs(c["from_mm"][2] - z_value) > TOL or abs(c["to_mm"][2] - z_value) > TOL):
            errors.append(f"test: cut {c['id']} is planned at Z {c['to_mm'][2]}, the program cuts at Z {z_value}")
# The load: feeds of C alone (X, Y, Z where the motion before left them), forward then back.
c_feeds = [(motions[i - 1][1][5], v[5]) for i, (k, v) in enumerate(motions)
           if i > 0 and k == "STRAIGHT_FEED" and close(v[:3], motions[i - 1][1][:3]) and abs(v[5] - motions[i - 1][1][5]) > CTOL]
if len(c_feeds) % 2:
    errors.append(f"test: {len(c_feeds)} feeds of C alone, not pairs of forward and back")
for n in range(0, len(c_feeds) - 1, 2):
    (a0, a1), (b0, b1) = c_feeds[n], c_feeds[n + 1]
    if abs(a1 - a0) < 360 - CTOL or abs(b1 - a0) > CTOL or abs(b0 - a1) > CTOL:
        errors.append(f"test: C load pair {n // 2 + 1}: C {a0} -> {a1} -> {b1}, expected whole turns forward and back to {a0}")
        break

insp = events(insp_file, "inspection")
points = plan["points"]
probes = [(i, v) for i, (k, v) in enumerate(insp) if k == "STRAIGHT_PROBE"]
logs = [(i, t) for i, (k, t) in enumerate(insp) if k == "LOG"]
# Distances not given: from the first measuring move (its target) and the move before it (its start).
first = next((n for n, (i, v) in enumerate(probes) if i + 1 < len(insp) and insp[i + 1][0] == "LOG"), None)
if points and first is not None:
    i, v = probes[first]
    c, a = points[0]["contact_mm"], points[0]["approach"]
    if overtravel is None:
        overtravel = round(sum((v[k] - c[k]) * a[k] for k in range(3)), 4)
    if approach_mm is None:
        prev = next((insp[q][1] for q in range(i - 1, -1, -1) if insp[q][0] != "LOG"), None)
        approach_mm = round(sum((c[k] - prev[k]) * a[k] for k in range(3)), 4) if prev else 0.0
    if not (overtravel > 0 and approach_mm > 0):
        errors.append(f"inspection: overtravel {overtravel} mm and approach {approach_mm} mm must both be positive")
overtravel = overtravel or 0.0
approach_mm = approach_mm or 0.0
if len(logs) != len(points):
    errors.append(f"inspection: {len(logs)} LOG lines, {len(points)} planned points")
measuring = 0
protected = 0
k = 0  # next point
for n, (i, v) in enumerate(probes):
    is_measuring = i + 1 < len(insp) and insp[i + 1][0] == "LOG"
    if k >= len(points):
        errors.append(f"inspection: STRAIGHT_PROBE {n + 1} after the last planned point")
        break
    p = points[k]
    contact, appr = p["contact_mm"], p["approach"]
    start = [contact[a] - approach_mm * appr[a] for a in range(3)]
    end = [contact[a] + overtravel * appr[a] for a in range(3)]
    where = f"point {p['feature']} {p['point']} (position {p['position']})"
    if is_measuring:
        measuring += 1
        if not close(v[:3], end):
            errors.append(f"inspection: {where}: measuring target {v[:3]}, planned {end}")
        if abs(v[5] - p["c_deg"]) > CTOL:
            errors.append(f"inspection: {where}: probed at C {v[5]}, planned {p['c_deg']}")
        # The move before it must end at the start (protected probe or traverse back to it).
        prev = next((insp[q][1] for q in range(i - 1, -1, -1) if insp[q][0] != "LOG"), None)
        if prev is None or not close(prev[:3], start):
            errors.append(f"inspection: {where}: the measuring move starts at {prev[:3] if prev else None}, planned start {start}")
        fields = insp[i + 1][1].split()
        if len(fields) != 6 or float(fields[0]) != 1 or int(fields[1]) != p["position"] or int(fields[2]) != p["point"]:
            errors.append(f"inspection: LOG '{insp[i + 1][1]}' after {where}, expected 'PT 1 {p['position']} {p['point']} x y z'")
        k += 1
    else:
        protected += 1
        if not close(v[:3], start):
            errors.append(f"inspection: protected move to {v[:3]} before {where}, planned start {start}")
if k != len(points):
    errors.append(f"inspection: {k} measuring moves, {len(points)} planned points")

if errors:
    sys.stdout.reconfigure(errors="replace")
    print("rs274 check of the thermal test piece FAILED:")
    for e in errors[:25]:
        print("  " + e)
    if len(errors) > 25:
        print(f"  ... and {len(errors) - 25} more")
    sys.exit(1)
n_pre = len([c for c in plan["cuts"] if c["program"] == "pre_machining"])
print(f"rs274 check ok: pre-machining {n_pre} finishing cuts in order; test {n_test_cuts} cuts in order at constant "
      f"Z {z_value:.4f}, {len(c_feeds) // 2} C load pairs back to their start; inspection {measuring} measuring + {protected} protected probe moves (approach {approach_mm} mm, "
      f"overtravel {overtravel} mm), {len(logs)} LOG lines, no ABORT")
