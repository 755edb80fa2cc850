#!/usr/bin/env bash
# The main job on the shipped example: plan the sphere-artifact cycle for the thesis's
# machine (seed 004), run it on the test generator with known C-axis location errors,
# evaluate the log, and write the glTF scene. Outputs in out/demo/.
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
echo "== 2. synth: the cycle on a machine whose C axis drifts (examples/truth_rigid.yaml) =="
$PL synth "$OUT/plan/plan.json" --truth examples/truth_rigid.yaml --out "$OUT/run" --seed 1
echo
echo "== 3. evaluate: the Fanuc DPRNT log -> location errors with U (k=2) =="
$PL evaluate "$OUT/run/sphere_probe_dprnt.txt" --format fanuc --manifest "$OUT/plan/plan.json" \
  --out "$OUT/eval" --scene "$OUT/eval/campaign.gltf"
echo
echo "== 4. compare with the injected truth =="
python3 tests/integration/compare_errors.py "$OUT/eval/errors.csv" "$OUT/run/truth.json" 0 0 --within-U \
  && echo "   every value lies within its expanded uncertainty of the injected truth"
echo
echo "Outputs: $OUT/plan (G-code, manifest), $OUT/run (logs, truth), $OUT/eval (errors.csv, evaluation.json, campaign.gltf)"
