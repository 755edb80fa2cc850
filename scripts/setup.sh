#!/usr/bin/env bash
# Installs what probeloop needs on Debian (bookworm), idempotently: Debian packages via
# apt-get only when one is missing, the npm validator only when absent.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(cmake g++ make python3 libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
          libtinygltf-dev libgtest-dev libcgal-dev libgmp-dev libmpfr-dev libceres-dev libboost-dev linuxcnc-uspace
          libjs-vega libjs-three chromium libxml2-dev libxml2-utils libsqlite3-dev ninja-build python3-yaml ccache)
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -d tests/tools/node_modules/gltf-validator ]; then
  echo "setup: installing the Khronos glTF validator (npm, pinned in tests/tools/package-lock.json)"
  npm ci --prefix tests/tools --no-audit --no-fund >/dev/null
fi
