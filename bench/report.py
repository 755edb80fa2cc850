#!/usr/bin/env python3
"""Builds bench/results/latest.md and summary.json from one bench.sh run.

usage: report.py RESULTS_DIR DATA_DIR --command "..." [--pcl-max N] [--scipy-max N]

Inputs in RESULTS_DIR: ours.json (Google Benchmark JSON), ours_fits.json (probeloop's fitted
parameters, from the benchmark executable), pcl.jsonl and scipy.jsonl (one JSON line per
file). Reads the point files again to judge every fit against
  - the generating truth (stored in each file), and
  - the least-squares optimum, computed here independently of all three tools: Gauss-Newton
    in float64 on centred coordinates, started from the truth and iterated until the step
    is below 1e-12 mm (sphere, cylinder), or centroid + SVD (plane).
Minimum-zone fits are checked against a linear programme (scipy.optimize.linprog, HiGHS) on
the same points, linearised at the least-squares element (second-order error below 1e-9 um
here), residuals in um.
"""
import argparse
import json
import math
import os
import platform
import sys

import numpy as np
import scipy
from scipy.optimize import linprog

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from scipy_fit import frame, read_data  # noqa: E402

LS_KINDS = [("plane", "LS_Plane"), ("sphere", "LS_Sphere"), ("cylinder", "LS_Cylinder")]
MZ_KINDS = [("roundness", "MZ_Roundness", "circle2d"), ("flatness", "MZ_Flatness", "plane")]
# "Equal accuracy": distances to the LS optimum within 1 nm (0.1 % of the 1 um noise) and
# axis angles within 0.01 urad (1 nm over 100 mm) count as equal.
EQUAL_MM, EQUAL_RAD = 1e-6, 1e-8


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


# ---------------------------------------------------------------- LS references ----------
def ls_sphere(points, c, r):
    m = points.mean(axis=0)
    q = points - m
    c = np.asarray(c, float) - m
    for _ in range(20):
        dq = q - c
        d = np.linalg.norm(dq, axis=1)
        res = d - r
        j = np.empty((len(q), 4))
        j[:, :3] = -dq / d[:, None]
        j[:, 3] = -1.0
        step = np.linalg.solve(j.T @ j, -(j.T @ res))
        c, r = c + step[:3], r + step[3]
        if np.abs(step).max() < 1e-12:
            break
    return {"position_mm": c + m, "radius_mm": r}


def ls_cylinder(points, c, w, r):
    m = points.mean(axis=0)
    q0 = points - m
    c = np.asarray(c, float) - m
    w = unit(w)
    for _ in range(20):
        u, v = frame(w)
        q = q0 - c
        t = q @ w
        h = q - t[:, None] * w
        d = np.linalg.norm(h, axis=1)
        res = d - r
        hu, hv = h @ u, h @ v
        j = np.column_stack([-hu / d, -hv / d, -t * hu / d, -t * hv / d, -np.ones_like(d)])
        step = np.linalg.solve(j.T @ j, -(j.T @ res))
        c = c + step[0] * u + step[1] * v
        w = unit(w + step[2] * u + step[3] * v)
        r = r + step[4]
        if max(abs(step[0]), abs(step[1]), abs(step[4])) < 1e-12 and \
                max(abs(step[2]), abs(step[3])) < 1e-14:
            break
    c = c + ((-c) @ w) * w  # axis point nearest the centroid
    return {"position_mm": c + m, "direction": w, "radius_mm": r}


def ls_plane(points):
    m = points.mean(axis=0)
    _, _, vt = np.linalg.svd(np.cov((points - m).T))
    n = vt[-1]
    return {"position_mm": m, "direction": n}


# ---------------------------------------------------------------- comparisons ------------
def diff(kind, a, b, ref_point):
    """(position/radius difference in mm, axis/normal angle in rad or None)."""
    if kind == "sphere":
        dp = np.linalg.norm(np.asarray(a["position_mm"]) - np.asarray(b["position_mm"]))
        return max(dp, abs(a["radius_mm"] - b["radius_mm"])), None
    wa, wb = unit(a["direction"]), unit(b["direction"])
    angle = float(np.linalg.norm(np.cross(wa, wb)))
    pa, pb = np.asarray(a["position_mm"]), np.asarray(b["position_mm"])
    if kind == "plane":
        # offset of the two planes along the normal at the reference point
        return abs((ref_point - pa) @ wa - np.sign(wa @ wb) * ((ref_point - pb) @ wb)), angle
    fa = pa + ((ref_point - pa) @ wa) * wa  # feet of the reference point on both axes
    fb = pb + ((ref_point - pb) @ wb) * wb
    return max(np.linalg.norm(fa - fb), abs(a["radius_mm"] - b["radius_mm"])), angle


