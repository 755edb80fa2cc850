#!/usr/bin/env bash
# Writes the seeds that come from probeloop's own outputs (fuzz/corpus/<harness>/out_*) and the
# plan manifests the manifest-bound harnesses read (fuzz/fixtures/): plans of the sphere
# artifact (Fanuc on the NMV 5000, LinuxCNC on the rotary mill) and of the thermal test piece,
# their simulated logs, points, inputs and CMM answers (QIF, DMIS), the evaluated errors.
# Long outputs are cut to their first lines (a seed is a start, not a test case), files above
# the harnesses' 64 KiB cap are left out. Usage: fuzz/make_output_seeds.sh [PROBELOOP]
# (default build/cli/probeloop). Run from anywhere; takes a minute or two in a release build.
set -euo pipefail
cd "$(dirname "$0")/.."
PL=$(realpath "${1:-build/cli/probeloop}")
W=$(mktemp -d "${TMPDIR:-/tmp}/probeloop-seeds.XXXXXX")
trap 'rm -rf "$W"' EXIT
C=fuzz/corpus
mkdir -p fuzz/fixtures

seed() {  # seed HARNESS NAME FILE [LINES]
  local h=$1 name=$2 f=$3 n=${4:-}
  [ -f "$f" ] || { echo "make_output_seeds: $f was not written" >&2; exit 1; }
  mkdir -p "$C/$h"
  if [ -n "$n" ]; then head -n "$n" "$f" > "$C/$h/$name"; else cp "$f" "$C/$h/$name"; fi
  if [ "$(stat -c %s "$C/$h/$name")" -gt 65536 ]; then rm "$C/$h/$name"; echo "  (left out $h/$name: above 64 KiB)"; fi
}

"$PL" plan parts/sphere_artifact.yaml --machine parts/machines/nmv5000.yaml --out "$W/plan" >/dev/null
"$PL" plan parts/sphere_artifact.yaml --machine parts/machines/linuxcnc_rotary_mill.yaml --out "$W/plan-lc" >/dev/null
"$PL" plan parts/thermal_test_piece.yaml --machine parts/machines/nmv5000.yaml --out "$W/ttp" >/dev/null
cp "$W/plan-lc/plan.json" fuzz/fixtures/sphere_plan.json
cp "$W/ttp/plan.json" fuzz/fixtures/ttp_plan.json
seed manifest_json out_sphere_plan.json "$W/plan/plan.json"
seed manifest_json out_ttp_plan.json "$W/ttp/plan.json"
seed gcode_fanuc out_sphere_cycle.nc "$W/plan/sphere_cycle.nc"
seed gcode_linuxcnc out_sphere_cycle.ngc "$W/plan-lc/sphere_cycle.ngc"
for p in pre_machining thermal_test inspection; do seed gcode_fanuc "out_$p.nc" "$W/ttp/$p.nc"; done
seed qif out_cmm_plan.qif "$W/ttp/cmm_plan.qif"
seed dmis out_cmm_plan.dmi "$W/ttp/cmm_plan.dmi"
seed ttp_cmm_csv out_cmm_points.csv "$W/ttp/cmm_points.csv" 60

"$PL" simulate "$W/plan-lc/sphere_cycle.ngc" --machine parts/machines/linuxcnc_rotary_mill.yaml \
  --part parts/sphere_artifact.yaml --truth examples/truth_campaign.yaml --out "$W/run-lc" --seed 1 >/dev/null
"$PL" simulate "$W/plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part parts/sphere_artifact.yaml \
  --truth examples/truth_campaign.yaml --out "$W/run" --seed 1 >/dev/null
seed probe_log out_sphere_probe.log "$W/run-lc/sphere_probe.log" 120
seed probe_log out_dprnt.txt "$W/run/dprnt.txt" 120
seed points_csv out_points.csv "$W/run-lc/points.csv" 120
seed inputs_errors_csv out_inputs.csv "$W/run/inputs.csv" 200
"$PL" evaluate "$W/run-lc/points.csv" --format csv --manifest "$W/plan-lc/plan.json" --out "$W/eval" >/dev/null
seed inputs_errors_csv out_errors.csv "$W/eval/errors.csv"

"$PL" simulate "$W/ttp/pre_machining.nc" "$W/ttp/thermal_test.nc" "$W/ttp/inspection.nc" --machine parts/machines/nmv5000.yaml \
  --part parts/thermal_test_piece.yaml --truth examples/truth_thermal_test.yaml --cmm-points "$W/ttp/cmm_plan.qif" \
  --out "$W/ttp-run" --seed 1 >/dev/null
seed ttp_on_machine out_dprnt.txt "$W/ttp-run/dprnt.txt" 150
seed qif out_cmm_results.qif "$W/ttp-run/cmm_results.qif"
seed dmis out_cmm_results.dmo "$W/ttp-run/cmm_results.dmo"
seed ttp_cmm_csv out_cmm_export.csv "$W/ttp-run/cmm_export.csv" 150
# The CMM's results without their points (the features routes, issue 34): QIF and DMIS.
sed -E -e '/<PointList n="[0-9]+">/,/<\/PointList>/d' -e '/<MeasuredPointSets /,/<\/MeasuredPointSets>/d' \
  "$W/ttp-run/cmm_results.qif" > "$W/ttp-run/features.qif"
seed feature_actuals out_features.qif "$W/ttp-run/features.qif"
ls "$W/ttp-run" "$W/run"
echo "make_output_seeds: done"
