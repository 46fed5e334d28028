#!/usr/bin/env bash
# docs/kinds.png, the README's "which kind suits which texture" picture: three exemplars and what
# `stex analyze` (--method auto, the default) makes of them, rendered beside each (512x256, seed 1):
#   a micro-texture (texton noise of data/grass.png, 256x256: Gaussian by construction) -> texton
#   data/gravel.png (stones, no lattice)                                                  -> tb
#   data/tiles_stone.png (a mosaic of stone cubes on a lattice)                           -> cs-tb
# Usage: scripts/kinds_figure.sh [BUILD_DIR]   (from the repository root)
set -euo pipefail
BUILD=${1:-build}
STEX="$BUILD/cli/stex"
FONT=/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf  # fonts-dejavu-core (scripts/install-deps.sh)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$STEX" -q analyze data/grass.png -o "$TMP/grass.stex" --method texton
"$STEX" -q render "$TMP/grass.stex" -o "$TMP/micro.png" --size 256x256 --seed 5
# --ch arguments that make an image RGB (a grey image's one channel three times).
rgb() { if oiiotool --info "$1" | grep -q " 1 channel"; then echo "--ch 0,0,0"; else echo "--ch 0,1,2"; fi; }
args=()
y=0
for ex in "$TMP/micro.png" data/gravel.png data/tiles_stone.png; do
  name=$(basename "$ex" .png)
  "$STEX" analyze "$ex" -o "$TMP/$name.stex" 2> "$TMP/$name.txt"
  kind=$(sed -n 's/^stex: --method auto: \([a-z-]*\) .*/\1/p' "$TMP/$name.txt")
  "$STEX" -q render "$TMP/$name.stex" -o "$TMP/$name.render.png" --size 512x256 --seed 1
  oiiotool "$ex" --cut 256x256+0+0 -o "$TMP/$name.ex.png"
  label="$name -> $kind"
  [ "$name" = micro ] && label="a micro-texture -> $kind"
  args+=("$TMP/$name.ex.png" $(rgb "$TMP/$name.ex.png") --swap --paste +0+$y
         "$TMP/$name.render.png" $(rgb "$TMP/$name.render.png") --swap --paste +264+$y
         "--text:x=8:y=$((y + 278)):size=16:color=0,0,0:font=$FONT" "$label (exemplar, then its render)")
  y=$((y + 290))
done
oiiotool --create 776x$y 3 --fill:color=1,1,1 776x$y "${args[@]}" -d uint8 -o docs/kinds.png
echo "wrote docs/kinds.png"
