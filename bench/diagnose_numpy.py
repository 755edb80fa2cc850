#!/usr/bin/env python3
"""The peer of `probeloop model diagnose` a user would otherwise write: numpy, vectorised,
on the same campaign. For every channel (offset-only starting model) and every candidate
(drift; static and lag of each temperature; lag of each speed/on-off input by magnitude;
transient of tool_changes) it fits on the first 60 % (time constants: best of a 32-point
logarithmic grid, no refinement), predicts the last 40 % and reports the validation RMSE.
Prints JSON {seconds (median of 5), fits, top: {channel: [candidate, rmse_before, rmse_after]}}.
Usage: diagnose_numpy.py inputs.csv errors.csv"""
import json, sys, time
import numpy as np


def read(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    head = lines[0].strip().split(",")
    data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    return head, data


def lag(t, u, tau):
    a = np.exp(-np.diff(t) / tau)
    x = np.empty_like(u)
    x[0] = u[0]
    for k in range(1, len(u)):  # a recursion: numpy has no vectorised first-order filter
        x[k] = u[k - 1] + (x[k - 1] - u[k - 1]) * a[k - 1]
    return x - u[0]


def transient(t, u, tau):
    s, out = 0.0, np.zeros_like(u)
    for k in range(1, len(u)):
        h = t[k] - t[k - 1]
        s = s * np.exp(-h / tau) + u[k] * np.exp(-0.5 * h / tau)
        out[k] = s
    return out


def diagnose(ih, idata, eh, edata):
    t, te = idata[:, 0], edata[:, 0]
    n = int(round(0.6 * len(te)))
    chans = [h for h in eh[1:] if h != "cycle" and not h.startswith("U_")]
    taus = np.geomspace(max(60.0, t[1] - t[0]), 4 * (te[n - 1] - t[0]), 32)
    cands = [("drift", None, (te - t[0]) / 3600.0)]
    for i, name in enumerate(ih[1:], start=1):
        u = idata[:, i]
        if np.ptp(u[t <= te[n - 1]]) == 0:
            continue
        if name.endswith("_C"):
            cands.append((f"static({name})", None, np.interp(te, t, u - u[0])))
        if name == "tool_changes":
            cands.append((f"transient({name})", "grid", [np.interp(te, t, transient(t, u, tau)) for tau in taus]))
        else:
            g = np.abs(u) if name.endswith("_rpm") or name.startswith("feed") else u
            cands.append((f"lag({name})", "grid", [np.interp(te, t, lag(t, g, tau)) for tau in taus]))
    top, fits = {}, 0
    for ch in chans:
        y = edata[:, eh.index(ch)]
        before = np.sqrt(np.mean((y[n:] - y[:n].mean()) ** 2))
        best = None
        for name, kind, reg in cands:
            pick = None  # the time constant of least training SSR, as a fit would choose it
            for r in (reg if kind else [reg]):
                X = np.column_stack([np.ones_like(te), r])
                theta, *_ = np.linalg.lstsq(X[:n], y[:n], rcond=None)
                fits += 1
                train = np.sum((y[:n] - X[:n] @ theta) ** 2)
                if pick is None or train < pick[0]:
                    pick = (train, np.sqrt(np.mean((y[n:] - X[n:] @ theta) ** 2)))
            if best is None or pick[1] < best[1]:
                best = (pick[0], pick[1], name)
        top[ch] = [best[2], float(before), float(best[1])]
    return top, fits


ih, idata = read(sys.argv[1])
eh, edata = read(sys.argv[2])
times = []
for _ in range(5):
    t0 = time.perf_counter()
    top, fits = diagnose(ih, idata, eh, edata)
    times.append(time.perf_counter() - t0)
print(json.dumps({"peer": f"numpy {np.__version__} (grid of 32 time constants, OLS)", "seconds": sorted(times)[2], "fits": fits, "top": top}))
