#!/usr/bin/env bash
# Configures and builds into $1 (default build/) with extra CMake arguments after it; with
# TARGET set (e.g. TARGET=probeloop), only that target and what it needs.
# A new build folder uses Ninja when it is installed (scripts/setup.sh installs it): it keeps
# both cores compiling across library boundaries, where make waits for each library to be
# archived (docs/performance.md#build-time). A folder configured earlier keeps its generator.
# ccache, when installed, caches the compiler's work across build folders and clean clones.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build}; shift || true
generator=()
if [ ! -f "$dir/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
launcher=()
if command -v ccache >/dev/null 2>&1; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B "$dir" "${generator[@]}" "${launcher[@]}" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$dir" -j"$(nproc)" ${TARGET:+--target "$TARGET"}
