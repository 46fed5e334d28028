#!/usr/bin/env python3
"""Tile latency through stex.imageio.so against `stex render` of the same tile (docs/oiio-plugin.md, Latency).

For each model: a 256 x 256 tile at (512, 0),
  cold: a fresh process reading the tile, `oiiotool 'M?RES=256x256&ORIGIN=512,0' -o t.exr` vs
        `stex render M -o t.exr --size 256x256 --origin 512,0`, median
        wall time of --runs runs each, alternating (both start OpenCL, read PoCL's kernel cache and the self-test
        cache, render, write an EXR);
  warm: in this process, ImageInput.read_tile of --tiles distinct tiles after the open (the device, kernels and
        model kept by the plugin), median ms per tile; beside it the device time `stex render` reports for the
        tile (the floor of any warm path).
Usage: /usr/bin/python3 scripts/oiio_latency.py --stex build/cli/stex --plugin-dir build/imageio M.stex [M2.stex ...]
"""
import argparse
import os
import re
import statistics
import subprocess
import tempfile
import time

import OpenImageIO as oiio


def wall(cmd, env):
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return (time.perf_counter() - t0) * 1e3


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--stex", required=True)
    ap.add_argument("--plugin-dir", required=True)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--tiles", type=int, default=20)
    ap.add_argument("models", nargs="+")
    a = ap.parse_args()
    env = dict(os.environ, OIIO_LIBRARY_PATH=a.plugin_dir)
    oiio.attribute("plugin_searchpath", a.plugin_dir)
    tmp = tempfile.mkdtemp()
    out = os.path.join(tmp, "t.exr")
    print("| model | cold: oiiotool (ms) | cold: stex render (ms) | ratio | warm tile via plugin (ms) | "
          "stex render device time (ms) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for m in a.models:
        name = f"{m}?RES=256x256&ORIGIN=512,0&TILE=256&SEED=1"
        plug, cli = [], []
        for _ in range(a.runs):
            plug.append(wall(["oiiotool", name, "-o", out], env))
            cli.append(wall([a.stex, "-q", "render", m, "-o", out, "--size", "256x256", "--origin", "512,0",
                             "--seed", "1"], env))
        r = subprocess.run([a.stex, "render", m, "-o", out, "--size", "256x256", "--origin", "512,0", "--seed", "1"],
                           env=env, capture_output=True, text=True, check=True)
        dev = float(re.search(r"device ([0-9.]+) ms", r.stdout + r.stderr).group(1))
        inp = oiio.ImageInput.open(f"{m}?RES={256 * (a.tiles + 1)}x256&TILE=256&SEED=1")
        times = []
        for i in range(1, a.tiles + 1):
            t0 = time.perf_counter()
            inp.read_tile(256 * i, 0, 0, oiio.FLOAT)
            times.append((time.perf_counter() - t0) * 1e3)
        inp.close()
        pc, cc = statistics.median(plug), statistics.median(cli)
        print(f"| {os.path.basename(m)} | {pc:.0f} | {cc:.0f} | {pc / cc:.2f} | {statistics.median(times):.1f} | "
              f"{dev:.1f} |")


if __name__ == "__main__":
    main()
