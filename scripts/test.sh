#!/usr/bin/env bash
# The whole test suite: unit and integration tests (real CLI, LinuxCNC's rs274, the Khronos
# glTF validator), then once more under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh build
(cd build && ctest --output-on-failure -j"$(nproc)")
echo "== again under ASan + UBSan =="
scripts/build.sh build-asan -DPROBELOOP_SANITIZE=ON -DCMAKE_BUILD_TYPE=Debug
(cd build-asan && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 ctest --output-on-failure -j"$(nproc)")
