#!/usr/bin/env bash
# Whole-command benchmark of the virtual machine (issue 4): a 72 h sphere-artifact campaign
# at one cycle per 5 min (seed 004), with a random C-axis duty and a day/night hall
# (examples/truth_campaign.yaml), simulated from the emitted programs in both dialects; and
# the peer a LinuxCNC user would run on the same program: LinuxCNC's own interpreter rs274
# (interpretation only, no physics). Then the evaluation of the simulated log.
# Writes bench/results/simulate.md. Needs a built build/ (scripts/build.sh) and rs274.
set -euo pipefail
cd "$(dirname "$0")/.."
PL=build/cli/probeloop
W=$(mktemp -d /tmp/probeloop-bench-sim.XXXXXX)
trap 'rm -rf "$W"' EXIT
REPS=${REPS:-5}

sed 's/  count: 12/  duration: 72 h/' parts/sphere_artifact.yaml > "$W/art72.yaml"
$PL plan "$W/art72.yaml" --machine parts/machines/nmv5000.yaml --out "$W/fa" > /dev/null
$PL plan "$W/art72.yaml" --machine parts/machines/linuxcnc_rotary_mill.yaml --out "$W/lc" > /dev/null
printf 'T99 P99 Z5.905511811 D0.236220472 ;probe\n' > "$W/tool.tbl"

# Median wall time of REPS runs, in seconds.
timeit() {
  local times=()
  for _ in $(seq "$REPS"); do
    local t0 t1
    t0=$(date +%s.%N); "$@" > /dev/null 2>&1; t1=$(date +%s.%N)
    times+=("$(python3 -c "print(f'{$t1 - $t0:.3f}')")")
  done
  printf '%s\n' "${times[@]}" | sort -g | sed -n "$(( (REPS + 1) / 2 ))p"
}

sim_fa=$(timeit $PL simulate "$W/fa/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part "$W/art72.yaml" \
  --truth examples/truth_campaign.yaml --out "$W/rf")
sim_lc=$(timeit $PL simulate "$W/lc/sphere_cycle.ngc" --machine parts/machines/linuxcnc_rotary_mill.yaml --part "$W/art72.yaml" \
  --truth examples/truth_campaign.yaml --out "$W/rl")
rs274=$(cd "$W/lc" && timeit rs274 -t "$W/tool.tbl" -g sphere_cycle.ngc)
eval_fa=$(timeit $PL evaluate "$W/rf/dprnt.txt" --format fanuc --manifest "$W/fa/plan.json" --out "$W/ef")
cycles=$(python3 -c "import json; print(json.load(open('$W/fa/plan.json'))['schedule']['cycles'])")
events=$(grep -c '^PT' "$W/rf/dprnt.txt")
blocks_lc=$($PL simulate "$W/lc/sphere_cycle.ngc" --machine parts/machines/linuxcnc_rotary_mill.yaml --part "$W/art72.yaml" \
  --truth examples/truth_campaign.yaml --out "$W/rl" | sed -n 's/.*: \([0-9]*\) blocks.*/\1/p')

mkdir -p bench/results
{
  echo "# Virtual machine: 72 h campaign (bench/simulate_campaign.sh)"
  echo
  echo "$(date -u +'%Y-%m-%d %H:%M UTC'), $(nproc) cores, median of $REPS runs, wall time."
  echo
  echo "72 h at one cycle per 5 min: $cycles cycles, $events probe points; LinuxCNC program: $blocks_lc blocks executed."
  echo
  echo "| command | s |"
  echo "|---|---|"
  echo "| probeloop simulate, Fanuc program (NMV 5000), full physics + 4 outputs | $sim_fa |"
  echo "| probeloop simulate, LinuxCNC program (mill), full physics + 4 outputs | $sim_lc |"
  echo "| LinuxCNC rs274 on the same LinuxCNC program (interpretation only) | $rs274 |"
  echo "| probeloop evaluate, the simulated Fanuc log | $eval_fa |"
  echo
  echo "Target (issue 4): the 72 h campaign simulates in < 10 s."
} > bench/results/simulate.md
cat bench/results/simulate.md
