#!/usr/bin/env bash
# The main job on the shipped examples: plan the sphere-artifact cycle for the thesis's
# machine (seed 004), run the emitted program on the virtual machine (thermal network, C-axis
# duty, day/night hall, probe physics, tool changes: examples/truth_campaign.yaml), evaluate
# the controller log, compare with the injected truth, and write the HTML report and the glTF
# scene; machine a block; fit and diagnose an error model on 72 h; then the thermal test piece of seed 004
# Ch. 7 from its description to E_X ... E_TTP with U, the R-test beside it and the model.
# Outputs in out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# Only the command line is built (the tests are scripts/test.sh's); an existing build/ is reused.
echo "== 0. build: the probeloop command line into build/ (from scratch about 7 min on 2 cores; reused after) =="
t_build=$SECONDS
build_log=$(mktemp)
set +e   # the build's own exit status, not the progress filter's
TARGET=probeloop scripts/build.sh build 2>&1 | tee "$build_log" |
  awk '/^\[[0-9]+\/[0-9]+\]/ && ++n % 10 == 0 {print "   " $1 " compiled"; fflush()}'
rc=${PIPESTATUS[0]}
set -e
[ "$rc" = 0 ] || { tail -30 "$build_log" >&2; echo "demo.sh: the build failed (above)" >&2; exit 1; }
rm -f "$build_log"
echo "   $(build/cli/probeloop --version), built in $((SECONDS - t_build)) s"
echo
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
# The page: the seven errors against time with U bands, budgets, schedule, temperatures and loads.
$PL report sphere --evaluation "$OUT/eval/evaluation.json" --inputs "$OUT/run/inputs.csv" --manifest "$OUT/plan/plan.json" \
  --scene "$OUT/eval/campaign.gltf" --html "$OUT/eval/report.html" | sed 's/^Wrote /   wrote /'
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
$PL report sphere --evaluation "$C/eval/evaluation.json" --inputs "$C/run/inputs.csv" --manifest "$C/plan/plan.json" \
  --html "$C/report.html" | sed 's/^Wrote /   wrote /'
export PATH="$PWD/build/cli:$PATH"   # the printed commands start with 'probeloop'
for round in 1 2; do
  echo "-- diagnose (round $round): where the model fails, what is missing --"
  probeloop model diagnose "$C/model.yaml" --part "$C/artifact.yaml" --html "$C/diagnosis-$round.html" > "$C/diagnosis-$round.txt"
  sed -n '/^  channel/,/^$/p' "$C/diagnosis-$round.txt" | grep -v '|residual|' | sed 's/^/   /'
  sed -n '/^1\. /,/add it:/p' "$C/diagnosis-$round.txt" | sed 's/^/   /'
  cmd=$(sed -n 's/^   add it: //p' "$C/diagnosis-$round.txt" | head -1)
  [ -n "$cmd" ] || { grep -v '^ ' "$C/diagnosis-$round.txt" | tail -1; break; }
  echo "-- add it, as printed: $cmd"
  eval "$cmd" >/dev/null
  probeloop model fit "$C/model.yaml" --html "$C/fit-$round.html" > "$C/fit-$round.txt"
  sed -n '/^Before -> after/,$p' "$C/fit-$round.txt" | sed 's/^/   /'
done
echo "-- diagnose (final) --"
probeloop model diagnose "$C/model.yaml" --part "$C/artifact.yaml" --html "$C/diagnosis-final.html" |
  grep -v '^Wrote' | grep . | tail -1 | fold -s -w 100 | sed 's/^/   /'
echo "-- TALC replay (seed 004 Ch. 6) on the same campaign, a 36 h calibration phase (it holds the door event at 30 h) --"
probeloop model talc --inputs "$C/run/inputs.csv" --errors "$C/eval/errors.csv" --cp-h 36 | sed -n '5,8p' | sed 's/^/   /'
echo "-- TALC live, closed on the virtual machine (docs/live_loop.md): the cycle paced through #500, the offsets of"
echo "   seed 004 Eqs. 6.3-6.5 applied as the machine runs; CP 24 h, then hourly; the door at 30 h starts a No-Good phase --"
sed 's/^  count: 12$/  duration: 72 h\n  live_interval: true/' parts/sphere_artifact.yaml > "$C/live.yaml"
$PL plan "$C/live.yaml" --machine parts/machines/nmv5000.yaml --out "$C/live-plan" >/dev/null
$PL campaign init "$C/live.campaign" --manifest "$C/live-plan/plan.json" >/dev/null
$PL simulate "$C/live-plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part "$C/live.yaml" \
  --truth examples/truth_campaign.yaml --out "$C/live" --seed 1 --live "$C/live.campaign" --cp-h 24 --post-interval-h 1 \
  --until-h 72 | tail -4 | sed 's/^/   /'
