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

# Histogram transfer (S4 §5.3), docs/cs/hist.png: an exemplar whose polyphase components are binary (each
# cell's disc is orange or teal at random, on beige with dark mortar; periods (24.5, 0), (3.2, 20.3), given),
# flat colours, no noise: 8-bit ties), then cs-tb with the stationary transfer (blends of the two disc colours and the background: false colours),
# cs-tb with the cyclostationary transfer (--delta 1), cs-spot without a transfer (Gaussian) and with it.
python3 - "$OUT/discs.ppm" <<'PY'
import math, random, sys
w, h = 192, 192
t0, t1 = (24.5, 0.0), (3.2, 20.3)
det = t0[0] * t1[1] - t0[1] * t1[0]
rnd = random.Random(11)
cells = {}
out = bytearray()
for j in range(h):
    for i in range(w):
        x, y = i + 0.5, j + 0.5
        a = (x * t1[1] - y * t1[0]) / det
        b = (t0[0] * y - t0[1] * x) / det
        k, l = math.floor(a), math.floor(b)
        if (k, l) not in cells:
            cells[(k, l)] = rnd.random() < 0.5
        fu, fv = a - k - 0.5, b - l - 0.5
        dx, dy = fu * t0[0] + fv * t1[0], fu * t0[1] + fv * t1[1]
        r = math.hypot(dx, dy)
        edge = min(abs(a - k - round(a - k)) * det / math.hypot(*t1), abs(b - l - round(b - l)) * det / math.hypot(*t0))
        if edge < 1.2:
            c = (0.25, 0.22, 0.2)
        elif r < 6.5:
            c = (0.92, 0.55, 0.12) if cells[(k, l)] else (0.1, 0.6, 0.62)
        else:
            c = (0.86, 0.8, 0.66)
        out += bytes(max(0, min(255, int(round(v * 255)))) for v in c)
with open(sys.argv[1], "wb") as f:
    f.write(b"P6\n%d %d\n255\n" % (w, h))
    f.write(out)
PY
P=24.5,0,3.2,20.3
"$STEX" --quiet analyze "$OUT/discs.ppm" -o "$OUT/discs_tb_st.stex" --method cs-tb --periods $P --tile 24
"$STEX" --quiet analyze "$OUT/discs.ppm" -o "$OUT/discs_tb_cs.stex" --method cs-tb --periods $P --tile 24 --delta 1
"$STEX" --quiet analyze "$OUT/discs.ppm" -o "$OUT/discs_spot.stex" --method cs-spot --periods $P
"$STEX" --quiet analyze "$OUT/discs.ppm" -o "$OUT/discs_spot_cs.stex" --method cs-spot --periods $P --delta 1
for m in discs_tb_st discs_tb_cs discs_spot discs_spot_cs; do
  "$STEX" render "$OUT/$m.stex" -o "$OUT/$m.png" --size 192x192 --origin 3000,-2000 --seed 2 > /dev/null
done
oiiotool "$OUT/discs.ppm" "$OUT/discs_tb_st.png" "$OUT/discs_tb_cs.png" "$OUT/discs_spot.png" "$OUT/discs_spot_cs.png" \
  --mosaic:pad=8 5x1 -o docs/cs/hist.png
