#!/usr/bin/env bash
# The live TALC loop's cost (issue 30 item 6): per step and per cycle of `campaign run` on the
# demo's 72 h campaign (616 cycles every 7 min, the demo's truth, Fanuc DPRNT log), the cost
# of starting a run on a full store (the state rebuilt from the stored steps), of the
# dashboard, of one pass after one new cycle (a process per pass, as a cron job would run
# it), and the loop closed on the virtual machine (`simulate --live`, 72 h, CP 24 h, hourly).
# Writes bench/results/campaign_live.md.
set -euo pipefail
cd "$(dirname "$0")/.."
PL=${PL:-build/cli/probeloop}
[ -x "$PL" ] || scripts/build.sh build >/dev/null
W=$(mktemp -d /tmp/probeloop-bench-live.XXXXXX)
trap 'rm -rf "$W"' EXIT
NMV=parts/machines/nmv5000.yaml
now() { date +%s.%N; }
secs() { python3 -c "print(f'{$2 - $1:.3f}')"; }

sed 's/^  count: 12$/  duration: 72 h/' parts/sphere_artifact.yaml > "$W/a.yaml"
"$PL" plan "$W/a.yaml" --machine "$NMV" --out "$W/plan" >/dev/null
"$PL" simulate "$W/plan/sphere_cycle.nc" --machine "$NMV" --part "$W/a.yaml" --truth examples/truth_campaign.yaml \
  --out "$W/run" --seed 1 >/dev/null
S="$W/s.campaign"
"$PL" campaign init "$S" --manifest "$W/plan/plan.json" >/dev/null
t0=$(now)
"$PL" campaign ingest "$S" --log "$W/run/dprnt.txt" --inputs "$W/run/inputs.csv" --finished >/dev/null
t1=$(now)
"$PL" campaign run "$S" --finished --cp-h 36 > "$W/run.txt"
t2=$(now)
steps=$(python3 -c "import sqlite3; d = sqlite3.connect('$S'); print(d.execute('SELECT COUNT(*) FROM talc_ticks').fetchone()[0] + d.execute('SELECT COUNT(*) FROM talc_measurements').fetchone()[0])")
cycles=$(python3 -c "import sqlite3; d = sqlite3.connect('$S'); print(d.execute('SELECT COUNT(*) FROM talc_measurements').fetchone()[0])")
"$PL" campaign run "$S" --finished --cp-h 36 >/dev/null
t3=$(now)
"$PL" campaign run "$S" --finished --cp-h 36 --html "$W/dash.html" --controller-file "$W/c.json" >/dev/null
t4=$(now)

# One pass after each of the last 20 cycles, a process per pass (ingest, evaluate, TALC steps,
# dashboard, controller file).
P="$W/p.campaign"
"$PL" campaign init "$P" --manifest "$W/plan/plan.json" >/dev/null
per=$(grep -c '^PT *1 ' "$W/run/dprnt.txt")
total=$(grep -c '^PT' "$W/run/dprnt.txt")
first=$((total - 20 * per))
head -n $((first + 2)) "$W/run/dprnt.txt" > "$W/grow.log"   # the % and START lines first
cp "$W/run/inputs.csv" "$W/grow.csv"
"$PL" campaign run "$P" --log "$W/grow.log" --inputs "$W/grow.csv" --cp-h 36 >/dev/null
t5=$(now)
for i in $(seq 1 20); do
  sed -n "$((first + 2 + (i - 1) * per + 1)),$((first + 2 + i * per))p" "$W/run/dprnt.txt" >> "$W/grow.log"
  "$PL" campaign run "$P" --log "$W/grow.log" --inputs "$W/grow.csv" --cp-h 36 \
    --html "$W/dash2.html" --controller-file "$W/c2.json" >/dev/null
done
t6=$(now)

# Closed on the virtual machine.
sed 's/^  count: 12$/  duration: 72 h\n  live_interval: true/' parts/sphere_artifact.yaml > "$W/l.yaml"
"$PL" plan "$W/l.yaml" --machine "$NMV" --out "$W/lplan" >/dev/null
"$PL" campaign init "$W/l.campaign" --manifest "$W/lplan/plan.json" >/dev/null
t7=$(now)
"$PL" simulate "$W/lplan/sphere_cycle.nc" --machine "$NMV" --part "$W/l.yaml" --truth examples/truth_campaign.yaml \
  --out "$W/lrun" --seed 1 --live "$W/l.campaign" --cp-h 24 --post-interval-h 1 --until-h 72 > "$W/live.txt"
t8=$(now)
syncs=$(sed -n 's/.*(\([0-9]*\) syncs).*/\1/p' "$W/live.txt")
lcycles=$(sed -n 's/.*; \([0-9]*\) cycles measured.*/\1/p' "$W/live.txt")

mkdir -p bench/results
{
  echo "# The live TALC loop: cost per step, per cycle, per pass"
  echo
  echo "\`bench/campaign_live.sh\` on this machine ($(nproc) cores). The demo's 72 h campaign: $cycles cycles"
  echo "(every 7 min, Fanuc DPRNT log), CP 36 h; a step is a grid step (prediction issued) or a"
  echo "measurement fed, each its own transaction (WAL, synchronous = FULL: one fsync per step)."
  echo
  echo "| quantity | value |"
  echo "|---|---|"
  echo "| ingest + evaluate the 72 h log (616 cycles, one transaction) | $(secs "$t0" "$t1") s |"
  echo "| \`campaign run\` over it: $steps steps | $(secs "$t1" "$t2") s ($(python3 -c "print(f'{($t2 - $t1) / $steps * 1000:.2f}')") ms a step, $(python3 -c "print(f'{($t2 - $t1) / $cycles * 1000:.2f}')") ms a cycle) |"
  echo "| start a run on the full store, nothing new (the state rebuilt from its steps) | $(secs "$t2" "$t3") s |"
  echo "| the same with the dashboard ($(du -k "$W/dash.html" | cut -f1) kB) and the controller file | $(secs "$t3" "$t4") s |"
  echo "| one pass after one new cycle, a process per pass (ingest, evaluate, TALC, dashboard, controller file; mean of 20 at the campaign's end) | $(python3 -c "print(f'{($t6 - $t5) / 20 * 1000:.0f}')") ms |"
  echo "| \`simulate --live\`: 72 h closed on the virtual machine ($lcycles cycles, $syncs syncs of the store: after every input sample and cycle) | $(secs "$t7" "$t8") s |"
  echo
  echo "A run that follows (\`--follow\`) keeps the state in memory: a pass costs its new steps and"
  echo "the dashboard, not the rebuild. The rebuild replays every stored step's fits; it grows with"
  echo "the campaign (a year of hourly cycles: about 9000 steps)."
} > bench/results/campaign_live.md
cat bench/results/campaign_live.md
