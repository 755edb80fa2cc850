#!/usr/bin/env bash
# The campaign store at shop scale (issue 30 item 6): per-cycle cost of `campaign ingest`
# (read the new log lines, store them, evaluate the cycle that became final, commit), and a
# fleet of MACHINES machines x DAYS days of hourly cycles ingested from their logs, one
# ingest per cycle as a live follower would do it. The logs are one simulated year of the
# demo's LinuxCNC sphere cycle (`simulate`, the demo's truth), one machine's log copied per
# machine (every machine ingests the same bytes: the cost does not depend on the values).
# Then the fleet's history: FLEET machines, each ingesting a whole year of hourly cycles from its
# log in one go (a store created after the fact, or a follower catching up). Writes
# bench/results/campaign.md. FLEET=100 is the issue's fleet (about 30 min on 2 cores); the
# defaults measure 2 machines x 7 days live and 4 machine-years, and extrapolate, saying so.
set -euo pipefail
cd "$(dirname "$0")/.."
PL=${PL:-build/cli/probeloop}
[ -x "$PL" ] || scripts/build.sh build >/dev/null
MACHINES=${MACHINES:-2}
DAYS=${DAYS:-7}
FLEET=${FLEET:-4}
JOBS=${JOBS:-$(nproc)}
W=$(mktemp -d /tmp/probeloop-bench-campaign.XXXXXX)
trap 'rm -rf "$W"' EXIT
MILL=parts/machines/linuxcnc_rotary_mill.yaml
CYCLES=$((DAYS * 24))

# One cycle an hour for DAYS days.
sed -e "s/^  count: 12$/  count: $CYCLES/" -e 's/^  gap: .*/  gap: 1 h/' parts/sphere_artifact.yaml > "$W/artifact.yaml"
grep -q "count: $CYCLES" "$W/artifact.yaml"
"$PL" plan "$W/artifact.yaml" --machine "$MILL" --out "$W/plan" >/dev/null
t0=$(date +%s.%N)
"$PL" simulate "$W/plan/sphere_cycle.ngc" --machine "$MILL" --part "$W/artifact.yaml" \
  --truth examples/truth_campaign.yaml --out "$W/run" --seed 1 >/dev/null
t1=$(date +%s.%N)
LOG="$W/run/sphere_probe.log"
per_cycle=$(grep -c '^PT 1\(\.0*\)\? ' "$LOG")
lines=$(wc -l < "$LOG")

# One machine: the log grows a cycle at a time; each growth is ingested.
machine() {  # $1 = machine number
  local d="$W/m$1" i
  mkdir -p "$d"
  "$PL" campaign init "$d/store.campaign" --manifest "$W/plan/plan.json" >/dev/null
  : > "$d/sphere_probe.log"
  for ((i = 0; i < CYCLES; i++)); do
    sed -n "$((i * per_cycle + 1)),$(((i + 1) * per_cycle))p" "$LOG" >> "$d/sphere_probe.log"
    "$PL" campaign ingest "$d/store.campaign" --log "$d/sphere_probe.log" >/dev/null
  done
}
export -f machine
export PL W LOG CYCLES per_cycle

t2=$(date +%s.%N)
seq 1 "$MACHINES" | xargs -P "$JOBS" -I{} bash -c 'machine {}'
t3=$(date +%s.%N)
"$PL" campaign status "$W/m1/store.campaign" > "$W/status.txt"
evaluated=$(sed -n 's/.*cycles: \([0-9]*\) evaluated.*/\1/p' "$W/status.txt")
[ "$evaluated" -ge $((CYCLES - 1)) ] || { cat "$W/status.txt"; echo "bench: cycles missing" >&2; exit 1; }
mkdir -p "$W/fleet" && for m in $(seq 1 "$MACHINES"); do ln "$W/m$m/store.campaign" "$W/fleet/m$m.campaign"; done
t4=$(date +%s.%N)
"$PL" campaign status "$W/fleet" > "$W/fleet.csv"
t5=$(date +%s.%N)
size=$(stat -c %s "$W/m1/store.campaign")

