#!/usr/bin/env bash
# Coverage-guided fuzzing of every reader (fuzz/README.md, docs/reliability.md):
#   scripts/fuzz.sh [SECONDS_PER_HARNESS] [HARNESS...]     default: 60 s, every harness
# Installs clang and the build dependencies when missing (apt-get, as scripts/setup.sh does), builds build-fuzz/ with clang,
# libFuzzer, ASan and UBSan (-DPROBELOOP_FUZZ=ON), then runs the harnesses one after another,
# each on a scratch copy of its corpus (fuzz/corpus/ is never written), with its dictionary,
# -max_len, -timeout and -rss_limit_mb. Crash, leak, timeout and OOM inputs land in
# out/fuzz/<harness>/; a summary line per harness at the end. Exit status 1 when any harness
# found something. FUZZ_JOBS (default: nproc) sets the build's parallelism; FUZZ_NICE (default
# 0) runs everything under nice; FUZZ_SKIP_BUILD=1 runs the harnesses already built.
set -euo pipefail
cd "$(dirname "$0")/.."

secs=${1:-60}
shift || true
case "$secs" in ''|*[!0-9]*) echo "fuzz.sh: SECONDS_PER_HARNESS must be a whole number, got '$secs'" >&2; exit 2;; esac

all=$(cd fuzz && ls ./*_fuzz.cpp | sed 's|^\./||; s|_fuzz\.cpp$||')
harnesses=("$@")
[ ${#harnesses[@]} -eq 0 ] && mapfile -t harnesses <<<"$all"
for h in "${harnesses[@]}"; do
  grep -qx "$h" <<<"$all" || { echo "fuzz.sh: no harness '$h' (there are: $(echo $all))" >&2; exit 2; }
done

nice_cmd=(nice -n "${FUZZ_NICE:-0}")
if [ -z "${FUZZ_SKIP_BUILD:-}" ]; then
  # What the libraries build with (scripts/setup.sh's list without the test-only tools) and
  # clang with its sanitizer and libFuzzer runtimes.
  missing=()
  for p in cmake make clang libclang-rt-14-dev libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev \
           libtinygltf-dev libgtest-dev libcgal-dev libgmp-dev libmpfr-dev libceres-dev libboost-dev libxml2-dev; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    echo "fuzz: installing ${missing[*]}"
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi

  CXX=clang++ "${nice_cmd[@]}" cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Release -DPROBELOOP_FUZZ=ON >/dev/null
  "${nice_cmd[@]}" cmake --build build-fuzz -j"${FUZZ_JOBS:-$(nproc)}" --target "${harnesses[@]/%/_fuzz}"
fi

# The dictionary of each harness's format.
dict_of() {
  case "$1" in
    ply) echo ply;;
    xyz|nist_ds) echo points;;
    fit_csv|points_csv|inputs_errors_csv|ttp_cmm_csv|feature_actuals) echo csv;;
    probe_log|ttp_on_machine) echo probe_log;;
    verify_linuxcnc) echo gcode_linuxcnc;;
    *_yaml) echo yaml;;
    *_json) echo json;;
    *) echo "$1";;  # gum_expression, gcode_linuxcnc, gcode_fanuc, qif, dmis
  esac
}

summary=()
status=0
for h in "${harnesses[@]}"; do
  scratch=$(mktemp -d "${TMPDIR:-/tmp}/probeloop-fuzz-$h.XXXXXX")
  cp -r "fuzz/corpus/$h/." "$scratch/"
  art="out/fuzz/$h"
  mkdir -p "$art"
  log="$art/fuzz.log"
  stamp="$art/.started"
  touch "$stamp"
  echo "== $h: $secs s (corpus $(ls "$scratch" | wc -l) inputs, dict fuzz/dict/$(dict_of "$h").dict)"
  # -rss_limit_mb: a reader that needs more than 2 GB for a 64 KiB input is a bug (OOM);
  # -timeout: 10 s for one input is a hang. -max_len matches the harnesses' 64 KiB cap.
  # -max_total_time is wall time: the CPU time the harness got (user + sys, bash's `time`) is
  # reported beside it, since a loaded machine gives a run fewer executions.
  set +e
  TIMEFORMAT='%U %S'
  { time ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    "${nice_cmd[@]}" "build-fuzz/fuzz/${h}_fuzz" "$scratch" -dict="fuzz/dict/$(dict_of "$h").dict" \
    -max_len=65536 -timeout=10 -rss_limit_mb=2048 -max_total_time="$secs" -print_final_stats=1 \
    -artifact_prefix="$art/" >"$log" 2>&1 ; } 2>"$art/cpu_seconds"
  rc=$?
  set -e
  # The last line: a harness killed by a signal puts bash's notice before it.
  cpu=$(awk 'END {printf "%.0f", $1 + $2}' "$art/cpu_seconds" 2>/dev/null || echo "?")
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1 || true)
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1 || true)
  found=$(find "$art" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \) -newer "$stamp" | wc -l)
  [ "$rc" -ne 0 ] && status=1
  line=$(printf '%-18s %4ss (cpu %4ss)  execs %-9s %-22s corpus %5s  findings %s%s' "$h" "$secs" "$cpu" "${execs:-?}" "${cov:-cov: ? ft: ?}" \
         "$(ls "$scratch" | wc -l)" "$found" "$([ "$rc" -ne 0 ] && echo "  (exit $rc: see $log)")")
  echo "$line"
  summary+=("$line")
  rm -rf "$scratch"
done
echo
echo "== summary (seconds per harness (wall, and the CPU time it got), executions, coverage, corpus after the run, findings in out/fuzz/<harness>/)"
printf '%s\n' "${summary[@]}"
exit $status
