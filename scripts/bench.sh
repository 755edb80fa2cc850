#!/usr/bin/env bash
# Fitting benchmarks in one run on the same data: probeloop (Google Benchmark), PCL and SciPy.
#   1. installs what it needs, idempotently (Debian packages only when one is missing)
#   2. builds build-bench/ in Release with -DPROBELOOP_BENCH=ON (bench targets only)
#   3. writes the deterministic point files into build-bench/bench-data/ (kept when present)
#   4. times probeloop's LS plane/sphere/cylinder (1e3..1e7 points), MZ roundness/flatness
#      (1e2..1e5) and one plain read pass; then the sphere and cylinder files through PCL
#      and SciPy from the same start
#   5. writes bench/results/latest.md (tables, ratios, agreement, targets), summary.json and
#      the raw JSON (ours.json, ours_fits.json, pcl.jsonl, scipy.jsonl)
# Environment: PCL_MAX / SCIPY_MAX (largest n given to the peers, default 1e7), LS_MAX
# (default 1e7), MZ_MAX (default 1e5), REPS (Google Benchmark repetitions, default 3).
set -euo pipefail
cd "$(dirname "$0")/.."
started=$(date -u +"%Y-%m-%d %H:%M UTC")
SECONDS=0

PCL_MAX=${PCL_MAX:-10000000}
SCIPY_MAX=${SCIPY_MAX:-10000000}
LS_MAX=${LS_MAX:-10000000}
MZ_MAX=${MZ_MAX:-100000}
REPS=${REPS:-3}
BUILD=build-bench
DATA=$BUILD/bench-data
OUT=bench/results

packages=(cmake g++ make python3 libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
          libtinygltf-dev libgtest-dev libcgal-dev libgmp-dev libmpfr-dev
          libbenchmark-dev libpcl-dev python3-numpy python3-scipy)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "bench: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# The Debian interpreter carries python3-scipy; a python3 earlier on PATH may not.
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
"$PY" -c "import scipy, numpy" || { echo "bench: $PY cannot import scipy/numpy" >&2; exit 1; }

echo "== build ($BUILD, Release, PROBELOOP_BENCH=ON)"
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DPROBELOOP_BENCH=ON >/dev/null
targets=(probeloop_bench_data probeloop_bench_fit)
have_pcl=0
if cmake --build "$BUILD" --target help | grep probeloop_bench_pcl >/dev/null; then
  targets+=(probeloop_bench_pcl); have_pcl=1
else
  echo "bench: PCL not found, the PCL columns stay empty"
fi
cmake --build "$BUILD" -j"$(nproc)" --target "${targets[@]}" >/dev/null

echo "== data ($DATA)"
"$BUILD/bench/probeloop_bench_data" "$DATA" --max-ls "$LS_MAX" --max-mz "$MZ_MAX"

mkdir -p "$OUT"
rm -f "$OUT"/ours.json "$OUT"/ours_fits.json "$OUT"/pcl.jsonl "$OUT"/scipy.jsonl

echo "== probeloop (Google Benchmark, $REPS repetitions, medians)"
"$BUILD/bench/probeloop_bench_fit" --data_dir="$DATA" --max_ls="$LS_MAX" --max_mz="$MZ_MAX" \
  --fits_out="$OUT/ours_fits.json" \
  --benchmark_repetitions="$REPS" --benchmark_report_aggregates_only=true \
  --benchmark_min_time=0.2 \
  --benchmark_out="$OUT/ours.json" --benchmark_out_format=json

echo "== PCL (up to n = $PCL_MAX) and SciPy (up to n = $SCIPY_MAX), same files, same start"
for kind in sphere cylinder; do
  for ((n = 1000; n <= LS_MAX; n *= 10)); do
    file="$DATA/${kind}_${n}.bin"
    if [ "$have_pcl" = 1 ] && [ "$n" -le "$PCL_MAX" ]; then
      "$BUILD/bench/probeloop_bench_pcl" "$file" >> "$OUT/pcl.jsonl"
      echo "   pcl   $kind $n: $(tail -n1 "$OUT/pcl.jsonl" | "$PY" -c 'import json,sys; r = json.load(sys.stdin); print("%.4g s CPU, %.4g s wall" % (r["median_cpu_s"], r["median_s"]))')"
    fi
    if [ "$n" -le "$SCIPY_MAX" ]; then
      OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
        "$PY" bench/scipy_fit.py "$file" >> "$OUT/scipy.jsonl"
      echo "   scipy $kind $n: $(tail -n1 "$OUT/scipy.jsonl" | "$PY" -c 'import json,sys; r = json.load(sys.stdin); print("%.4g s CPU, %.4g s wall" % (r["median_cpu_s"], r["median_s"]))')"
    fi
  done
done

echo "== report ($OUT/latest.md)"
cmd="scripts/bench.sh"
[ "$PCL_MAX:$SCIPY_MAX:$LS_MAX:$MZ_MAX:$REPS" != "10000000:10000000:10000000:100000:3" ] &&
  cmd="PCL_MAX=$PCL_MAX SCIPY_MAX=$SCIPY_MAX LS_MAX=$LS_MAX MZ_MAX=$MZ_MAX REPS=$REPS scripts/bench.sh"
"$PY" bench/report.py "$OUT" "$DATA" --command "$cmd" --pcl-max "$PCL_MAX" \
  --scipy-max "$SCIPY_MAX" --date "$started" --seconds-so-far "$SECONDS" > /dev/null
cat "$OUT/latest.md"
echo
echo "bench: done in ${SECONDS} s; results in $OUT/"
