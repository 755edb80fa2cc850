#!/usr/bin/env bash
# The whole test suite: unit and integration tests (real CLI, LinuxCNC's rs274 and LinuxCNC in
# simulation, the Khronos glTF validator), then once more under AddressSanitizer +
# UndefinedBehaviorSanitizer. Each phase prints how long it took (docs/performance.md#build-time).
set -euo pipefail
cd "$(dirname "$0")/.."
phase() { echo "== $1: $((SECONDS - start)) s"; start=$SECONDS; }
start=$SECONDS
scripts/setup.sh
phase "setup"
scripts/build.sh build
phase "release build"
(cd build && ctest --output-on-failure -j"$(nproc)" -E '^linuxcnc_')
phase "release tests"
# The tests on LinuxCNC in simulation (about 12 min, one LinuxCNC at a time) mostly wait for the
# simulated machine's moves: they run beside the sanitizer build. Their contacts are decided in
# LinuxCNC's servo thread, so a loaded machine delays them but does not move them (docs/linuxcnc.md).
(cd build && { ctest --output-on-failure -R '^linuxcnc_' > linuxcnc_tests.log 2>&1 && rc=0 || rc=$?; echo "$rc" > linuxcnc_tests.rc; }) &
linuxcnc_tests=$!
trap 'wait' EXIT  # a failure below still lets LinuxCNC stop cleanly first
echo "== again under ASan + UBSan =="
scripts/build.sh build-asan -DPROBELOOP_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug
phase "sanitizer build"
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j"$(nproc)")
phase "sanitizer tests"
wait "$linuxcnc_tests" || true
echo "== the LinuxCNC tests (run beside the sanitizer build) =="
cat build/linuxcnc_tests.log
[ "$(cat build/linuxcnc_tests.rc 2>/dev/null)" = 0 ] || { echo "test.sh: the LinuxCNC tests failed" >&2; exit 1; }
phase "LinuxCNC tests, waited for"
