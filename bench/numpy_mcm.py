#!/usr/bin/env python3
"""The peer of bench/gum_bench.cpp: the same location-error model (bench/location_mcm.hpp)
by Monte Carlo in numpy, vectorised, as a metrologist would write it in Python.
Prints one JSON line: trials, seconds (median of REPS), u and the symmetric 95 % interval."""
import json, sys, time
import numpy as np

M = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
REPS = int(sys.argv[2]) if len(sys.argv) > 2 else 5


def run(seed):
    rng = np.random.default_rng(seed)
    u_xy, u_z = 0.5 * np.sqrt(0.5), 0.5
    # centres: cycle i and reference, 4 positions, x y z (only the z of positions 2 and 4
    # enter EA0C, but all 24 are drawn, as in the C++ model)
    c = rng.normal(0.0, 1.0, size=(M, 24)) * np.tile([u_xy, u_xy, u_z], 8)
    c[:, 3 * 1 + 2] += 3.0
    half = rng.normal(160.0, 0.05, size=M)
    atc = rng.normal(0.0, 0.75, size=(M, 6))
    dT = rng.uniform(-1.0, 1.0, size=M)
    lift = 11.5e-3 * 90.0
    d_m = 2.0 * half * 1e-3
    zi2 = c[:, 5] + atc[:, 2] + lift * dT
    zi4 = c[:, 11] + atc[:, 2] + lift * dT
    z12 = c[:, 17] + atc[:, 5]
    z14 = c[:, 23] + atc[:, 5]
    y = (zi2 - zi4) / d_m - (z12 - z14) / d_m
    u = y.std(ddof=1)
    ys = np.sort(y)
    q = int(round(0.95 * M))
    r = (M - q) // 2
    return u, ys[r], ys[r + q]


times = []
for k in range(REPS):
    t0 = time.perf_counter()
    u, lo, hi = run(k + 1)
    times.append(time.perf_counter() - t0)
times.sort()
print(json.dumps({"peer": "numpy " + np.__version__, "trials": M, "seconds": times[len(times) // 2],
                  "u_um_per_m": u, "interval": [lo, hi]}))
