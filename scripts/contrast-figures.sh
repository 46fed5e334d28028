#!/bin/sh
# Regenerates the pictures of docs/contrast.md and the README's S5 section: a bi-lobe Gabor noise (S5 Fig. 9)
# raw / simple / quality renormalisation, each with and without a colour LUT (S5 Fig. 1, 12), and the contrast
# fields. Needs a built stex (STEX=build/cli/stex) and oiiotool (Debian openimageio-tools) for the mosaic.
# Usage: scripts/contrast-figures.sh [OUTDIR]   (default docs/contrast)
set -eu
STEX=${STEX:-build/cli/stex}
OUT=${1:-docs/contrast}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
# A sharp two-colour LUT (16 entries: 8 dark blue, 8 cream; the transition is 1/15 of the range wide).
{
  echo "P3 16 1 255"
  for i in 0 1 2 3 4 5 6 7; do echo "20 40 90"; done
  for i in 0 1 2 3 4 5 6 7; do echo "245 225 170"; done
} > "$TMP/lut.ppm"
"$STEX" -q gabor -o "$TMP/bilobe.stex" --frequency 0.08 --orientation 30 --bandwidth 0.03
"$STEX" -q render "$TMP/bilobe.stex" -o "$TMP/raw.exr" --size 256x256 --seed 1
"$STEX" -q renormalize "$TMP/raw.exr" -o "$TMP/simple.exr" --mode simple --L 16
"$STEX" -q renormalize "$TMP/raw.exr" -o "$TMP/quality.exr" --mode quality --L 16 --model "$TMP/bilobe.stex"
for m in raw simple quality; do
  "$STEX" -q renormalize "$TMP/$m.exr" -o "$TMP/${m}_lut.png" --mode none --lut "$TMP/lut.ppm"
  "$STEX" -q contrast "$TMP/$m.exr" --L 16 --field "$TMP/${m}_field.png"
  oiiotool "$TMP/$m.exr" --ch 0,0,0 -d uint8 -o "$TMP/${m}_grey.png"
done
oiiotool "$TMP/raw_grey.png" "$TMP/simple_grey.png" "$TMP/quality_grey.png" \
  "$TMP/raw_lut.png" "$TMP/simple_lut.png" "$TMP/quality_lut.png" \
  --mosaic:pad=4 3x2 -d uint8 -o "$OUT/renormalize.png"
oiiotool "$TMP/raw_field.png" "$TMP/simple_field.png" "$TMP/quality_field.png" --mosaic:pad=4 3x1 \
  -d uint8 -o "$OUT/contrast-fields.png"
echo "wrote $OUT/renormalize.png and $OUT/contrast-fields.png"
