#!/bin/sh
# Regenerates the README picture of noise mixing (S1 §7) into docs/mixing/:
#   strip.png - exemplar A (data/gravel.png, left), the mixing strip A -> B (ramp map quantised to 21 levels, as
#               S1 Fig. 5), exemplar B (right): a procedural "wood grain" made by an existing stex mode
#               (anisotropic Gabor noise, `stex gabor` + `stex render`), so nothing outside the repo is needed
#   map.png   - the grey image map (made with oiiotool) and the same model driven by it: A outside, B in the
#               middle
# Usage: scripts/mix_figures.sh [path/to/stex]   (default build/cli/stex)
set -eu
STEX=${1:-build/cli/stex}
OUT=docs/mixing
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
# Exemplar B: streaks at 80 degrees, 0.05 cycles/pixel, with gravel's mean and a similar contrast.
"$STEX" -q gabor -o "$TMP/wood.stex" --frequency 0.05 --orientation 80 --lobes 2 --bandwidth 0.02 --mean 0.45 --std 0.13
"$STEX" -q render "$TMP/wood.stex" -o "$TMP/wood.png" --size 512x512 --seed 1
"$STEX" -q analyze-mix data/gravel.png "$TMP/wood.png" -o "$TMP/mix.stex" --levels 21 --support 48 --seed 0
"$STEX" -q render "$TMP/mix.stex" -o "$TMP/strip.png" --size 1024x192 --mix-map ramp:64:960 --seed 4
oiiotool data/gravel.png --cut 192x192+0+0 -o "$TMP/a.png"
oiiotool "$TMP/wood.png" --cut 192x192+0+0 -o "$TMP/b.png"
# A | strip | B on one canvas (oiiotool's --paste: the image below the top of the stack goes onto the top one).
oiiotool --create 1424x192 1 -o "$TMP/canvas.png"
oiiotool "$TMP/a.png" "$TMP/canvas.png" --paste +0+0 "$TMP/strip.png" --swap --paste +200+0 "$TMP/b.png" --swap \
  --paste +1232+0 -o "$OUT/strip.png"
# A grey map of 128x128 pixels: a blurred square, 1 in the middle and 0 outside, spread by --mix-scale 3 over the
# 384x384 render.
oiiotool --pattern constant:color=0 128x128 1 --box:color=1:fill=1 36,36,92,92 --blur 33x33 -o "$TMP/map.png"
"$STEX" -q render "$TMP/mix.stex" -o "$TMP/disc.png" --size 384x384 --mix-map "$TMP/map.png" --mix-scale 3 \
  --mix-wrap clamp --seed 4
oiiotool "$TMP/map.png" --resize 384x384 "$TMP/disc.png" --mosaic:pad=6 2x1 -o "$OUT/map.png"
ls -l "$OUT"
