#!/usr/bin/env bash
# Monte Carlo benchmark of the GUM engine (issue 6): 1e6 trials of the location-error model
# (bench/location_mcm.hpp) by probeloop (Google Benchmark, median of 5) and by numpy on the
# same model in the same run; writes bench/results/gum.md.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
ensure_packages cmake g++ make libbenchmark-dev python3-numpy libceres-dev libboost-dev
build_bench_target probeloop_bench_gum
mkdir -p bench/results
$BUILD/bench/probeloop_bench_gum --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_format=json > bench/results/gum_ours.json
/usr/bin/python3 bench/numpy_mcm.py 1000000 5 > bench/results/gum_numpy.json
python3 - <<'PY'
import json
ours = json.load(open("bench/results/gum_ours.json"))
peer = json.loads(open("bench/results/gum_numpy.json").read())
med = {b["run_name"]: b for b in ours["benchmarks"] if b.get("aggregate_name") == "median"}
m = med["BM_McmLocationError/1000000/real_time"]
g = med["BM_GufLocationError"]
t_ours = m["real_time"] / 1e3
ctx = ours["context"]
lines = ["# GUM engine: Monte Carlo of the location-error model", "",
         f"Machine: {ctx.get('num_cpus')} CPUs at {ctx.get('mhz_per_cpu')} MHz; {ctx.get('date')}. "
         "Reproduce: `bench/gum_mcm.sh`. Model: bench/location_mcm.hpp (32 inputs: 24 centre coordinates, "
         "d/2, 6 tool-change translations, the artifact's temperature change; output EA0C by seed 004 Eq. 5.8).", "",
         "| method | trials | time (median of 5) | u (um/m) | 95 % interval (um/m) |", "|---|---|---|---|---|",
         f"| probeloop `monteCarlo` (1 thread) | 1e6 | {t_ours:.3f} s | {m['u_um_per_m']:.4f} | [{m['interval_low']:.3f}, {m['interval_high']:.3f}] |",
         f"| {peer['peer']} (vectorised) | 1e6 | {peer['seconds']:.3f} s | {peer['u_um_per_m']:.4f} | [{peer['interval'][0]:.3f}, {peer['interval'][1]:.3f}] |",
         f"| probeloop GUF (`propagate<32>`, ceres::Jet) | - | {g['real_time']:.2f} us | {g['u_um_per_m']:.4f} | 9.375 +- {1.96 * g['u_um_per_m']:.3f} |", "",
         f"Target (issue 6): 1e6 trials < 1 s: **{'met' if t_ours < 1 else 'missed'}** ({t_ours:.2f} s). "
         f"numpy / probeloop time ratio: {peer['seconds'] / t_ours:.2f}."]
open("bench/results/gum.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
