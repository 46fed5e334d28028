#!/usr/bin/env bash
# The README demo (`make demo`): the main job on the bundled exemplar, on the default OpenCL device.
#   1. stex info                      which device runs it
#   2. stex analyze                   data/gravel.png -> out/gravel.stex (S1 Algorithm 1, texton 64x64)
#   3. stex render                    a 2048x2048 float EXR and a 1024x512 PNG of the unbounded noise
#   4. oiiotool                       exemplar and render side by side -> out/side_by_side.png
set -euo pipefail
BUILD=${1:-build}
STEX="$BUILD/cli/stex"
OUT=out
mkdir -p "$OUT"
"$STEX" info
echo
"$STEX" analyze data/gravel.png -o "$OUT/gravel.stex"
echo
"$STEX" render "$OUT/gravel.stex" -o "$OUT/gravel_2048.exr" --size 2048x2048 --seed 1
"$STEX" render "$OUT/gravel.stex" -o "$OUT/gravel_render.png" --size 1024x512 --seed 1
# Exemplar (512x512) | 8-pixel white gap | render (1024x512), at the same scale.
oiiotool data/gravel.png --create 1544x512 1 --fill:color=1 1544x512 --paste +0+0 \
  "$OUT/gravel_render.png" --swap --paste +520+0 -d uint8 -o "$OUT/side_by_side.png"
echo
echo "demo outputs in $OUT/: gravel.stex (model), gravel_2048.exr (float render), side_by_side.png"