def fmt_diff(d):
    mm, rad = d
    s = f"{mm * 1e3:.2g} µm"
    if rad is not None:
        s += f" · {rad * 1e6:.2g} µrad"
    return s


def sz(n):
    e = int(round(math.log10(n)))
    return f"1e{e}" if 10**e == n else str(n)


def fmt_ms(s):
    ms = s * 1e3
    return f"{ms:.3g}" if ms < 1000 else f"{ms:.0f}"


def not_worse(ours, peer):
    ok = ours[0] <= peer[0] + EQUAL_MM
    if ours[1] is not None:
        ok = ok and ours[1] <= peer[1] + EQUAL_RAD
    return ok


# ---------------------------------------------------------------- MZ check ---------------
def mz_lp(kind, points):
    """Minimum-zone width (mm) by a linear programme linearised at the LS element."""
    if kind == "roundness":
        p = points[:, :2]
        m = p.mean(axis=0)
        q = p - m
        a = np.column_stack([2 * q, np.ones(len(q))])
        x = np.linalg.lstsq(a, (q * q).sum(axis=1), rcond=None)[0]
        c = x[:2]
        e = np.linalg.norm(q - c, axis=1)
        u = (q - c) / e[:, None]
        base = e.mean()
        coeff = -u  # residual = e - u . delta
        rhs = (e - base) * 1e3  # um
        coeff = coeff * 1e3
    else:
        m = points.mean(axis=0)
        n = ls_plane(points)["direction"]
        uu, vv = frame(n)
        q = points - m
        rhs = (q @ n) * 1e3
        coeff = -np.column_stack([q @ uu, q @ vv]) / 100.0 * 1e3  # tilt per 100 mm, um
    k = coeff.shape[1]
    # variables: linear parameters (k), lo, hi; residual_i = rhs_i + coeff_i . x
    ones = np.ones((len(rhs), 1))
    a_ub = np.vstack([np.hstack([coeff, np.zeros_like(ones), -ones]),   # res <= hi
                      np.hstack([-coeff, ones, np.zeros_like(ones)])])  # res >= lo
    b_ub = np.concatenate([-rhs, rhs])
    cost = np.zeros(k + 2)
    cost[k], cost[k + 1] = -1.0, 1.0
    sol = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * (k + 2), method="highs")
    if not sol.success:
        return None
    return (sol.x[k + 1] - sol.x[k]) * 1e-3


# ---------------------------------------------------------------- main -------------------
def load_jsonl(path):
    out = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                if line.strip():
                    rec = json.loads(line)
                    out[(rec["kind"], rec["n"])] = rec
    return out


