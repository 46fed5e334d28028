"""embed_render.py: the smallest Python program that embeds stex (docs/embedding.md). Analyses an exemplar
image (or loads a model file), renders a 256 x 256 region into a NumPy array and prints the mean per channel;
then evaluates point queries at pixel centres, which equal the rendered pixels exactly.

    python3 embed_render.py data/gravel.png [DEVICE]   (PYTHONPATH must reach the installed/built module;
                                                        DEVICE as --device, default: the default device)
"""
import sys

import numpy as np

import stex


def main(path, device=""):
    model = stex.load(path) if path.endswith(".stex") else stex.analyse(path)
    ctx = stex.Context(device)  # "": the default OpenCL device
    img = ctx.render(model, -128, -128, 256, 256, seed=1)  # float32, shape (256, 256, channels)
    print(f"embed_render.py: stex {stex.__version__} on '{ctx.device_name}', {img.shape}, support {model.support}")
    for c, (m, r) in enumerate(zip(model.info["mean"], img.mean(axis=(0, 1)))):
        print(f"  channel {c}: model mean {m:.4f}, render mean {r:.4f}")
    # The centre of image pixel (row 20, column 10) is output position (-128 + 10.5, -128 + 20.5).
    values = ctx.eval_points(model, [[-117.5, -107.5]], seed=1)
    same = np.array_equal(values[0].view(np.uint32), img[20, 10].view(np.uint32))
    print(f"  point query at (-117.5, -107.5) {'equals' if same else 'DIFFERS FROM'} the rendered pixel")
    return 0 if same else 1


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit("usage: embed_render.py EXEMPLAR_IMAGE|MODEL.stex [DEVICE]")
    sys.exit(main(*sys.argv[1:]))
