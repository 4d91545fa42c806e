#!/usr/bin/python3
"""Write the 512^3 uint16 benchmark phantom as a raw NRRD file.

usage: bench/phantom512.py OUT.nrrd [--size N] [--sigma S]

The volume the render-speed benchmarks call "the 512^3 volume"
(docs/rendering.md, "Speed against the peers"): on the grid x, y, z in
[-1, 1] (N points each, spacing 1), a Gaussian blob of standard deviation
S (default 0.6, so that it fills most of the box) times a texture
0.6 + 0.4 sin(18x) sin(18y) sin(18z), scaled to 0 .. 30000. Render it
with the transfer-function ramp 8000 .. 28000 (bench/pairs_vtk.py
--tf-lo 8000 --tf-hi 28000). It is 256 MiB at N = 512: write it to a
temporary folder, not into the repository. Needs numpy (Debian's
/usr/bin/python3 has it).
"""
import argparse
import os

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--sigma", type=float, default=0.6)
    a = ap.parse_args()
    n = a.size
    ax = np.linspace(-1, 1, n, dtype=np.float32)
    y, x = ax[:, None], ax[None, :]
    if n < 2 or not a.sigma > 0:
        ap.error("--size must be at least 2 and --sigma above 0")
    tmp = a.out + ".part"
    try:
        with open(tmp, "wb") as f:
            f.write(("NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\n"
                     "spacings: 1 1 1\nendian: little\nencoding: raw\n\n" % (n, n, n)).encode())
            for z in ax:  # one slice at a time: bounded memory
                blob = np.exp(-(x * x + y * y + z * z) / (2 * a.sigma ** 2))
                tex = 0.6 + 0.4 * np.sin(18 * x) * np.sin(18 * y) * np.sin(18 * z)
                f.write((blob * tex * 30000).astype("<u2").tobytes())
        os.replace(tmp, a.out)  # never a partial OUT
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    print(a.out)


if __name__ == "__main__":
    main()
