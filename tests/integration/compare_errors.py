#!/usr/bin/env python3
"""Compare an evaluation's error series with the injected truth, per cycle.
Usage: compare_errors.py errors.csv truth.json tol_um tol_urad [--within-U | --coverage]
With --within-U each |measured - truth| must also be <= its expanded uncertainty U.
With --coverage (noisy data, U for k = 2 covers ~95 %): at least 90 % of the values must lie
within U and none beyond 2 U; the fraction found is printed."""
import csv
import json
import sys

errors_csv, truth_json, tol_um, tol_urad = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
within_u = "--within-U" in sys.argv
coverage = "--coverage" in sys.argv
rows = list(csv.DictReader(line for line in open(errors_csv) if not line.startswith("#")))
truth = {c["cycle"]: c for c in json.load(open(truth_json))["cycles"]}
names = ["EX0C_um", "EY0C_um", "EZ0T_um", "ER0T_um", "EA0C_urad", "EB0C_urad", "EC0C_urad"]
bad, worst = [], {}
inside, counted = 0, 0
for r in rows:
    t = truth[int(r["cycle"])]
    for n in names:
        d = abs(float(r[n]) - t[n])
        worst[n] = max(worst.get(n, 0.0), d)
        if coverage:
            U = float(r["U_" + n])
            if U == 0:
                continue  # the reference cycle
            counted += 1
            inside += d <= U + 1e-12
            if d > 2 * U:
                bad.append(f"cycle {r['cycle']} {n}: measured {r[n]}, injected {t[n]:.6f}, |diff| {d:.6f} > 2U = {2 * U}")
            continue
        tol = float(r["U_" + n]) if within_u else (tol_um if n.endswith("_um") else tol_urad)
        if d > tol + 1e-12:
            bad.append(f"cycle {r['cycle']} {n}: measured {r[n]}, injected {t[n]:.6f}, |diff| {d:.6f} > {tol}")
if not rows:
    bad.append("no cycles in " + errors_csv)
if coverage:
    if counted == 0 or inside < 0.9 * counted:
        bad.append(f"only {inside} of {counted} values lie within U (k = 2); at least 90 % expected")
    else:
        print(f"{inside} of {counted} values ({100.0 * inside / counted:.0f} %) lie within U (k = 2), none beyond 2U")
if bad:
    print("\n".join(bad[:20]))
    sys.exit(1)
print("recovered: worst |diff| " + ", ".join(f"{n} {worst[n]:.2e}" for n in names))
