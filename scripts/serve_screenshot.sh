#!/usr/bin/env bash
# Makes docs/serve.png (README, docs/serve.md): a texton model of data/gravel.png served by `stex serve` on a
# free loopback port, its viewer screenshotted by headless Chromium. Usage: scripts/serve_screenshot.sh [BUILD]
set -euo pipefail
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
STEX="$ROOT/$BUILD/cli/stex"
WORK=$(mktemp -d)
trap 'kill "$PID" 2>/dev/null || true; wait "$PID" 2>/dev/null || true; rm -rf "$WORK"' EXIT
mkdir -p "$WORK/models"
"$STEX" -q analyze "$ROOT/data/gravel.png" -o "$WORK/models/gravel.stex" --method texton
"$STEX" serve --models "$WORK/models" --port 0 --port-file "$WORK/port" > "$WORK/serve.log" 2>&1 &
PID=$!
for _ in $(seq 300); do [ -s "$WORK/port" ] && break; sleep 0.1; done
PORT=$(cat "$WORK/port")
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
  --disable-component-update --disable-sync --disable-extensions --hide-scrollbars --force-device-scale-factor=1 \
  --force-color-profile=srgb --user-data-dir="$WORK/profile" --window-size=1024,600 --virtual-time-budget=60000 \
  --screenshot="$ROOT/docs/serve.png" "http://127.0.0.1:$PORT/?model=gravel&seed=1&mni=30&z=1&x=1000000&y=-2000&w=1024&h=560" \
  > "$WORK/chromium.log" 2>&1
echo "wrote docs/serve.png"
