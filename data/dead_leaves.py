#!/usr/bin/env python3
"""Writes data/leaves.png: a synthetic stochastic exemplar, the dead-leaves model (Matheron; Lee, Mumford and
Huang 2001), 512 x 512, 8-bit grey, reproducible bit for bit (its own integer RNG, the standard library only).

Leaves are ellipses falling on the plane; each pixel shows the first leaf that covers it (drawn front to back:
a pixel keeps the first value it gets). Radii follow p(r) ~ r^-3 on [2, 64] pixels (the scale-invariant
choice: a power spectrum close to 1/f^3, steep like a photograph's), aspect ratio 2.5, orientations
30 +- 20 degrees (an anisotropic spectrum, for the polar sectors), grey levels uniform in [40, 215]. Leaves
centred up to 64 pixels outside the frame also fall, so the border is like the inside.

Unlike gravel and grass it is not a photograph: its value is what a photograph cannot give, a texture that is
stochastic, non-Gaussian (flat patches, sharp edges) and whose making is known exactly.

  python3 data/dead_leaves.py [OUTPUT]      (default: leaves.png beside this script)
"""
import math
import os
import struct
import sys
import zlib

SIZE = 512
SEED = 20261206


class Rng:
    """xorshift64*: integers, so every Python gives the same image."""

    def __init__(self, seed):
        self.s = (seed * 0x9E3779B97F4A7C15 + 1) & 0xFFFFFFFFFFFFFFFF

    def u32(self):
        x = self.s
        x ^= (x >> 12)
        x ^= (x << 25) & 0xFFFFFFFFFFFFFFFF
        x ^= (x >> 27)
        self.s = x
        return ((x * 0x2545F4914F6CDD1D) & 0xFFFFFFFFFFFFFFFF) >> 32

    def uniform(self):
        return self.u32() / 4294967296.0


def leaves():
    rng = Rng(SEED)
    img = bytearray(SIZE * SIZE)
    filled = bytearray(SIZE * SIZE)
    left = SIZE * SIZE
    rmin, rmax, aspect, margin = 2.0, 64.0, 2.5, 64
    while left > 0:
        # inverse CDF of p(r) ~ r^-3 on [rmin, rmax]
        u = rng.uniform()
        r = 1.0 / math.sqrt(1.0 / rmin ** 2 - u * (1.0 / rmin ** 2 - 1.0 / rmax ** 2))
        a, b = r * math.sqrt(aspect), r / math.sqrt(aspect)  # semi-axes, area pi r^2
        th = math.radians(30.0 + 40.0 * (rng.uniform() - 0.5))
        cx = -margin + rng.uniform() * (SIZE + 2 * margin)
        cy = -margin + rng.uniform() * (SIZE + 2 * margin)
        grey = 40 + (rng.u32() % 176)
        c, s = math.cos(th), math.sin(th)
        x0, x1 = max(0, int(cx - a) - 1), min(SIZE - 1, int(cx + a) + 1)
        y0, y1 = max(0, int(cy - a) - 1), min(SIZE - 1, int(cy + a) + 1)
        for y in range(y0, y1 + 1):
            dy = y + 0.5 - cy
            row = y * SIZE
            for x in range(x0, x1 + 1):
                if filled[row + x]:
                    continue
                dx = x + 0.5 - cx
                u1 = (dx * c + dy * s) / a
                v1 = (-dx * s + dy * c) / b
                if u1 * u1 + v1 * v1 <= 1.0:
                    img[row + x] = grey
                    filled[row + x] = 1
                    left -= 1
    return img


def write_png(path, img):
    raw = b"".join(b"\x00" + bytes(img[y * SIZE:(y + 1) * SIZE]) for y in range(SIZE))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", SIZE, SIZE, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "leaves.png")
    write_png(out, leaves())
