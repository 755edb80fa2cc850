#!/usr/bin/env bash
# Hidden-effect campaigns (issue 5): plan, simulate and evaluate one of the truths in
# tests/data/hidden/ with the real CLI: 48 h of sphere-artifact cycles (one per ~6.6 min)
# on the NMV 5000 (Fanuc), the artifact of parts/sphere_artifact.yaml. Each truth file says
# what is hidden, the starting model and the candidate a diagnosis should rank first.
#
# Usage: hidden_campaign.sh NAME OUTDIR [SEED]     (NAME = a file name in tests/data/hidden/
#        without .yaml; SEED default 1)
# Leaves OUTDIR/artifact.yaml, OUTDIR/plan/ (sphere_cycle.nc, plan.json), OUTDIR/run/
# (dprnt.txt, points.csv, inputs.csv, truth.json) and OUTDIR/eval/ (errors.csv, ...), the
# errors on the simulated machine's clock (see the evaluate step).
# Same NAME and SEED -> byte-identical files.
# Env: PROBELOOP (default $PROBELOOP_SOURCE_DIR/build/cli/probeloop), PROBELOOP_SOURCE_DIR
# (default: this repository), HIDDEN_DURATION (default "48 h").
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
SRC=${PROBELOOP_SOURCE_DIR:-$(cd "$here/../.." && pwd)}
PL=${PROBELOOP:-$SRC/build/cli/probeloop}
DURATION=${HIDDEN_DURATION:-48 h}
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
  echo "usage: $0 NAME OUTDIR [SEED]   (NAME: $(cd "$SRC/tests/data/hidden" && ls *.yaml | sed 's/\.yaml$//' | tr '\n' ' '))" >&2
  exit 2
fi
NAME=$1 OUT=$2 SEED=${3:-1}
TRUTH=$SRC/tests/data/hidden/$NAME.yaml
MACHINE=$SRC/parts/machines/nmv5000.yaml
[ -f "$TRUTH" ] || { echo "$0: no campaign '$NAME' ($TRUTH)" >&2; exit 2; }
[ -x "$PL" ] || { echo "$0: no probeloop binary at $PL (set PROBELOOP)" >&2; exit 2; }

# The tool-change campaign keeps the probe in the spindle (its own M6 once): the changes
# that matter are the production ones at random times, not one per cycle in step with the
# probing, which would look the same in every cycle.
each_cycle=true
[ "$NAME" = tool_change ] && each_cycle=false

mkdir -p "$OUT"
art=$OUT/artifact.yaml
sed -e "s/^  count: 12\$/  duration: $DURATION/" \
    -e "s/^  tool_change_each_cycle: true\$/  tool_change_each_cycle: $each_cycle/" \
    "$SRC/parts/sphere_artifact.yaml" > "$art"
# Fail loudly if parts/sphere_artifact.yaml no longer has the lines edited above.
grep -q "^  duration: $DURATION\$" "$art" && grep -q "^  tool_change_each_cycle: $each_cycle\$" "$art" ||
  { echo "$0: parts/sphere_artifact.yaml changed: cannot set cycles.duration / tool_change_each_cycle" >&2; exit 1; }

rm -rf "$OUT/plan" "$OUT/run" "$OUT/eval"
"$PL" plan "$art" --machine "$MACHINE" --out "$OUT/plan" > /dev/null
"$PL" simulate "$OUT/plan/sphere_cycle.nc" --machine "$MACHINE" --part "$art" --truth "$TRUTH" \
  --out "$OUT/run" --seed "$SEED" > /dev/null
# Evaluate the canonical points (the same reported coordinates as dprnt.txt, each trigger's time
# to the millisecond). The DPRNT log carries the controller's clock to the second; model_cli.py
# evaluates it too and checks that its stamps and the lag fitted from them agree with these.
"$PL" evaluate "$OUT/run/points.csv" --format csv --manifest "$OUT/plan/plan.json" --out "$OUT/eval" > /dev/null
echo "$NAME (seed $SEED): $OUT/run/inputs.csv, $OUT/eval/errors.csv, $OUT/run/truth.json"
