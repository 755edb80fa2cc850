#!/usr/bin/env bash
# Regenerates the report screenshots in docs/img/ from the demo's outputs (issue 32): every
# HTML page probeloop writes, as headless Chromium draws it at 1280 px wide.
# Usage: scripts/screenshots.sh [DEMO_OUT]   (default out/demo; run scripts/demo.sh first)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/demo}
chromium=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}
[ -n "$chromium" ] || { echo "screenshots: chromium not found (scripts/setup.sh installs it)" >&2; exit 1; }
mkdir -p docs/img
shot() {  # PAGE PNG HEIGHT
  [ -f "$1" ] || { echo "screenshots: $1 missing (run scripts/demo.sh)" >&2; exit 1; }
  local tmp
  tmp=$(mktemp -d)
  # --virtual-time-budget lets Vega finish drawing before the capture.
  "$chromium" --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir="$tmp" \
    --window-size=1280,"$3" --virtual-time-budget=10000 --screenshot="$PWD/$2" "file://$(realpath "$1")" >/dev/null 2>&1
  rm -rf "$tmp"
  echo "  $2 <- $1"
}
shot "$out/eval/report.html" docs/img/report-sphere.png 2400
shot "$out/ttp/report.html" docs/img/report-thermal-test-piece.png 3000
shot "$out/stepped/report.html" docs/img/report-stepped-workpiece.png 3000
shot "$out/campaign/fit-2.html" docs/img/report-model-fit.png 2400
shot "$out/campaign/diagnosis-1.html" docs/img/report-model-diagnosis.png 2400
shot "$out/campaign/live/live/dashboard.html" docs/img/report-live-dashboard.png 2000
