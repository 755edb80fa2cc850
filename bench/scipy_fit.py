#!/usr/bin/env python3
"""The same point file through scipy.optimize.least_squares; prints JSON.

usage: scipy_fit.py FILE [--reps N] [--budget SECONDS] [--method lm|trf]

Sphere: parameters (cx, cy, cz, r), residual |p - c| - r.
Cylinder: a minimal parametrisation around the start (axis point p0, unit axis w, frame
u, v): (a, b, alpha, beta, r) with c = p0 + a u + b v, axis = normalise(w + alpha u + beta v),
residual = distance(p, axis) - r.
Both with the analytic Jacobian (no finite differences), method 'lm' (MINPACK lmder) by
default, the default tolerances (ftol = xtol = gtol = 1e-8), in float64 on the raw
coordinates, from the start stored in the file (the start probeloop's and PCL's fits get).
Only the least_squares call is timed (time.perf_counter and time.process_time; bench.sh
pins BLAS to one thread so that, like the other two, it runs on one core), repeated up to N times (default 5)
or until the budget (default 3 s) is spent, at least once.
"""
import argparse
import json
import struct
import sys
import time

import numpy as np
import scipy
from scipy.optimize import least_squares

HEADER = 256
KINDS = {1: "plane", 2: "sphere", 3: "cylinder", 4: "roundness", 5: "flatness"}


def read_data(path):
    """Returns (kind, truth, start, points, normals) of a PLBENCH1 file (bench_data.hpp)."""
    with open(path, "rb") as f:
        header = f.read(HEADER)
    if header[:8] != b"PLBENCH1":
        raise SystemExit(f"{path}: not a PLBENCH1 point file")
    kind, has_normals, n = struct.unpack_from("<IIQ", header, 8)
    truth = struct.unpack_from("<8d", header, 24)
    start = struct.unpack_from("<8d", header, 88)
    data = np.memmap(path, dtype="<f8", mode="r", offset=HEADER)
    points = np.array(data[: 3 * n]).reshape(n, 3)
    normals = np.array(data[3 * n: 6 * n]).reshape(n, 3) if has_normals else None

    def params(v):
        return {"position_mm": list(v[0:3]), "direction": list(v[3:6]), "radius_mm": v[6]}

    return KINDS[kind], params(truth), params(start), points, normals


def frame(w):
    """Unit vectors u, v completing w to a right-handed orthonormal frame."""
    a = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = a - a.dot(w) * w
    u /= np.linalg.norm(u)
    return u, np.cross(w, u)


def sphere_problem(points, start):
    x0 = np.array(start["position_mm"] + [start["radius_mm"]])

    def fun(x):
        return np.linalg.norm(points - x[:3], axis=1) - x[3]

    def jac(x):
        q = points - x[:3]
        d = np.linalg.norm(q, axis=1)
        j = np.empty((len(points), 4))
        j[:, :3] = -q / d[:, None]
        j[:, 3] = -1.0
        return j

    def result(x):
        return {"position_mm": list(x[:3]), "radius_mm": float(x[3])}

    return x0, fun, jac, result


def cylinder_problem(points, start):
    p0 = np.array(start["position_mm"])
    w = np.array(start["direction"])
    w /= np.linalg.norm(w)
    u, v = frame(w)
    x0 = np.array([0.0, 0.0, 0.0, 0.0, start["radius_mm"]])

    def parts(x):
        c = p0 + x[0] * u + x[1] * v
        nvec = w + x[2] * u + x[3] * v
        m = np.linalg.norm(nvec)
        e = nvec / m
        q = points - c
        t = q @ e
        h = q - t[:, None] * e  # component of q perpendicular to the axis
        d = np.linalg.norm(h, axis=1)
        return e, m, t, h, d

    def fun(x):
        return parts(x)[4] - x[4]

    def jac(x):
        e, m, t, h, d = parts(x)
        hu, hv = h @ u, h @ v
        j = np.empty((len(points), 5))
        j[:, 0] = -hu / d  # d(dist)/d(axis point) = -h/d
        j[:, 1] = -hv / d
        # d(dist)/d(axis) = -t q/d and d(axis)/d(alpha) = (u - e (e.u)) / m, whose
        # product is -t (h.u) / (d m); likewise for beta with v.
        j[:, 2] = -t * hu / (d * m)
        j[:, 3] = -t * hv / (d * m)
        j[:, 4] = -1.0
        return j

    def result(x):
        c = p0 + x[0] * u + x[1] * v
        nvec = w + x[2] * u + x[3] * v
        return {"position_mm": list(c), "direction": list(nvec / np.linalg.norm(nvec)),
                "radius_mm": float(x[4])}

    return x0, fun, jac, result


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--budget", type=float, default=3.0)
    ap.add_argument("--method", default="lm", choices=["lm", "trf"])
    args = ap.parse_args()

    kind, _, start, points, _ = read_data(args.file)
    if kind == "sphere":
        x0, fun, jac, result = sphere_problem(points, start)
    elif kind == "cylinder":
        x0, fun, jac, result = cylinder_problem(points, start)
    else:
        raise SystemExit("scipy_fit.py handles sphere and cylinder files only")

    times, cpu, spent, sol = [], [], 0.0, None
    while len(times) < args.reps and (not times or spent < args.budget):
        c0, t0 = time.process_time(), time.perf_counter()
        sol = least_squares(fun, x0, jac=jac, method=args.method)
        t1, c1 = time.perf_counter(), time.process_time()
        times.append(t1 - t0)
        cpu.append(c1 - c0)
        spent += t1 - t0
    out = {
        "tool": "scipy", "version": scipy.__version__, "numpy": np.__version__,
        "method": args.method, "jacobian": "analytic", "file": args.file, "n": len(points),
        "kind": kind, "params": result(sol.x), "times_s": times,
        "median_s": float(np.median(times)), "cpu_times_s": cpu,
        "median_cpu_s": float(np.median(cpu)), "nfev": int(sol.nfev),
        "njev": int(sol.njev) if sol.njev is not None else None, "status": int(sol.status),
    }
    json.dump(out, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