def gb_times(path, clock):
    """{(benchmark, n): (median seconds on `clock`, error or None)} from Google Benchmark
    JSON, and {(benchmark, n): {"real_s": .., "cpu_s": ..}}."""
    with open(path) as f:
        gb = json.load(f)
    scale = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}
    out, both = {}, {}
    for b in gb["benchmarks"]:
        name = b.get("run_name", b["name"]).replace("/real_time", "")
        base, n = name.split("/")[:2]
        key = (base, int(n))
        if b.get("error_occurred"):
            out[key] = (None, b.get("error_message", "error"))
        elif b.get("aggregate_name") == "median" or \
                (b.get("run_type") == "iteration" and key not in both):
            k = scale[b["time_unit"]]
            both[key] = {"real_s": b["real_time"] * k, "cpu_s": b["cpu_time"] * k}
            out[key] = (both[key]["cpu_s" if clock == "cpu" else "real_s"], None)
    return gb.get("context", {}), out, both


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("results")
    ap.add_argument("data")
    ap.add_argument("--command", default="scripts/bench.sh")
    ap.add_argument("--pcl-max", type=int, default=10**7)
    ap.add_argument("--scipy-max", type=int, default=10**7)
    ap.add_argument("--date", default="")
    ap.add_argument("--clock", default="cpu", choices=["cpu", "real"])
    ap.add_argument("--seconds-so-far", type=int, default=None)
    args = ap.parse_args()

    context, ours_t, ours_both = gb_times(os.path.join(args.results, "ours.json"), args.clock)
    peer_key = "median_cpu_s" if args.clock == "cpu" else "median_s"
    with open(os.path.join(args.results, "ours_fits.json")) as f:
        ours_fit = json.load(f)
    pcl = load_jsonl(os.path.join(args.results, "pcl.jsonl"))
    scp = load_jsonl(os.path.join(args.results, "scipy.jsonl"))

    ls_sizes = sorted({n for (b, n) in ours_t if b.startswith("LS_")})
    mz_sizes = sorted({n for (b, n) in ours_t if b.startswith("MZ_")})
    summary = {"ls": [], "mz": [], "targets": {}}
    time_rows, agree_rows, mz_rows = [], [], []
    read = {n: ours_t.get(("ReadPass", n), (None, None))[0] for n in ls_sizes}

    for kind, bench in LS_KINDS:
        for n in ls_sizes:
            path = os.path.join(args.data, f"{kind}_{n}.bin")
            if not os.path.exists(path):
                continue
            _, truth, _, points, _ = read_data(path)
            t_ours, err = ours_t.get((bench, n), (None, "not run"))
            fit = ours_fit.get(f"{bench}/{n}", {})
            rec = {"kind": kind, "n": n, "clock": args.clock, "ours_s": t_ours,
                   "ours_error": err, "read_pass_s": read.get(n),
                   "ours_real_and_cpu": ours_both.get((bench, n)),
                   "read_pass_real_and_cpu": ours_both.get(("ReadPass", n))}
            ref_point = np.asarray(truth["position_mm"])
            if kind == "plane":
                ref = ls_plane(points)
            elif kind == "sphere":
                ref = ls_sphere(points, truth["position_mm"], truth["radius_mm"])
            else:
                ref = ls_cylinder(points, truth["position_mm"], truth["direction"],
                                  truth["radius_mm"])
            fits = {}
            if "error" not in fit and fit:
                fits["ours"] = fit
            p, s = pcl.get((kind, n)), scp.get((kind, n))
            if p:
                fits["pcl"] = p["params"]
                rec["pcl_s"] = p[peer_key]
                rec["pcl_real_and_cpu"] = {"real_s": p["median_s"], "cpu_s": p["median_cpu_s"]}
            if s:
                fits["scipy"] = s["params"]
                rec["scipy_s"] = s[peer_key]
                rec["scipy_real_and_cpu"] = {"real_s": s["median_s"], "cpu_s": s["median_cpu_s"]}
            d_ref = {k: diff(kind, v, ref, ref_point) for k, v in fits.items()}
            d_truth = {k: diff(kind, v, truth, ref_point) for k, v in fits.items()}
            names = list(fits)
            pair = [diff(kind, fits[a], fits[b], ref_point)
                    for i, a in enumerate(names) for b in names[i + 1:]]
            rec["to_ls_optimum"] = d_ref
            rec["to_truth"] = d_truth
            rec["ls_optimum_to_truth"] = diff(kind, ref, truth, ref_point)
            if pair:
                rec["max_pairwise"] = (max(x[0] for x in pair),
                                       None if pair[0][1] is None else max(x[1] for x in pair))
            summary["ls"].append(rec)

            def cell_t(peer):
                if kind == "plane":
                    return "—", "—"
                cap = args.pcl_max if peer == "pcl" else args.scipy_max
                r = rec.get(f"{peer}_s")
                if r is None:
                    return ("not run (cap)" if n > cap else "—"), "—"
                ratio = f"{r / t_ours:.1f}×" if t_ours else "—"
                return fmt_ms(r), ratio

            pt, pr = cell_t("pcl")
            st, sr = cell_t("scipy")
            ours_cell = fmt_ms(t_ours) if t_ours else f"error: {err}"
            rp = read.get(n)
            time_rows.append(
                f"| {kind} | {sz(n)} | {fmt_ms(rp) if rp else '—'} | {ours_cell} | "
                f"{(f'{t_ours / rp:.1f}×' if (t_ours and rp) else '—')} | {pt} | {pr} | {st} | {sr} |")

            def cell(d, k):
                return fmt_diff(d[k]) if k in d else "—"

            if kind == "plane":
                agree_rows.append(
                    f"| {kind} | {sz(n)} | — | {cell(d_ref, 'ours')} | — | — | "
                    f"{cell(d_truth, 'ours')} | — | — |")
            else:
                agree_rows.append(
                    f"| {kind} | {sz(n)} | "
                    f"{fmt_diff(rec['max_pairwise']) if 'max_pairwise' in rec else '—'} | "
                    f"{cell(d_ref, 'ours')} | {cell(d_ref, 'pcl')} | {cell(d_ref, 'scipy')} | "
                    f"{cell(d_truth, 'ours')} | {cell(d_truth, 'pcl')} | {cell(d_truth, 'scipy')} |")

    for kind, bench, element in MZ_KINDS:
        for n in mz_sizes:
            path = os.path.join(args.data, f"{kind}_{n}.bin")
            if not os.path.exists(path):
                continue
            _, _, _, points, _ = read_data(path)
            t_ours, err = ours_t.get((bench, n), (None, "not run"))
            fit = ours_fit.get(f"{bench}/{n}", {})
            lp = mz_lp(kind, points)
            rec = {"kind": kind, "element": element, "n": n, "clock": args.clock, "ours_s": t_ours,
                   "ours_error": err, "ours_real_and_cpu": ours_both.get((bench, n)),
                   "zone_mm": fit.get("form_mm"), "ls_form_mm": fit.get("ls_form_mm"),
                   "support_points": fit.get("support_points"), "lp_zone_mm": lp}
            summary["mz"].append(rec)
            z, lsf, sp = rec["zone_mm"], rec["ls_form_mm"], rec["support_points"]
            um = lambda v: f"{v * 1e3:.4f}" if v is not None else "—"  # noqa: E731
            dz = f"{(z - lp) * 1e3:+.1e}" if (z is not None and lp is not None) else "—"
            t_cell = fmt_ms(t_ours) if t_ours else f"error: {err}"
            mz_rows.append(f"| {kind} ({element}) | {sz(n)} | {t_cell} | {um(z)} | {um(lp)} | "
                           f"{dz} | {um(lsf)} | {sp if sp is not None else '—'} |")

    # ------------------------------------------------------------ targets --------------
    targets = []
    # Issue 16's targets: LS plane <= 3x one read pass (n >= 1e4); LS sphere and cylinder
    # <= 10x one read pass (n >= 1e5), >= 5x faster than PCL and >= 10x faster than SciPy at
    # every n from 1e3 to 1e6, at equal or better accuracy.
    def read_pass_target(kind, bound, n_min):
        rows = [r for r in summary["ls"] if r["kind"] == kind and r["ours_s"] and r["read_pass_s"]
                and r["n"] >= n_min]
        if rows:
            ratios = {r["n"]: r["ours_s"] / r["read_pass_s"] for r in rows}
            targets.append((f"LS {kind} ≤ {bound:g}× one read pass for n ≥ {sz(n_min)}",
                            bool(all(v <= bound for v in ratios.values())),
                            ", ".join(f"{sz(n)}: {v:.1f}×" for n, v in ratios.items())))
    read_pass_target("plane", 3.0, 10000)
    for kind in ("sphere", "cylinder"):
        read_pass_target(kind, 10.0, 100000)
    for kind in ("sphere", "cylinder"):
        rows = [r for r in summary["ls"] if r["kind"] == kind and r["ours_s"]
                and 1000 <= r["n"] <= 1000000]
        for peer, factor in (("pcl", 5.0), ("scipy", 10.0)):
            rr = [r for r in rows if r.get(f"{peer}_s")]
            if not rr:
                continue
            parts, met = [], True
            for r in rr:
                ratio = r[f"{peer}_s"] / r["ours_s"]
                acc = not_worse(r["to_ls_optimum"]["ours"], r["to_ls_optimum"][peer]) \
                    if "ours" in r["to_ls_optimum"] else False
                met = met and ratio >= factor and acc
                parts.append(f"{sz(r['n'])}: {ratio:.1f}×{'' if acc else ' (less accurate)'}")
            label = "PCL" if peer == "pcl" else "SciPy"
            targets.append((f"LS {kind} ≥ {factor:g}× faster than {label} at equal or better "
                            f"accuracy (1e3…1e6)", met, ", ".join(parts)))
    rnd = [r for r in summary["mz"] if r["kind"] == "roundness" and r["n"] == 10000]
    if rnd and rnd[0]["ours_s"]:
        t = rnd[0]["ours_s"]
        targets.append(("MZ roundness on 1e4 points < 50 ms", t < 0.05, f"{t * 1e3:.3g} ms"))
    summary["targets"] = [{"target": a, "met": bool(b), "numbers": c} for a, b, c in targets]

    # ------------------------------------------------------------ markdown -------------
    cores = os.cpu_count()
    lines = [
        "# probeloop fitting benchmarks — latest run",
        "",
        f"- Date: {args.date or 'n/a'}; command: `{args.command}`"
        + (f" (the script had run {args.seconds_so_far} s, build and data included, when "
           "this report was written)"
           if args.seconds_so_far is not None else ""),
        f"- Machine: {cpu_model()}, {cores} cores, "
        f"{context.get('mhz_per_cpu', '?')} MHz reported; "
        f"Google Benchmark {context.get('library_build_type', '?')} library build",
        f"- Peers: PCL {next(iter(pcl.values()))['version'] if pcl else 'n/a'} "
        f"(optimizeModelCoefficients, float, numerical Jacobian), SciPy "
        f"{next(iter(scp.values()))['version'] if scp else scipy.__version__} "
        f"(least_squares method "
        f"'{next(iter(scp.values()))['method'] if scp else 'lm'}', analytic Jacobian), "
        f"numpy {np.__version__}, Python {platform.python_version()}",
        f"- PCL run up to n = {sz(args.pcl_max)}, SciPy up to n = {sz(args.scipy_max)}.",
        f"- Times are {'process CPU' if args.clock == 'cpu' else 'wall-clock'} times in ms, "
        "medians (probeloop: Google Benchmark, 3 repetitions; peers: up to 5 runs or 3 s of "
        "runs, at least one); every fitter runs on one core (SciPy's BLAS pinned to one thread). "
        "summary.json has both clocks. Ratios > 1 mean probeloop is faster.",
        f"- Load average when the benchmarks started: "
        f"{', '.join(f'{x:.2f}' for x in context.get('load_avg', [])) or 'n/a'}.",
        "",
        "## Least squares: times",
        "",
        "| element | n | read pass | probeloop | probeloop / read pass | PCL | PCL / probeloop "
        "| SciPy | SciPy / probeloop |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        *time_rows,
        "",
        "## Least squares: agreement",
        "",
        "Differences are max(|Δ axis point or centre|, |Δ radius|) in µm (the axis point is the "
        "foot of the generating centroid on each axis; for planes the offset along the normal "
        "there) and the angle between axes / normals in µrad. \"LS optimum\" is computed "
        "independently by report.py (Gauss-Newton in float64 from the truth to a 1e-12 mm "
        "step; plane: centroid + SVD); \"truth\" is the generating geometry (1 µm noise, so "
        "the LS optimum itself sits about σ/√n from it).",
        "",
        "| element | n | max Δ among the three fits | probeloop − LS opt | PCL − LS opt "
        "| SciPy − LS opt | probeloop − truth | PCL − truth | SciPy − truth |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
        *agree_rows,
        "",
        "## Minimum zone",
        "",
        "Zone widths in µm. \"LP check\": the same points through a linear programme "
        "(scipy.optimize.linprog, HiGHS) linearised at the least-squares element; "
        "\"LS p-v\": peak to valley of the least-squares residuals (≥ the zone).",
        "",
        "| fit | n | probeloop ms | zone µm | LP check µm | zone − LP µm | LS p-v µm "
        "| support points |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
        *mz_rows,
        "",
        "## Targets",
        "",
        "| target | met | numbers |",
        "|---|---|---|",
        *[f"| {a} | {'yes' if b else 'no'} | {c} |" for a, b, c in targets],
        "",
    ]
    with open(os.path.join(args.results, "latest.md"), "w") as f:
        f.write("\n".join(lines))

    def clean(o):
        if isinstance(o, dict):
            return {str(k): clean(v) for k, v in o.items()}
        if isinstance(o, (list, tuple)):
            return [clean(v) for v in o]
        if isinstance(o, (np.floating, float)):
            return None if math.isnan(o) else float(o)
        if isinstance(o, np.ndarray):
            return clean(o.tolist())
        return o

    with open(os.path.join(args.results, "summary.json"), "w") as f:
        json.dump(clean(summary), f, indent=1)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