echo "   events: $(python3 -c "import sqlite3; print('; '.join(f'{t / 3600:.1f} h {a}' for t, a in sqlite3.connect('$C/live.campaign').execute('SELECT t_s, action FROM talc_events ORDER BY seq')))")"
echo "   dashboard: $C/live/live/dashboard.html (store: $C/live.campaign)"
echo
echo "== 7. the thermal test piece (seed 004 Ch. 7): plan -> 8 h on the virtual machine -> CMM and on-machine -> E with U =="
T=$OUT/ttp
$PL plan parts/thermal_test_piece.yaml --machine parts/machines/nmv5000.yaml --out "$T/plan" | sed -n '1,11p' | sed 's/^/   /'
$PL simulate "$T/plan/pre_machining.nc" "$T/plan/thermal_test.nc" "$T/plan/inspection.nc" --machine parts/machines/nmv5000.yaml \
  --part parts/thermal_test_piece.yaml --truth examples/truth_thermal_test.yaml --cmm-points "$T/plan/cmm_plan.qif" \
  --out "$T/run" --seed 1 | sed 's/^/   /'
echo "   the CMM read the QIF 3.0 plan and answered in QIF and DMIS (docs/interop.md):"
$PL read "$T/run/cmm_results.qif" | head -1 | sed 's/^/     /'
$PL read "$T/run/cmm_results.dmo" | head -1 | sed 's/^/     /'
$PL evaluate "$T/run/cmm_results.qif" --manifest "$T/plan/plan.json" --out "$T/cmm" --scene "$T/cmm/test_piece.gltf" |
  sed -n '1,12p' | sed 's/^/   /'
$PL evaluate "$T/run/dprnt.txt" --manifest "$T/plan/plan.json" --out "$T/om" > /dev/null
echo "   E_Y and E_TTP against the injected values (as cut; route 1 CMM, route 2 on the machine):"
python3 tests/integration/compare_ttp.py "$T/run/truth.json" "$T/cmm/errors.csv" "$T/om/errors.csv" |
  awk '/^  EY_um|^  ETTP_um/{on=1} /^  EZ_um|^  EB_urad/{on=0} on || /route [12] \(/' | sed 's/^/   /'
echo "-- the R-test beside it (the sphere cycle of step 1, hourly, under the same C load; seed 004 Fig. 7.10) --"
R=$T/r-test
mkdir -p "$R"
sed -e 's/^  count: 12$/  count: 9/' -e 's/^  gap: 5 min .*/  gap: 3480 s/' parts/sphere_artifact.yaml > "$R/artifact.yaml"
$PL plan "$R/artifact.yaml" --machine parts/machines/nmv5000.yaml --out "$R/plan" > /dev/null
# The same physics with the steel sphere on the table, and the test's load as a duty: 4 h of C at
# 1200 rpm from the end of the first sphere cycle, as the piece's warm-up starts after its references.
t1=$(python3 -c "import json; print(round(json.load(open('$R/plan/plan.json'))['schedule']['cycle_time_s']))")
{ sed 's/^artifact: .*/artifact: {node: table, alpha_um_per_m_K: 11.5}/' examples/truth_thermal_test.yaml
  printf 'duty:\n  c_axis:\n    profile:\n      - {at: 0 s, speed: 0 rpm}\n      - {at: %s s, speed: 1200 rpm}\n      - {at: %s s, speed: 0 rpm}\n' \
    "$t1" "$((t1 + 14400))"; } > "$R/truth.yaml"
$PL simulate "$R/plan/sphere_cycle.nc" --machine parts/machines/nmv5000.yaml --part "$R/artifact.yaml" \
  --truth "$R/truth.yaml" --out "$R/run" --seed 1 > /dev/null
$PL evaluate "$R/run/points.csv" --manifest "$R/plan/plan.json" --out "$R/eval" > /dev/null
# On the piece's clock: the R-test's load starts where the piece's warm-up starts.
shift=$(python3 -c "import json; print(json.load(open('$T/plan/plan.json'))['cycles'][0]['end_s'] - $t1)")
awk -F, -v OFS=, -v s="$shift" '/^#/ || /^time_s/ {print; next} {$1 = $1 + s; print}' "$R/eval/errors.csv" > "$R/errors_on_piece_clock.csv"
$PL report ttp --evaluation "$T/cmm/evaluation.json" --second "$T/om/evaluation.json" --r-test "$R/errors_on_piece_clock.csv" \
  --inputs "$T/run/inputs.csv" --html "$T/report.html" | sed 's/^/   /'
