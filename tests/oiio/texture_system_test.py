#!/usr/bin/env python3
"""stex.imageio.so from Python's OpenImageIO (ctest oiio_texture_system; docs/oiio-plugin.md).

A texton model opened as a MIP-mapped texture (`MODEL?RES=..&MIP=1`):
  1. the texels of levels 0..3 (through an ImageCache) equal `stex render --scale 2^-k --filter` bit for bit;
  2. TextureSystem lookups at footprints of levels 0..3 equal the bilinear interpolation of those renders,
     within interpolation error: OIIO interpolates in float32 from weights it derives in float32, so the
     tolerance is a few float32 ulps of the texel values (1e-6 absolute, 8 ulps at 1, on values within
     [-1, 2]; measured worst 9e-8); an off-by-one texel or a wrong level misses by about the texture's
     standard deviation, 0.15 here;
  3. a damaged model gives an error from OIIO (no crash, no exception), naming the file.
Exit status 0 when every check passes.
"""
import argparse
import os
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio


def run(cmd, cwd):
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"FAIL: {' '.join(cmd)} exited {r.returncode}\n{r.stderr}")


def read_exr(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        sys.exit(f"FAIL: cannot open {path}: {oiio.geterror()}")
    px = inp.read_image(oiio.FLOAT)
    inp.close()
    return np.asarray(px, dtype=np.float32)  # (h, w, c)


def bilinear(img, x, y):
    """OIIO's bilinear lookup at pixel coordinates (x, y) (texel centres at i + 0.5), clamped at the edges."""
    h, w, _ = img.shape
    fx, fy = x - 0.5, y - 0.5
    x0, y0 = int(np.floor(fx)), int(np.floor(fy))
    ax, ay = fx - x0, fy - y0
    def at(i, j):
        return img[min(max(j, 0), h - 1), min(max(i, 0), w - 1)].astype(np.float64)
    return ((1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
            ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stex", required=True)
    ap.add_argument("--plugin-dir", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--exemplar", required=True)
    a = ap.parse_args()
    oiio.attribute("plugin_searchpath", a.plugin_dir)
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    run([a.stex, "-q", "analyze", a.exemplar, "-o", "m.stex", "--support", "12", "--iterations", "4"], a.work)
    model = os.path.join(a.work, "m.stex")
    side, origin, seed = 512, (2048, -1024), 3
    name = f"{model}?RES={side}x{side}&ORIGIN={origin[0]},{origin[1]}&SEED={seed}&TILE=64&MIP=1"

    refs = []
    for k in range(4):
        s = side >> k
        cmd = [a.stex, "-q", "render", "m.stex", "-o", f"l{k}.exr", "--size", f"{s}x{s}",
               "--origin", f"{origin[0] >> k},{origin[1] >> k}", "--seed", str(seed)]
        if k > 0:
            cmd += ["--filter", "--scale", repr(1.0 / (1 << k))]
        run(cmd, a.work)
        refs.append(read_exr(os.path.join(a.work, f"l{k}.exr")))
    sd = float(refs[0].std())

    failures = []
    # 1. Texels of every level, bit for bit.
    cache = oiio.ImageCache(False)
    for k, ref in enumerate(refs):
        s = side >> k
        got = cache.get_pixels(name, 0, k, 0, s, 0, s, 0, 1, oiio.FLOAT)
        if got is None:
            failures.append(f"level {k}: get_pixels failed: {cache.geterror()}")
            continue
        got = np.asarray(got, dtype=np.float32).reshape(ref.shape)
        if not np.array_equal(got.view(np.uint32), ref.view(np.uint32)):
            n = int(np.count_nonzero(got != ref))
            failures.append(f"level {k}: {n} texels differ from stex render --scale 2^-{k} --filter")
    oiio.ImageCache.destroy(cache)

    # 2. Lookups at each level's footprint (one level: the footprint's level exactly).
    ts = oiio.TextureSystem(False)
    opt = oiio.TextureOpt()
    opt.interpmode = oiio.InterpMode.Bilinear
    opt.mipmode = oiio.MipMode.OneLevel
    rng = np.random.default_rng(7)
    worst = 0.0
    for k, ref in enumerate(refs):
        s = side >> k
        d = (1 << k) / side  # a texel of level k in texture coordinates
        for _ in range(200):
            u, v = rng.uniform(0.05, 0.95, 2)
            got = np.array(ts.texture(name, opt, float(u), float(v), d, 0.0, 0.0, d, ref.shape[2]), dtype=np.float64)
            want = bilinear(ref, float(np.float32(u)) * s, float(np.float32(v)) * s)
            err = float(np.max(np.abs(got - want)))
            worst = max(worst, err)
            if err > 1e-6:
                failures.append(f"level {k}: lookup at ({u:.6f}, {v:.6f}) = {got} but bilinear of the render = {want}")
                break
    print(f"lookups: worst |texture - bilinear(render)| = {worst:.3g} (texture sd {sd:.3g})")

    # 3. A damaged model: an OIIO error naming it, for a TextureSystem lookup and for ImageInput.open.
    data = open(model, "rb").read()
    damaged = os.path.join(a.work, "damaged.stex")
    with open(damaged, "wb") as f:
        f.write(data[: len(data) // 2])
    ts.texture(damaged + "?RES=64x64", opt, 0.5, 0.5, 0.01, 0.0, 0.0, 0.01, 1)
    err = ts.geterror()
    if "damaged.stex" not in err:
        failures.append(f"damaged model: TextureSystem error does not name it: {err!r}")
    if oiio.ImageInput.open(damaged + "?RES=64x64") is not None:
        failures.append("damaged model: ImageInput.open succeeded")
    elif "stex: " not in oiio.geterror():
        failures.append("damaged model: ImageInput.open's error is not stex's")

    if failures:
        print("\n".join("FAIL: " + f for f in failures))
        return 1
    print("ok: levels 0-3 bit-identical to stex render, lookups within interpolation error, damaged model refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
