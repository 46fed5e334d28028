#!/bin/sh
# Regenerates the README picture of surface noise (S1 §6) into docs/surface/:
#   torus.png - `stex surface --preview` of the gravel model on a procedural bumpy torus (two views side by
#               side): every pixel evaluates the noise at its surface point and normal, no UVs involved
# The mesh is made here (no third-party asset): a torus of radii 1 and 0.35 whose tube radius is modulated by
# 0.06 cos(5 phi + 3 theta), 192 x 64 vertices, written as OBJ (positions and triangles only; the loader
# generates smooth normals).
# Usage: scripts/surface_figures.sh [path/to/stex]   (default build/cli/stex)
set -eu
STEX=${1:-build/cli/stex}
OUT=docs/surface
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"
python3 - "$TMP/torus.obj" <<'PY'
import math, sys
nu, nv = 192, 64  # around the ring, around the tube
with open(sys.argv[1], "w") as f:
    f.write("# bumpy torus (scripts/surface_figures.sh)\n")
    for i in range(nu):
        phi = 2 * math.pi * i / nu
        for j in range(nv):
            theta = 2 * math.pi * j / nv
            r = 0.35 + 0.06 * math.cos(5 * phi + 3 * theta)
            x = (1 + r * math.cos(theta)) * math.cos(phi)
            y = (1 + r * math.cos(theta)) * math.sin(phi)
            z = r * math.sin(theta)
            f.write(f"v {x:.7f} {y:.7f} {z:.7f}\n")
    idx = lambda i, j: (i % nu) * nv + (j % nv) + 1
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            f.write(f"f {a} {b} {c}\nf {a} {c} {d}\n")
PY
"$STEX" -q analyze data/gravel.png -o "$TMP/gravel.stex" --support 32
"$STEX" -q surface "$TMP/gravel.stex" --mesh "$TMP/torus.obj" --preview "$TMP/a.png" --preview-size 420x420 \
  --texel 0.004 --seed 1 --view 1,0.8,1.6
"$STEX" -q surface "$TMP/gravel.stex" --mesh "$TMP/torus.obj" --preview "$TMP/b.png" --preview-size 420x420 \
  --texel 0.004 --seed 1 --view 0.2,-1,0.35
oiiotool "$TMP/a.png" "$TMP/b.png" --mosaic:pad=4 2x1 -o "$OUT/torus.png"
ls -l "$OUT"
