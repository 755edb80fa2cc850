#!/usr/bin/python3
"""The peer a metrologist would otherwise write: the thermal test piece's CMM evaluation in
numpy (seed 004 L2055-L2093, Eqs. 7.1-7.5 with 7.1/7.2's sign corrected), on the same
labelled CMM export and plan manifest probeloop reads. No budgets: values only.

Usage: ttp_numpy.py cmm_export.csv plan.json  -> JSON on stdout: per cycle E_X, E_Y, E_Z,
E_B (urad), E_TTP, and the seconds the evaluation took (reading included).
Independent of probeloop's code: SVD planes, a Gauss-Newton circle, the frame built here.
"""
import json
import sys
import time

import numpy as np


def plane(p):
    """Least-squares plane: centroid and unit normal (smallest singular vector)."""
    c = p.mean(axis=0)
    n = np.linalg.svd(p - c)[2][-1]
    return c, n


def circle(xy):
    """Geometric least-squares circle (Kasa start, then Gauss-Newton on the distances)."""
    A = np.c_[2 * xy, np.ones(len(xy))]
    a, b, c = np.linalg.lstsq(A, (xy ** 2).sum(1), rcond=None)[0]
    x = np.array([a, b, np.sqrt(c + a * a + b * b)])
    for _ in range(20):
        d = xy - x[:2]
        r = np.hypot(d[:, 0], d[:, 1])
        J = np.c_[-d / r[:, None], -np.ones(len(xy))]
        step = np.linalg.lstsq(J, -(r - x[2]), rcond=None)[0]
        x += step
        if np.abs(step).max() < 1e-13:
            break
    return x


def main(cmm, manifest):
    t0 = time.perf_counter()
    m = json.load(open(manifest))
    feats = {f["id"]: f for f in m["features"]}
    pts = {}
    for line in open(cmm):
        if line.startswith("#") or line.startswith("feature"):
            continue
        f, _, x, y, z = line.split(",")[:5]
        pts.setdefault(f, []).append((float(x), float(y), float(z)))
    P = {k: np.array(v) for k, v in pts.items()}

    # The datum frame (L2055): top plane -> Z and its origin, the flanks' symmetry -> X,
    # the circle on the datum band -> the X/Y origin.
    ct, z = plane(P["TOP"])
    z = z if z[2] > 0 else -z
    _, nP = plane(P["FLANK_P"])
    _, nN = plane(P["FLANK_N"])
    nP = nP if nP[1] < 0 else -nP  # outward: into the notch
    nN = nN if nN[1] > 0 else -nN
    y = nN - nP
    y -= y.dot(z) * z
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    R = np.array([x, y, z])
    cyl = (P["CYL"] - ct) @ R.T
    cx, cy, _ = circle(cyl[:, :2])
    O = ct + cx * x + cy * y  # on the top plane, above the circle's centre
    local = {k: (v - O) @ R.T for k, v in P.items()}

    meas = {}
    for fid, f in feats.items():
        if f["role"] not in ("facet", "z_path"):
            continue
        c, n = plane(local[fid])
        if f["role"] == "facet":
            nom = np.array(f["direction"])
            n = n if n.dot(nom) > 0 else -n
            meas[fid] = c.dot(n)  # distance from the origin along its normal
        else:
            n = n if n[2] > 0 else -n
            yj = f["point_mm"][1]
            # depth below the datum plane at the path's centre (x = 0, y = y_j)
            zc = c[2] - (n[0] * (0 - c[0]) + n[1] * (yj - c[1])) / n[2]
            meas[fid] = (-zc, np.arctan2(n[0], n[2]) * 1e6)
    out = []
    cyc = {c["cycle"]: c for c in m["cycles"]}
    ref = cyc[0]

    def d(side, k):
        return meas[f"{side}_{k}"]

    for c in sorted(cyc):
        k, k0, j, j0 = cyc[c]["facet"], ref["facet"], cyc[c]["z_path"], ref["z_path"]
        dx1, dx2 = d("X1", k) - d("X1", k0), d("X2", k) - d("X2", k0)
        dy1, dy2 = d("Y1", k) - d("Y1", k0), d("Y2", k) - d("Y2", k0)
        out.append({"cycle": c,
                    "EX_um": (dx2 - dx1) / 2 * 1e3, "EY_um": (dy2 - dy1) / 2 * 1e3,
                    "EZ_um": (meas[f"Z{j}"][0] - meas[f"Z{j0}"][0]) * 1e3,
                    "EB_urad": meas[f"Z{j}"][1] - meas[f"Z{j0}"][1],
                    "ETTP_um": (dx1 + dx2 + dy1 + dy2) / 2 * 1e3})
    return {"peer": f"numpy {np.__version__}", "seconds": time.perf_counter() - t0, "cycles": out}


if __name__ == "__main__":
    print(json.dumps(main(sys.argv[1], sys.argv[2])))