# The fleet's year: one log of 8760 hourly cycles, ingested whole by each machine's store.
sed -e "s/^  count: 12$/  count: 8760/" -e 's/^  gap: .*/  gap: 1 h/' parts/sphere_artifact.yaml > "$W/year.yaml"
"$PL" plan "$W/year.yaml" --machine "$MILL" --out "$W/year-plan" >/dev/null
"$PL" simulate "$W/year-plan/sphere_cycle.ngc" --machine "$MILL" --part "$W/year.yaml" \
  --truth examples/truth_campaign.yaml --out "$W/year-run" --seed 1 >/dev/null
year_machine() {  # $1 = machine number
  local d="$W/y$1"
  mkdir -p "$d"
  "$PL" campaign init "$d/store.campaign" --manifest "$W/year-plan/plan.json" >/dev/null
  "$PL" campaign ingest "$d/store.campaign" --log "$W/year-run/sphere_probe.log" --finished >/dev/null
  rm -f "$d/store.campaign"*
}
export -f year_machine
t6=$(date +%s.%N)
seq 1 "$FLEET" | xargs -P "$JOBS" -I{} bash -c 'year_machine {}'
t7=$(date +%s.%N)

python3 - "$MACHINES" "$DAYS" "$CYCLES" "$JOBS" "$t0" "$t1" "$t2" "$t3" "$t4" "$t5" "$size" "$lines" "$FLEET" "$t6" "$t7" <<'EOF'
import sys
m, days, cycles, jobs = (int(x) for x in sys.argv[1:5])
t0, t1, t2, t3, t4, t5 = (float(x) for x in sys.argv[5:11])
size, lines = int(sys.argv[11]), int(sys.argv[12])
fleet_n, t6, t7 = int(sys.argv[13]), float(sys.argv[14]), float(sys.argv[15])
bulk = t7 - t6
bulk_per_machine = bulk * jobs / fleet_n
bulk_100 = bulk * 100 / fleet_n
fleet = t3 - t2
per = fleet * jobs / (m * cycles)
year = 100 * 365 * 24 * per / jobs
out = f"""# Campaign store: ingest per cycle and a fleet

`bench/campaign_fleet.sh` (MACHINES={m} DAYS={days}, {jobs} parallel ingesters on this machine).
Each machine's LinuxCNC log grows one hourly cycle at a time ({lines // cycles} lines a cycle) and
`campaign ingest` runs after each: read the new lines, store the points, evaluate the cycle that
became final (5 sphere fits, the location errors and their budgets), commit (WAL,
synchronous = FULL: one fsync per ingest).

| quantity | value |
|---|---|
| simulate {cycles} hourly cycles (the log) | {t1 - t0:.1f} s |
| ingest + evaluate + commit, per cycle (one process per ingest) | {per * 1000:.1f} ms |
| {m} machines x {days} days ({m * cycles} cycles) | {fleet:.1f} s wall |
| 100 machines x 1 year (876 000 cycles), extrapolated at this rate on {jobs} cores | {year / 60:.1f} min |
| `campaign status` over the {m} stores | {t5 - t4:.2f} s |
| one machine-year (8760 cycles) ingested in one go | {bulk_per_machine:.1f} s ({bulk_per_machine / 8760 * 1000:.2f} ms a cycle) |
| {fleet_n} machine-years, {jobs} at a time | {bulk:.1f} s wall |
| 100 machines x 1 year in one go each{"" if fleet_n == 100 else ", extrapolated"} | {bulk_100 / 60:.1f} min |
| store size after {cycles} cycles | {size / 1e6:.2f} MB ({size / cycles / 1e3:.1f} kB a cycle) |
"""
open("bench/results/campaign.md", "w").write(out)
print(out)
EOF
