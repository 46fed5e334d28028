#!/usr/bin/env bash
# The README demo (`make demo`): the main job on the bundled exemplar, on the default OpenCL device.
#   1. stex info                      which device runs it
#   2. stex analyze --method texton   data/gravel.png -> out/gravel.stex (S1 Algorithm 1, texton 64x64)
#   3. stex analyze                   data/gravel.png -> out/gravel_auto.stex (--method auto, the default: it
#                                     prints the kind it picks and why; docs/auto.md)
#   4. stex render                    a 2048x2048 float EXR of the texton noise, and 512x512 PNGs of both models
#   5. oiiotool                       exemplar | texton noise | the auto pick, captioned -> out/side_by_side.png
set -euo pipefail
BUILD=${1:-build}
STEX="$BUILD/cli/stex"
OUT=out
FONT=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf  # fonts-dejavu-core (scripts/install-deps.sh)
mkdir -p "$OUT"
"$STEX" info
echo
"$STEX" analyze data/gravel.png -o "$OUT/gravel.stex" --method texton
echo
"$STEX" analyze data/gravel.png -o "$OUT/gravel_auto.stex" 2> "$OUT/auto.txt"
cat "$OUT/auto.txt" >&2
# "stex: --method auto: tb (gradient ratio ...": the kind it picked.
AUTO=$(sed -n 's/^stex: --method auto: \([a-z-]*\) .*/\1/p' "$OUT/auto.txt")
echo
"$STEX" render "$OUT/gravel.stex" -o "$OUT/gravel_2048.exr" --size 2048x2048 --seed 1
"$STEX" render "$OUT/gravel.stex" -o "$OUT/gravel_texton.png" --size 512x512 --seed 1
"$STEX" render "$OUT/gravel_auto.stex" -o "$OUT/gravel_auto.png" --size 512x512 --seed 1
# Exemplar | texton noise | the auto pick (512x512 each, 8-pixel white gaps), a caption line under each.
caption() { echo "--text:x=$1:y=536:size=18:color=0:font=$FONT"; }
oiiotool data/gravel.png --create 1552x548 1 --fill:color=1 1552x548 --paste +0+0 \
  "$OUT/gravel_texton.png" --ch 0 --swap --paste +520+0 \
  "$OUT/gravel_auto.png" --ch 0 --swap --paste +1040+0 \
  "$(caption 8)" "exemplar (data/gravel.png)" \
  "$(caption 528)" "texton noise (--method texton)" \
  "$(caption 1048)" "$AUTO (--method auto, the default)" \
  -d uint8 -o "$OUT/side_by_side.png"
echo
echo "--method auto picked $AUTO for data/gravel.png: texton noise keeps the exemplar's spectrum (a micro-texture's"
echo "whole look) but loses the stones' edges; $AUTO keeps them (docs/auto.md)."
echo "demo outputs in $OUT/: gravel.stex (texton model), gravel_auto.stex ($AUTO), gravel_2048.exr (float render),"
echo "side_by_side.png (exemplar | texton | $AUTO)"
