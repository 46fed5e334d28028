#!/bin/sh
# docs/cyclostationary.md pictures for cyclostationary random-phase noise from user spectra (S4 §4.2, kind
# cs-rpn, `stex cs-rpn`):
#  - docs/cs/rpn.png (S4 Fig. 1 left): a bi-lobe whose orientation turns along t0 = (128, 0) (4 spectra at
#    0, 45, 90, 135 degrees, interpolated bilinearly, periodic), rendered as local random-phase, Gabor and
#    phasor noise (top to bottom);
#  - docs/cs/rpn_grid.png (S4 Fig. 4): 3 x 3 spectra (bi-lobes, rings, Gaussian lobes) over a skewed
#    parallelogram t0 = (96, 20), t1 = (-24, 88), random-phase, Gabor and the Fourier series (T = 64:
#    it repeats every 64 px) side by side.
# Usage: scripts/cs_rpn_figures.sh [path/to/stex]   (default build/cli/stex)
set -eu
STEX=${1:-build/cli/stex}
OUT=${OUT:-out/cs_rpn}
mkdir -p "$OUT" docs/cs
cat > "$OUT/rotating.json" <<'J'
{"grid": [4, 1], "size": 64,
 "spectra": ["bilobe:0.09,0,0.008", "bilobe:0.09,45,0.008", "bilobe:0.09,90,0.008", "bilobe:0.09,135,0.008"]}
J
for v in random-phase gabor phasor; do
  # each variant's own options (stex cs-rpn refuses the others')
  if [ "$v" = random-phase ]; then opts="--spacing 14 --cosines 16"; else opts="--bandwidth 0.04"; fi
  "$STEX" --quiet cs-rpn -o "$OUT/rot_$v.stex" --periods 128,0,0,128 --spectra "$OUT/rotating.json" --variant $v $opts
  mni=""; [ "$v" = random-phase ] || mni="--mni 16"  # random-phase reads no MNI (stex render refuses it)
  "$STEX" render "$OUT/rot_$v.stex" -o "$OUT/rot_$v.png" --size 512x160 --seed 3 $mni > /dev/null
done
oiiotool "$OUT/rot_random-phase.png" "$OUT/rot_gabor.png" "$OUT/rot_phasor.png" --mosaic:pad=6 1x3 -o docs/cs/rpn.png
cat > "$OUT/grid.json" <<'J'
{"grid": [3, 3], "size": 64,
 "spectra": ["bilobe:0.1,0,0.008", "bilobe:0.1,60,0.008", "bilobe:0.1,120,0.008",
             "ring:0.07,0.008", "ring:0.12,0.008", {"psd": "gauss:0.05,0.05,0.01", "variance": 0.01},
             "bilobe:0.16,90,0.01", {"psd": "ring:0.1,0.02", "variance": 0.005}, "gauss:0.08,0,0.01;0,0.08,0.01"]}
J
for v in random-phase gabor fourier; do
  case $v in random-phase) opts="--spacing 12 --cosines 24" ;; gabor) opts="--bandwidth 0.05" ;; *) opts="" ;; esac
  "$STEX" --quiet cs-rpn -o "$OUT/grid_$v.stex" --periods 96,20,-24,88 --spectra "$OUT/grid.json" --variant $v $opts
  mni=""; [ "$v" = gabor ] && mni="--mni 16"  # random-phase and fourier read no MNI
  "$STEX" render "$OUT/grid_$v.stex" -o "$OUT/grid_$v.png" --size 288x288 --seed 5 $mni > /dev/null
done
oiiotool "$OUT/grid_random-phase.png" "$OUT/grid_gabor.png" "$OUT/grid_fourier.png" --mosaic:pad=6 3x1 -o docs/cs/rpn_grid.png
