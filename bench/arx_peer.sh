#!/usr/bin/env bash
# ARX identification against an independent implementation on the same data in one run
# (issue 5 item 8): probeloop's fitArx and statsmodels' AutoReg; writes bench/results/arx.md.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
ensure_packages cmake g++ make python3-statsmodels python3-pandas
build_bench_target probeloop_bench_arx
mkdir -p bench/results
$BUILD/bench/probeloop_bench_arx bench/results/arx_data.csv > bench/results/arx_ours.json
/usr/bin/python3 bench/arx_statsmodels.py bench/results/arx_data.csv > bench/results/arx_statsmodels.json
python3 - <<'PY'
import json
o = json.load(open("bench/results/arx_ours.json"))
p = json.load(open("bench/results/arx_statsmodels.json"))
d = max(abs(o["theta"][k] - p["theta"][k]) for k in o["theta"])
du = max(abs(o["u"][k] - p["u"][k]) / p["u"][k] for k in o["u"])
lines = ["# ARX identification against statsmodels", "",
         "Same data (bench/results/arx_data.csv: 864 samples = 72 h at 5 min, 6 inputs, na = 1, nb = 3 with "
         "the instantaneous term, intercept: 20 parameters), one run. Reproduce: `bench/arx_peer.sh`.", "",
         "| implementation | time per fit (median of 51) |", "|---|---|",
         f"| probeloop `fitArx` | {o['seconds'] * 1e3:.3f} ms |",
         f"| {p['peer']} | {p['seconds'] * 1e3:.3f} ms |", "",
         f"Largest coefficient difference: {d:.2e}; largest relative difference of the standard uncertainties: {du:.2e}. "
         f"Speed ratio (statsmodels / probeloop): {p['seconds'] / o['seconds']:.1f}."]
open("bench/results/arx.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
