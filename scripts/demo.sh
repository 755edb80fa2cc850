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
echo "Outputs: $OUT/plan (G-code, manifest), $OUT/run (controller log, points.csv, inputs.csv, truth.json),"
echo "         $OUT/eval (errors.csv, evaluation.json, report.md, campaign.gltf), $OUT/machining (cuts.json, cmm_export.csv)"
