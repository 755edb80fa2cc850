#!/usr/bin/env bash
# The main job on the shipped example: plan the sphere-artifact cycle for the thesis's
# machine (seed 004), run the emitted program on the virtual machine (thermal network, C-axis
# duty, day/night hall, probe physics, tool changes: examples/truth_campaign.yaml), evaluate
# the controller log, compare with the injected truth, and write the glTF scene.
# Outputs in out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh build >/dev/null
PL=build/cli/probeloop
OUT=out/demo
rm -rf "$OUT"; mkdir -p "$OUT"
echo "== 1. plan: parts/sphere_artifact.yaml on parts/machines/nmv5000.yaml =="
$PL plan parts/sphere_artifact.yaml --machine parts/machines/nmv5000.yaml --out "$OUT/plan"
$PL plan parts/sphere_artifact.yaml --machine parts/machines/linuxcnc_rotary_mill.yaml --out "$OUT/plan-linuxcnc" >/dev/null
echo "   (also the LinuxCNC program: $OUT/plan-linuxcnc/sphere_cycle.ngc)"
echo
echo "== 2. simulate: the Fanuc program on the virtual machine (examples/truth_campaign.yaml) =="
$PL simulate "$OUT/plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part parts/sphere_artifact.yaml \
  --truth examples/truth_campaign.yaml --out "$OUT/run" --seed 1
$PL simulate "$OUT/plan-linuxcnc/sphere_cycle.ngc" --machine parts/machines/linuxcnc_rotary_mill.yaml \
  --part parts/sphere_artifact.yaml --truth examples/truth_campaign.yaml --out "$OUT/run-linuxcnc" --seed 1 >/dev/null
echo "   (also the LinuxCNC program on the LinuxCNC mill: $OUT/run-linuxcnc/sphere_probe.log)"
echo
echo "== 3. evaluate: the Fanuc DPRNT log -> location errors with U (k=2) =="
$PL evaluate "$OUT/run/dprnt.txt" --format fanuc --manifest "$OUT/plan/plan.json" \
  --out "$OUT/eval" --scene "$OUT/eval/campaign.gltf"
echo "   Uncertainty budgets (out/demo/eval/report.md; every term in docs/uncertainty.md):"
awk '/^## Range of U/{on=1; next} /^## /{on=0} on && NF' "$OUT/eval/report.md" | sed 's/^/   /'
echo
echo "== 4. compare with the injected truth (truth.json: what the simulator put in) =="
python3 tests/integration/compare_errors.py "$OUT/eval/errors.csv" "$OUT/run/truth.json" 0 0 --coverage
echo
echo "== 5. machining on the virtual VMC: face and side-mill a block, then the CMM (examples/truth_machining.yaml) =="
$PL simulate examples/block_face_and_wall.ngc --machine parts/machines/vmc3.yaml --part examples/workpiece_block.yaml \
  --truth examples/truth_machining.yaml --cmm-points examples/block_cmm_points.csv --out "$OUT/machining"
$PL fit plane "$OUT/machining/cmm_export.csv" --feature TOP | sed -n '1p;4p;9p'
$PL fit plane "$OUT/machining/cmm_export.csv" --feature WALL_X | sed -n '1,2p;9p'
echo "   (the top is faced deep by the spindle's growth; the wall stands proud by the tool's deflection: cuts.json)"
echo
echo "== 6. model: 72 h of the same machine against a static temperature map (examples/model/start.yaml) =="
C=$OUT/campaign
mkdir -p "$C"
sed 's/^  count: 12$/  duration: 72 h/' parts/sphere_artifact.yaml > "$C/artifact.yaml"
$PL plan "$C/artifact.yaml" --machine parts/machines/nmv5000.yaml --out "$C/plan" >/dev/null
$PL simulate "$C/plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part "$C/artifact.yaml" \
  --truth examples/truth_campaign.yaml --out "$C/run" --seed 1 >/dev/null
# The canonical points carry each trigger's time (a DPRNT log does not; docs/model.md#data).
$PL evaluate "$C/run/points.csv" --format csv --manifest "$C/plan/plan.json" --out "$C/eval" >/dev/null
{ echo "data: {inputs: run/inputs.csv, errors: eval/errors.csv}"; cat examples/model/start.yaml; } > "$C/model.yaml"
echo "   $(grep -c '^[0-9]' "$C/eval/errors.csv") cycles, inputs every 60 s: $C/run/inputs.csv, $C/eval/errors.csv"
export PATH="$PWD/build/cli:$PATH"   # the printed commands start with 'probeloop'
for round in 1 2; do
  echo "-- diagnose (round $round): where the model fails, what is missing --"
  probeloop model diagnose "$C/model.yaml" --part "$C/artifact.yaml" --report "$C/diagnosis-$round.html" > "$C/diagnosis-$round.txt"
  sed -n '/^  channel/,/^$/p' "$C/diagnosis-$round.txt" | grep -v '|residual|' | sed 's/^/   /'
  sed -n '/^1\. /,/add it:/p' "$C/diagnosis-$round.txt" | sed 's/^/   /'
  cmd=$(sed -n 's/^   add it: //p' "$C/diagnosis-$round.txt" | head -1)
  [ -n "$cmd" ] || { grep -v '^ ' "$C/diagnosis-$round.txt" | tail -1; break; }
  echo "-- add it, as printed: $cmd"
  eval "$cmd" >/dev/null
  probeloop model fit "$C/model.yaml" --report "$C/fit-$round.html" --json "$C/fit-$round.json" > "$C/fit-$round.txt"
  sed -n '/^Before -> after/,$p' "$C/fit-$round.txt" | sed 's/^/   /'
done
echo "-- diagnose (final) --"
probeloop model diagnose "$C/model.yaml" --part "$C/artifact.yaml" --report "$C/diagnosis-final.html" |
  grep -v '^Wrote' | grep . | tail -1 | fold -s -w 100 | sed 's/^/   /'
echo "-- TALC replay (seed 004 Ch. 6) on the same campaign, a 36 h calibration phase (it holds the door event at 30 h) --"
probeloop model talc --inputs "$C/run/inputs.csv" --errors "$C/eval/errors.csv" --cp-h 36 | sed -n '5,8p' | sed 's/^/   /'
echo
echo "Outputs: $OUT/plan (G-code, manifest), $OUT/run (controller log, points.csv, inputs.csv, truth.json),"
echo "         $OUT/eval (errors.csv, evaluation.json, report.md, campaign.gltf), $OUT/machining (cuts.json, cmm_export.csv),"
echo "         $OUT/campaign (72 h: model.yaml, diagnosis-*.html, fit-*.html with the plots)"