echo "-- the model: what the table-side model misses on the piece (seed 004 L2226) --"
{ echo "data: {inputs: run/inputs.csv, errors: cmm/errors.csv}"; cat <<'Y'
kind: error_model
channels:
  EX_um: []
  EY_um: [{effect: static, input: T_caxis_C}]
  EZ_um: [{effect: static, input: T_caxis_C}]
  ETTP_um: []
Y
} > "$T/model.yaml"
probeloop model diagnose "$T/model.yaml" --part parts/thermal_test_piece.yaml > "$T/diagnosis.txt"
sed -n '/^1\. /,/add it:/p' "$T/diagnosis.txt" | sed 's/^/   /'
cmd=$(sed -n 's/^   add it: //p' "$T/diagnosis.txt" | head -1)
echo "-- add it, as printed: $cmd"
eval "$cmd" > /dev/null
probeloop model fit "$T/model.yaml" --html "$T/fit.html" > "$T/fit.txt"
sed -n '/^Before -> after/,$p' "$T/fit.txt" | grep -E 'Before|channel|ETTP' | sed 's/^/   /'

echo "== 8. the stepped workpiece (seed 000): the programs of W8, each step's Temp state, W8 on the virtual VMC, the separation =="
S=$OUT/stepped
$PL plan parts/stepped_workpiece.yaml --machine parts/machines/vmc3.yaml --out "$S/plan" --experiment W8 | sed 's/^/   /'
$PL simulate "$S/plan/roughing.ngc" "$S/plan/finishing.ngc" "$S/plan/probing.ngc" --machine parts/machines/vmc3.yaml \
  --part parts/stepped_workpiece.yaml --truth examples/stepped_workpiece/truth.yaml --cmm-points "$S/plan/cmm_points.csv" \
  --schedule "$S/plan/plan.json" --out "$S/run" | sed 's/^/   /'
echo "-- CMM - probe, process and spindle errors per step (truth: 0.15 / 0.25 um/mm; the rest in $S/run/truth.json)"
$PL evaluate "$S/run/cmm_export.csv" --probe-log "$S/run/sw_probe.log" --manifest "$S/plan/plan.json" --out "$S/eval" | sed 's/^/   /'
echo "-- compensation (Ch. 6): the predicted errors out of the finishing path, W8 cut again, before/after"
$PL plan parts/stepped_workpiece.yaml --machine parts/machines/vmc3.yaml --out "$S/plan-compensated" --experiment W8 \
  --compensate "$S/eval/compensation.json" | sed -n '/^Compensated/,/^Steps/p' | sed '$d' | sed 's/^/   /'
$PL simulate "$S/plan-compensated/roughing.ngc" "$S/plan-compensated/finishing.ngc" "$S/plan-compensated/probing.ngc" \
  --machine parts/machines/vmc3.yaml --part parts/stepped_workpiece.yaml --truth examples/stepped_workpiece/truth.yaml \
  --cmm-points "$S/plan-compensated/cmm_points.csv" --schedule "$S/plan-compensated/plan.json" --seed 2 --out "$S/run-compensated" > /dev/null
$PL evaluate "$S/run-compensated/cmm_export.csv" --probe-log "$S/run-compensated/sw_probe.log" \
  --manifest "$S/plan-compensated/plan.json" --compare "$S/eval/evaluation.json" --out "$S/eval-compensated" | grep -A13 'against' | sed 's/^/   /'
# Both parts side by side: the plain part's numbers as printed above, the compensated part's before/after with U.
$PL report stepped --evaluation "$S/eval/evaluation.json" --compensated "$S/eval-compensated/evaluation.json" \
  --html "$S/report.html" | sed 's/^/   /'
echo "-- the campaign (Sec. 3.5-3.6): thermal stages W6 / W1 / W7 (1000 / 3500 / 5500 rpm), W8's process error without them,"
echo "   the control errors of W2 (transitions at 1200 mm/min) and W5 (one continuous path) against W8"
sw_part() {  # DIR EXPERIMENT SEED: plan, cut on the virtual VMC (its waits), CMM + probe log, evaluate
  $PL plan parts/stepped_workpiece.yaml --machine parts/machines/vmc3.yaml --out "$1/plan" --experiment "$2" > /dev/null
  $PL simulate "$1/plan/roughing.ngc" "$1/plan/finishing.ngc" "$1/plan/probing.ngc" --machine parts/machines/vmc3.yaml \
    --part parts/stepped_workpiece.yaml --truth examples/stepped_workpiece/truth.yaml --cmm-points "$1/plan/cmm_points.csv" \
    --schedule "$1/plan/plan.json" --seed "$3" --out "$1/run" > /dev/null
  $PL evaluate "$1/run/cmm_export.csv" --probe-log "$1/run/sw_probe.log" --manifest "$1/plan/plan.json" --out "$1/eval" > /dev/null
}
seed=11
for W in W6 W1 W7 W2 W5; do
  sw_part "$S/$W" $W $seed
  seed=$((seed + 1))
