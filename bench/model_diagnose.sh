#!/usr/bin/env bash
# Whole-command benchmark of `probeloop model diagnose` (issue 5 item 8): a 72 h
# sphere-artifact campaign at one cycle per 5 min gap on the virtual machine
# (bench/diagnose_truth.yaml: C-axis duty, day/night hall with a door, coolant on/off,
# production tool changes: 7 channels, 7 varying inputs), an offset-only starting model, the
# artifact-expansion candidates on; against the numpy peer a user would write
# (bench/diagnose_numpy.py) on the same files in the same run. Writes bench/results/diagnose.md.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
ensure_packages python3-numpy
PL=build/cli/probeloop
[ -x $PL ] || scripts/build.sh build >/dev/null
W=$(mktemp -d /tmp/probeloop-bench-diag.XXXXXX)
trap 'rm -rf "$W"' EXIT
sed 's/^  count: 12$/  duration: 72 h/' parts/sphere_artifact.yaml > "$W/art.yaml"
$PL plan "$W/art.yaml" --machine parts/machines/nmv5000.yaml --out "$W/plan" >/dev/null
$PL simulate "$W/plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part "$W/art.yaml" \
  --truth bench/diagnose_truth.yaml --out "$W/run" --seed 1 >/dev/null
$PL evaluate "$W/run/points.csv" --format csv --manifest "$W/plan/plan.json" --out "$W/eval" >/dev/null
{ echo "kind: error_model"; echo "channels:"
  for c in EX0C_um EY0C_um EZ0T_um ER0T_um EA0C_urad EB0C_urad EC0C_urad; do echo "  $c: []"; done; } > "$W/m.yaml"
args=(model diagnose "$W/m.yaml" --inputs "$W/run/inputs.csv" --errors "$W/eval/errors.csv" --part "$W/art.yaml" --json)
times=()
for _ in 1 2 3 4 5; do
  t0=$(date +%s.%N); $PL "${args[@]}" > "$W/d.json"; t1=$(date +%s.%N)
  times+=("$(python3 -c "print(f'{$t1 - $t0:.3f}')")")
done
ours=$(printf '%s\n' "${times[@]}" | sort -g | sed -n 3p)
/usr/bin/python3 bench/diagnose_numpy.py "$W/run/inputs.csv" "$W/eval/errors.csv" > "$W/peer.json"
mkdir -p bench/results
OURS=$ours W=$W python3 - <<'PY'
import json, os
W = os.environ["W"]
d = json.load(open(f"{W}/d.json")); p = json.load(open(f"{W}/peer.json"))
cycles = sum(1 for l in open(f"{W}/eval/errors.csv") if l[0].isdigit())
inputs = open(f"{W}/run/inputs.csv").read().splitlines()[1].split(",")[1:]
lines = ["# Diagnosis of a 72 h campaign", "",
         f"Same files, one run (`bench/model_diagnose.sh`): {cycles} cycles over 72 h, inputs every 60 s "
         f"({len(inputs)} columns: {', '.join(inputs)}), 7 channels, offset-only starting model.", "",
         "| implementation | candidate fits | wall time (median of 5) |", "|---|---|---|",
         f"| `probeloop model diagnose` (whole command: load, 16-point grid + Ceres per time constant, residual tests, ranking, JSON) | {d['candidates_tried']} | {float(os.environ['OURS']):.3f} s |",
         f"| {p['peer']} (candidate scoring only) | {p['fits']} least-squares solves | {p['seconds']:.3f} s |", "",
         f"probeloop's verdict: {d['verdict']}; ranked: " + ", ".join(f"{c['id']} ({c['score']:.1f})" for c in d['candidates'][:4]) + ".", "",
         "Best candidate per channel, validation RMSE before -> after (probeloop | numpy):", ""]
best = {}
for c in d["candidates"]:
    for ch in c["channels"]:
        if ch["channel"] not in best or ch["validation_rmse_after"] < best[ch["channel"]][2]:
            best[ch["channel"]] = (c["id"], ch["validation_rmse_before"], ch["validation_rmse_after"])
for ch, (name, b, a) in sorted(best.items()):
    q = p["top"][ch]
    lines.append(f"- {ch}: {name} {b:.3f} -> {a:.3f} | {q[0]} {q[1]:.3f} -> {q[2]:.3f}")
open("bench/results/diagnose.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
