#!/bin/sh
# Regenerates the README pictures of filtering (S1 §5) and higher-order textons (S1 §10) into docs/filter/:
#   plane.png  - a perspective view of the gravel plane, point-sampled (left) vs filtered (right)
#   orders.png - texton noise of orders 0, 1, 3, 5 at 8x magnification
# Usage: scripts/filter_figures.sh [path/to/stex]   (default build/cli/stex)
set -eu
STEX=${1:-build/cli/stex}
OUT=docs/filter
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
"$STEX" -q analyze data/gravel.png -o "$TMP/o1.stex" --support 64 --order 1
"$STEX" -q render "$TMP/o1.stex" -o "$TMP/plane_point.png" --size 400x240 --camera 40,78,70 --no-filter --seed 3
"$STEX" -q render "$TMP/o1.stex" -o "$TMP/plane_filtered.png" --size 400x240 --camera 40,78,70 --seed 3
oiiotool "$TMP/plane_point.png" "$TMP/plane_filtered.png" --mosaic:pad=4 2x1 -o "$OUT/plane.png"
for k in 0 1 3 5; do
  "$STEX" -q analyze data/gravel.png -o "$TMP/k$k.stex" --support 32 --order $k
  "$STEX" -q render "$TMP/k$k.stex" -o "$TMP/k$k.png" --size 192x192 --scale 8 --seed 5
done
oiiotool "$TMP/k0.png" "$TMP/k1.png" "$TMP/k3.png" "$TMP/k5.png" --mosaic:pad=4 4x1 -o "$OUT/orders.png"
ls -l "$OUT"
