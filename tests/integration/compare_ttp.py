#!/usr/bin/env python3
"""The thermal test piece's evaluated errors against the simulator's injected (as-cut) truth.

Usage: compare_ttp.py truth.json errors.csv [errors2.csv ...]
Prints per quantity and cycle the injected value and each route's E +- U, then per route how
many values lie within U (k = 2) and the rms of d/u (d = E - injected, u = U/2: near 1 when U
is calibrated). Exit 1 when a value lies beyond 2U. As a module: coverage(rows, injected).
"""
import csv
import json
import math
import sys

QUANTITIES = ["EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"]


def rows(path):
    """errors.csv as {cycle: row}."""
    return {int(r["cycle"]): r for r in csv.DictReader(l for l in open(path) if not l.startswith("#"))}


def injected(truth_json):
    return {c["cycle"]: c for c in json.load(open(truth_json))["ttp_cycles"]}


def coverage(route_rows, inj):
    """The normalised deviations z = d / (U/2) of every value but the reference's, and how
    many lie within U."""
    z, inside = [], 0
    for cyc, r in route_rows.items():
        if cyc == 0:
            continue  # the reference: 0 by definition
        for q in QUANTITIES:
            if q not in r or r[q] == "":
                continue
            d, U = float(r[q]) - inj[cyc][q], float(r["U_" + q])
            z.append(d / (U / 2))
            inside += abs(d) <= U
    return z, inside


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    inj = injected(argv[1])
    routes = [(p, rows(p)) for p in argv[2:]]
    for q in QUANTITIES:
        print(f"  {q:8s} cycle  injected " + "  ".join(f"{'route ' + str(i + 1):>17s}" for i in range(len(routes))))
        for cyc in sorted(inj):
            vals = "  ".join(f"{float(r[cyc][q]):8.2f} +- {float(r[cyc]['U_' + q]):5.2f}" for _, r in routes)
            print(f"  {'':8s} {cyc:5d} {inj[cyc][q]:9.2f} {vals}")
    worst = 0.0
    for i, (path, r) in enumerate(routes):
        z, inside = coverage(r, inj)
        worst = max([worst] + [abs(x) for x in z])
        rms = math.sqrt(sum(x * x for x in z) / len(z))
        print(f"  route {i + 1} ({path}): {inside} of {len(z)} values within U (k = 2), rms of d/u {rms:.2f}")
    return 1 if worst > 4 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
