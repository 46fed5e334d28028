#!/bin/sh
# README / docs/cyclostationary.md pictures for cyclostationary noise (S4): a synthetic near-regular exemplar
# (skewed bricks with per-brick random colour, mortar, a smooth pattern inside each brick and grain; periods
# t0 = (41.3, 6.2), t1 = (-9.4, 29.7) pixels, generated here: no third-party data), its stationary spot noise
# (ADSN of a texton model, `stex render --mode adsn`) and its cyclostationary spot noise (`--method cs-spot`,
# periods estimated) and its cyclostationary tiling and blending (`--method cs-tb`), side by side as
# docs/cs/spot.png.
# Usage: scripts/cs_figures.sh [path/to/stex]   (default build/cli/stex)
set -eu
STEX=${1:-build/cli/stex}
OUT=${OUT:-out/cs}
mkdir -p "$OUT" docs/cs
python3 - "$OUT/bricks.ppm" <<'PY'
import math, random, sys
w, h = 256, 256
t0, t1 = (41.3, 6.2), (-9.4, 29.7)
det = t0[0] * t1[1] - t0[1] * t1[0]
l0, l1 = math.hypot(*t0), math.hypot(*t1)
rnd = random.Random(7)
cells = {}
def cell(k, l):
    if (k, l) not in cells:
        g = rnd.gauss(0, 1)
        cells[(k, l)] = (0.62 + 0.10 * g + 0.04 * rnd.gauss(0, 1), 0.36 + 0.07 * g + 0.03 * rnd.gauss(0, 1),
                         0.25 + 0.05 * g + 0.03 * rnd.gauss(0, 1))
    return cells[(k, l)]
out = bytearray()
for j in range(h):
    for i in range(w):
        x, y = i + 0.5, j + 0.5
        a = (x * t1[1] - y * t1[0]) / det
        b = (t0[0] * y - t0[1] * x) / det
        k, l = math.floor(a), math.floor(b)
        fu, fv = a - k, b - l
        du = min(fu, 1 - fu) * det / l1
        dv = min(fv, 1 - fv) * det / l0
        m = math.exp(-(min(du, dv) / 1.6) ** 2)
        c = cell(k, l)
        pat = 0.05 * math.sin(2 * math.pi * fu) * math.cos(2 * math.pi * fv)
        px = []
        for ch in range(3):
            v = (1 - m) * (c[ch] + pat) + m * 0.78 + rnd.gauss(0, 0.035)
            px.append(max(0, min(255, int(round(v * 255)))))
        out += bytes(px)
with open(sys.argv[1], "wb") as f:
    f.write(b"P6\n%d %d\n255\n" % (w, h))
    f.write(out)
PY
"$STEX" --quiet analyze "$OUT/bricks.ppm" -o "$OUT/bricks_texton.stex" --support 64
"$STEX" render "$OUT/bricks_texton.stex" -o "$OUT/adsn.png" --size 256x256 --mode adsn --seed 1 > /dev/null
"$STEX" analyze "$OUT/bricks.ppm" -o "$OUT/bricks_cs.stex" --method cs-spot --estimate-periods --json > "$OUT/cs.json"
"$STEX" render "$OUT/bricks_cs.stex" -o "$OUT/cs_spot.png" --size 256x256 --origin 5000,-3000 --seed 1 > /dev/null
"$STEX" --quiet analyze "$OUT/bricks.ppm" -o "$OUT/bricks_cstb.stex" --method cs-tb --estimate-periods
"$STEX" render "$OUT/bricks_cstb.stex" -o "$OUT/cs_tb.png" --size 256x256 --origin 5000,-3000 --seed 1 > /dev/null
oiiotool "$OUT/bricks.ppm" "$OUT/adsn.png" "$OUT/cs_spot.png" "$OUT/cs_tb.png" --mosaic:pad=8 4x1 -o docs/cs/spot.png
cat "$OUT/cs.json"
