"""The consumer test's Python check: the INSTALLED module `stex` (found through PYTHONPATH=<prefix>/<platlib>,
its libstex.so through its RPATH) imports from the prefix, analyses, renders and answers point queries.
Usage: check_module.py PREFIX EXEMPLAR"""
import os
import sys

import numpy as np

import stex

prefix, exemplar = sys.argv[1], sys.argv[2]
assert stex.__file__.startswith(prefix), stex.__file__
if os.path.exists("/proc/self/maps"):  # the libstex.so loaded is the installed one (RPATH), not the build's
    with open("/proc/self/maps") as maps:
        libs = {line.split()[-1] for line in maps if "libstex.so" in line}
    assert libs and all(lib.startswith(prefix) for lib in libs), libs
model = stex.analyse(exemplar, support=8, iterations=2)
ctx = stex.Context()
img = ctx.render(model, 10, 20, 16, 12, seed=2)
assert img.shape == (12, 16, 1) and img.dtype == np.float32, (img.shape, img.dtype)
ys, xs = np.mgrid[0:12, 0:16]
vals = ctx.eval_points(model, np.stack([10 + xs + 0.5, 20 + ys + 0.5], axis=-1), seed=2)
assert np.array_equal(vals.view(np.uint32), img.view(np.uint32))
print("check_module: stex", stex.__version__, "from", stex.__file__, "mean", float(img.mean()))
