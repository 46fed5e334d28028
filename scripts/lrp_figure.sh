#!/bin/sh
# Regenerates docs/lrp.png (README, docs/lrp.md), three 256^2 panels: the gravel exemplar (its top-left
# 256^2), LRP noise (the default analysis: J = 50, L = 8, fitted amplitudes, r = 0) and LRP texture by example
# (J = 50, r = 0.2, random placement),
# both rendered with seed 7.
# Usage: scripts/lrp_figure.sh [path/to/stex]   (default build/cli/stex; needs oiiotool)
set -eu
STEX=${1:-build/cli/stex}
OUT=docs/lrp.png
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$STEX" -q analyze data/gravel.png --method lrp -o "$TMP/noise.stex"
"$STEX" -q analyze data/gravel.png --method lrp --structure 0.2 --placement -o "$TMP/texture.stex"
"$STEX" -q render "$TMP/noise.stex" -o "$TMP/noise.png" --size 256x256 --seed 7
"$STEX" -q render "$TMP/texture.stex" -o "$TMP/texture.png" --size 256x256 --seed 7
oiiotool data/gravel.png --cut 256x256+0+0 -o "$TMP/exemplar.png"
oiiotool "$TMP/exemplar.png" "$TMP/noise.png" "$TMP/texture.png" --mosaic:pad=4 3x1 -d uint8 -o "$OUT"
ls -l "$OUT"
