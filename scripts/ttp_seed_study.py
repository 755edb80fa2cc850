#!/usr/bin/env python3
"""The thermal test piece over many seeds: is U calibrated, and how often does the model
diagnosis name the piece's expansion? Reproduces docs/decisions.md (coverage over seeds 1-12)
and docs/model.md (diagnosis rates over seeds 1-30, shipped and ideal CMM).

Usage: scripts/ttp_seed_study.py [--coverage-seeds 12] [--diagnosis-seeds 30]
Needs build/cli/probeloop (scripts/build.sh build). About 1 s per seed and variant.
"""
import argparse, collections, json, math, os, subprocess, sys, tempfile

SRC = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, f"{SRC}/tests/integration")
from compare_ttp import QUANTITIES, injected, rows  # noqa: E402

PL = os.environ.get("PROBELOOP", f"{SRC}/build/cli/probeloop")
NMV = f"{SRC}/parts/machines/nmv5000.yaml"
TRUTH = f"{SRC}/examples/truth_thermal_test.yaml"
SHIPPED_CMM = "cmm: {mpe_constant: 1.2 um, mpe_length: 400 mm, temperature_half_width: 0.3 K}"
IDEAL_CMM = "cmm: {mpe_constant: 0.1 um, mpe_length: 0 mm, temperature_half_width: 0 K}"
MODEL = ("kind: error_model\ndata: {inputs: run/inputs.csv, errors: cmm/errors.csv}\nchannels:\n"
         "  EY_um: [{effect: static, input: T_caxis_C}]\n  EZ_um: [{effect: static, input: T_caxis_C}]\n  ETTP_um: []\n")


def pl(*args, cwd=None):
    subprocess.run([PL, *args], check=True, capture_output=True, cwd=cwd)


def piece(work, ideal):
    text = open(f"{SRC}/parts/thermal_test_piece.yaml").read()
    assert SHIPPED_CMM in text, "the shipped CMM line changed: update this script"
    path = f"{work}/{'ideal' if ideal else 'shipped'}.yaml"
    open(path, "w").write(text.replace(SHIPPED_CMM, IDEAL_CMM) if ideal else text)
    pl("plan", path, "--machine", NMV, "--out", f"{work}/plan-{'ideal' if ideal else 'shipped'}")
    return path, f"{work}/plan-{'ideal' if ideal else 'shipped'}"


def run(work, path, plan, seed, routes):
    d = tempfile.mkdtemp(dir=work)
    progs = [f"{plan}/{f}" for f in ("pre_machining.nc", "thermal_test.nc", "inspection.nc")]
    pl("simulate", *progs, "--machine", NMV, "--part", path, "--truth", TRUTH, "--cmm-points", f"{plan}/cmm_points.csv",
       "--out", f"{d}/run", "--seed", str(seed))
    for route, src in routes:
        pl("evaluate", f"{d}/run/{src}", "--manifest", f"{plan}/plan.json", "--out", f"{d}/{route}")
    return d


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--coverage-seeds", type=int, default=12)
    ap.add_argument("--diagnosis-seeds", type=int, default=30)
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="probeloop-ttp-seeds-")
    shipped = piece(work, False)
    ideal = piece(work, True)

    z = {"cmm": collections.defaultdict(list), "om": collections.defaultdict(list)}
    for seed in range(1, a.coverage_seeds + 1):
        d = run(work, *shipped, seed, (("cmm", "cmm_export.csv"), ("om", "dprnt.txt")))
        inj = injected(f"{d}/run/truth.json")
        for route in z:
            for cyc, r in rows(f"{d}/{route}/errors.csv").items():
                if cyc:
                    for q in QUANTITIES:
                        z[route][q].append((float(r[q]) - inj[cyc][q]) / (float(r["U_" + q]) / 2))
    print(f"Coverage over seeds 1-{a.coverage_seeds} (z = d / u, u = U/2):")
    for route, by_q in z.items():
        every = [x for q in QUANTITIES for x in by_q[q]]
        inside = sum(abs(x) <= 2 for x in every)
        rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))  # noqa: E731
        print(f"  {route}: {inside} of {len(every)} within U ({100 * inside / len(every):.1f} %), rms of d/u {rms(every):.2f} "
              f"({', '.join(f'{q} {rms(by_q[q]):.2f}' for q in QUANTITIES)}), largest |d/u| {max(map(abs, every)):.2f}")

    print(f"Model diagnosis over seeds 1-{a.diagnosis_seeds} (the table-side model of docs/model.md):")
    for name, (path, plan) in (("shipped CMM", shipped), ("ideal CMM", ideal)):
        tops = collections.Counter()
        for seed in range(1, a.diagnosis_seeds + 1):
            d = run(work, path, plan, seed, (("cmm", "cmm_export.csv"),))
            open(f"{d}/model.yaml", "w").write(MODEL)
            diag = subprocess.run([PL, "model", "diagnose", "model.yaml", "--part", path, "--json"],
                                  check=True, capture_output=True, text=True, cwd=d).stdout
            top = json.loads(diag)["candidates"][0]
            on = "on E_TTP" if "ETTP_um" in [c["channel"] for c in top["channels"]] else "not on E_TTP"
            tops[(on, top["id"])] += 1
        print(f"  {name}: " + ", ".join(f"{n} x {i} ({on})" for (on, i), n in tops.most_common()))
    subprocess.run(["rm", "-rf", work])


if __name__ == "__main__":
    main()