done
$PL separate --stage "$S/W6/eval/evaluation.json" --stage "$S/W1/eval/evaluation.json" --stage "$S/W7/eval/evaluation.json" \
  --process "$S/eval/evaluation.json" --control "$S/W2/eval/evaluation.json" --force "$S/W5/eval/evaluation.json" \
  --out "$S/separation" | grep -v '^    ' | sed 's/^/   /'
echo "-- W3 (speeds 3500 / 5500 / 1000 / 3500 rpm step by step) predicted from the campaign"
$PL plan parts/stepped_workpiece.yaml --machine parts/machines/vmc3.yaml --out "$S/W3/plan" --experiment W3 \
  --predict-from "$S/separation/separation.json" | sed -n '/^Compensated/,/^Steps/p' | sed '$d' | sed 's/^/   /'
echo "-- the model loop (§9.1 item 10): W8, W6, W1, W7 and W3 cut plain as one series, from the position error only;"
echo "   each round adds what the diagnosis names first (its printed command)"
sw_part "$S/W3plain" W3 14
$PL model series --part "$S/eval/evaluation.json" "$S/run/inputs.csv" --part "$S/W6/eval/evaluation.json" "$S/W6/run/inputs.csv" \
  --part "$S/W1/eval/evaluation.json" "$S/W1/run/inputs.csv" --part "$S/W7/eval/evaluation.json" "$S/W7/run/inputs.csv" \
  --part "$S/W3plain/eval/evaluation.json" "$S/W3plain/run/inputs.csv" --out "$S/series" | sed 's/^/   /'
loop_rounds() {  # DIR: add what the diagnosis names first while its score is >= 1
  for round in 1 2 3 4; do
    $PL model diagnose "$1/model.yaml" > "$1/diagnosis-$round.txt"
    cmd=$(sed -n 's/^   add it: //p' "$1/diagnosis-$round.txt" | head -1)
    [ -n "$cmd" ] || break
    score=$(sed -n 's/^1\. .*(score \([0-9.]*\)).*/\1/p' "$1/diagnosis-$round.txt")
    awk -v s="$score" 'BEGIN { exit !(s >= 1) }' || break
    echo "   round $round: $(sed -n 's/^1\. //p' "$1/diagnosis-$round.txt")"
    $PL ${cmd#probeloop } > /dev/null
    $PL model fit "$1/model.yaml" | grep -E '^[a-z_]+_um  |validation  |validation, before' | sed 's/^/     /'
  done
}
loop_rounds "$S/series"
echo "-- the campaign grows (the control round): W2 (walls joined at 1200 mm/min) trains, a repeat of W2 validates;"
echo "   the model goes on from where the loop ended"
sw_part "$S/W2repeat" W2 15
$PL model series --part "$S/eval/evaluation.json" "$S/run/inputs.csv" --part "$S/W6/eval/evaluation.json" "$S/W6/run/inputs.csv" \
  --part "$S/W1/eval/evaluation.json" "$S/W1/run/inputs.csv" --part "$S/W2/eval/evaluation.json" "$S/W2/run/inputs.csv" \
  --part "$S/W7/eval/evaluation.json" "$S/W7/run/inputs.csv" --part "$S/W2repeat/eval/evaluation.json" "$S/W2repeat/run/inputs.csv" \
  --part "$S/W3plain/eval/evaluation.json" "$S/W3plain/run/inputs.csv" --train-parts 4 --start-from "$S/series/model.yaml" \
  --out "$S/series-grown" | sed 's/^/   /'
loop_rounds "$S/series-grown"
echo "   (the thesis's tables are reproduced by evaluate/stepped_separation_test; docs/stepped-workpiece.md)"

echo
echo "Outputs: $OUT/plan (G-code, manifest), $OUT/run (controller log, points.csv, inputs.csv, truth.json),"
echo "         $OUT/eval (errors.csv, evaluation.json, report.md, report.html, campaign.gltf), $OUT/machining (cuts.json, cmm_export.csv),"
echo "         $OUT/campaign (72 h: report.html, model.yaml, diagnosis-*.html, fit-*.html with the plots),"
echo "         $OUT/ttp (thermal test piece: plan/ (with cmm_plan.qif, .dmi), run/ (cmm_results.qif, .dmo), cmm/ (results.qif) and om/ evaluations, report.html, cmm/test_piece.gltf, r-test/, fit.html),"
echo "         $OUT/stepped (stepped workpiece W8: plan/ with the roughing, finishing, probing programs; run/ with cmm_export.csv, sw_probe.log; eval/ with compensation.json;
         plan-compensated/, run-compensated/, eval-compensated/ with before/after; report.html;
         W6/, W1/, W7/ the thermal stages, W2/, W5/ the control parts, separation/ the campaign (control.csv), W3/plan the program predicted from it,
         W3plain/, series/ the model loop's inputs.csv, errors.csv, model.yaml and each round's diagnosis,
         W2repeat/, series-grown/ the control round)"
