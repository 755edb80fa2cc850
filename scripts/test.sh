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
(cd build && ctest --output-on-failure -j"$(nproc)")
phase "release tests"
echo "== again under ASan + UBSan =="
scripts/build.sh build-asan -DPROBELOOP_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug
phase "sanitizer build"
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j"$(nproc)")
phase "sanitizer tests"
