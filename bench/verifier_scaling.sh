#!/usr/bin/env bash
# The safety verifier's cost against the number of probe lines (issue 29 item 4): `plan` runs
# the verifier on everything it writes, and each probe line's inverted outcome used to re-run
# the program from its start (probe lines x program length). Times `plan` (median of 3, wall)
# for the thermal test piece (its 364-point inspection, 717 G31 lines, plus the pre-machining
# and the 8 h test) and for sphere artifacts of 1 000 and 5 000 points (one cycle: 5 positions
# x 200 / 1 000 points, two G38 moves a point); then checks that the outputs are
# byte-identical to another build's (BEFORE=path/to/probeloop, optional), whose times are
# listed beside. Writes bench/results/verifier.md.
set -euo pipefail
cd "$(dirname "$0")/.."
PL=${PL:-build/cli/probeloop}
[ -x "$PL" ] || scripts/build.sh build >/dev/null
BEFORE=${BEFORE:-}
W=$(mktemp -d /tmp/probeloop-bench-verifier.XXXXXX)
trap 'rm -rf "$W"' EXIT
MILL=parts/machines/linuxcnc_rotary_mill.yaml
NMV=parts/machines/nmv5000.yaml

median() {  # median wall time of 3 runs of a command, s
  local times=() t0 t1
  for _ in 1 2 3; do
    t0=$(date +%s.%N); "$@" >/dev/null 2>&1; t1=$(date +%s.%N)
    times+=("$(python3 -c "print(f'{$t1 - $t0:.3f}')")")
  done
  printf '%s\n' "${times[@]}" | sort -g | sed -n 2p
}

for n in 199 999; do
  sed -e "s/  equator_points: 4 .*/  equator_points: $n/" -e 's/  count: 12/  count: 1/' \
      parts/sphere_artifact.yaml > "$W/sphere_$n.yaml"
done
rows=()
run_case() {  # name, points, piece, machine
  local name=$1 points=$2 piece=$3 machine=$4 now before="" probes same=""
  now=$(median "$PL" plan "$piece" --machine "$machine" --out "$W/now_$name")
  probes=$(cat "$W/now_$name"/*.n*c | grep -cE "G38\.[23]|G31" || true)
  if [ -n "$BEFORE" ]; then
    before=$(median "$BEFORE" plan "$piece" --machine "$machine" --out "$W/before_$name")
    if diff -r -q "$W/before_$name" "$W/now_$name" >/dev/null; then same="yes"; else same="NO"; fi
  fi
  rows+=("| $name | $points | $probes | ${before:-–} | $now | ${same:-–} |")
}
run_case "thermal test piece (NMV 5000, Fanuc)" 364 parts/thermal_test_piece.yaml $NMV
run_case "sphere artifact, 1 cycle (LinuxCNC mill)" 1000 "$W/sphere_199.yaml" $MILL
run_case "sphere artifact, 1 cycle (LinuxCNC mill)" 5000 "$W/sphere_999.yaml" $MILL

{
  echo "# The safety verifier against probe lines"
  echo
  echo "\`bench/verifier_scaling.sh\` ($(date -u +%Y-%m-%d), $(nproc) cores). \`plan\` wall time, median of 3;"
  echo "it includes planning and writing, the verifier being most of it before issue 29."
  echo
  echo "| plan | points | probe moves | before, s | now, s | outputs identical |"
  echo "|---|---:|---:|---:|---:|---|"
  printf '%s\n' "${rows[@]}"
} > bench/results/verifier.md
cat bench/results/verifier.md
