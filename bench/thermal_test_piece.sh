#!/usr/bin/env bash
# Whole-command benchmark of the thermal test piece (issue 13): plan, simulate (pre-machining,
# the 8 h test, the inspection and the CMM) and evaluate both routes, median of 5 each; against
# the peers a user would otherwise run on the same files in the same run: LinuxCNC's rs274
# interpreting the three LinuxCNC programs (interpretation only, no physics), and the numpy
# evaluation a metrologist would write (bench/ttp_numpy.py: values, no budgets), whose E values
# are compared with ours. Writes bench/results/thermal_test_piece.md.
set -euo pipefail
cd "$(dirname "$0")/.."
. bench/common.sh
ensure_packages python3-numpy linuxcnc-uspace
PL=build/cli/probeloop
[ -x $PL ] || scripts/build.sh build >/dev/null
W=$(mktemp -d /tmp/probeloop-bench-ttp.XXXXXX)
trap 'rm -rf "$W"' EXIT
NMV=parts/machines/nmv5000.yaml
PIECE=parts/thermal_test_piece.yaml

median() {  # median wall time of 5 runs of a command, s
  local times=() t0 t1
  for _ in 1 2 3 4 5; do
    t0=$(date +%s.%N); "$@" >/dev/null 2>&1; t1=$(date +%s.%N)
    times+=("$(python3 -c "print(f'{$t1 - $t0:.4f}')")")
  done
  printf '%s\n' "${times[@]}" | sort -g | sed -n 3p
}

t_plan=$(median $PL plan $PIECE --machine $NMV --out "$W/fa")
$PL plan $PIECE --machine $NMV --dialect linuxcnc --out "$W/lc" >/dev/null
progs=("$W/fa/pre_machining.nc" "$W/fa/thermal_test.nc" "$W/fa/inspection.nc")
sim=(simulate "${progs[@]}" --machine $NMV --part $PIECE --truth examples/truth_thermal_test.yaml
     --cmm-points "$W/fa/cmm_points.csv" --out "$W/run" --seed 1)
t_sim=$(median $PL "${sim[@]}")
t_cmm=$(median $PL evaluate "$W/run/cmm_export.csv" --manifest "$W/fa/plan.json" --out "$W/cmm")
t_om=$(median $PL evaluate "$W/run/dprnt.txt" --manifest "$W/fa/plan.json" --out "$W/om")
# rs274 reads tool lengths in inches (docs/sphere-cycle.md): the piece's tools and the probe.
python3 - "$PIECE" "$NMV" > "$W/tool.tbl" <<'PY'
import re, sys
for n, body in re.findall(r"\{number: (\d+),(.*?)\}", open(sys.argv[1]).read(), re.S):
    print(f"T{n} P{n} Z{float(re.search(r'[ ,]length: ([0-9.]+) mm', body).group(1)) / 25.4:.9f}")
probe = re.search(r"\nprobe:\n  tool: (\d+)\n  length: ([0-9.]+) mm", open(sys.argv[2]).read())
print(f"T{probe.group(1)} P{probe.group(1)} Z{float(probe.group(2)) / 25.4:.9f}")
PY
rs274_all() { for p in pre_machining thermal_test inspection; do (cd "$W/lc" && rs274 -t "$W/tool.tbl" -g $p.ngc >/dev/null); done; }
t_rs274=$(median rs274_all)
t_numpy=$(median /usr/bin/python3 bench/ttp_numpy.py "$W/run/cmm_export.csv" "$W/fa/plan.json")
/usr/bin/python3 bench/ttp_numpy.py "$W/run/cmm_export.csv" "$W/fa/plan.json" > "$W/peer.json"
summary=$($PL "${sim[@]}" | head -1)
blocks=$(echo "$summary" | sed -n 's/.*: \([0-9]*\) blocks.*/\1/p')
events=$(echo "$summary" | sed -n 's/.*blocks, \([0-9]*\) probe events.*/\1/p')
hours=$(echo "$summary" | sed -n 's/.*events, \([0-9.]*\) h of machine time.*/\1/p')
cmm_points=$(grep -vc '^#\|^feature' "$W/run/cmm_export.csv")

mkdir -p bench/results
T_PLAN=$t_plan T_SIM=$t_sim T_CMM=$t_cmm T_OM=$t_om T_RS274=$t_rs274 T_NUMPY=$t_numpy BLOCKS=$blocks EVENTS=$events \
  HOURS=$hours CMM_POINTS=$cmm_points W=$W python3 - <<'PY'
import csv, json, os, platform
e = os.environ
W = e["W"]
peer = json.load(open(f"{W}/peer.json"))
ours = {int(r["cycle"]): r for r in csv.DictReader(l for l in open(f"{W}/cmm/errors.csv") if not l.startswith("#"))}
worst = max(abs(c[q] - float(ours[c["cycle"]][q])) for c in peer["cycles"] for q in ("EX_um", "EY_um", "EZ_um", "EB_urad", "ETTP_um"))
cpu = next((l.split(":")[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.machine())
lines = ["# The thermal test piece (issue 13)", "",
         f"Reproduce: `bench/thermal_test_piece.sh`. {os.cpu_count()} CPUs ({cpu}). The shipped piece on the NMV 5000 "
         f"(parts/thermal_test_piece.yaml, examples/truth_thermal_test.yaml): 3 programs, {e['BLOCKS']} blocks, {e['HOURS']} h of "
         f"machine time, {e['EVENTS']} probed points, {e['CMM_POINTS']} CMM points. Median wall time of 5 runs of the whole command.", "",
         "| command | s |", "|---|---|",
         f"| `probeloop plan` (three programs, manifest, CMM plan, predicted U) | {float(e['T_PLAN']):.3f} |",
         f"| `probeloop simulate` (pre-machining, the 8 h test, the inspection, the CMM; truth) | {float(e['T_SIM']):.3f} |",
         f"| LinuxCNC rs274 on the same three programs (LinuxCNC dialect), interpretation only | {float(e['T_RS274']):.3f} |",
         f"| `probeloop evaluate`, CMM export (frame, fits, E, budgets, three files) | {float(e['T_CMM']):.3f} |",
         f"| `probeloop evaluate`, on-machine DPRNT log | {float(e['T_OM']):.3f} |",
         f"| {peer['peer']}: the same evaluation without budgets (bench/ttp_numpy.py, whole command incl. start-up) | {float(e['T_NUMPY']):.3f} |",
         f"| the same, evaluation only (in-process, reading included) | {peer['seconds']:.4f} |", "",
         f"The numpy peer's E_X, E_Y, E_Z, E_B, E_TTP agree with probeloop's to {worst:.1e} (um, urad), "
         "the 0.1 nm errors.csv prints: the datum frame, the distances, the depths, the angles and the formulas are "
         "the same quantities computed independently."]
open("bench/results/thermal_test_piece.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
PY
