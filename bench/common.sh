# Sourced by the benchmark scripts: Debian packages installed only when missing, and the
# Release build of one bench target in build-bench/.
ensure_packages() {
  local missing=() p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -gt 0 ]; then
    local SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}
BUILD=build-bench
build_bench_target() {
  cmake -S . -B $BUILD -DCMAKE_BUILD_TYPE=Release -DPROBELOOP_BENCH=ON >/dev/null
  cmake --build $BUILD --target "$1" -j2 >/dev/null
}
