"""What the corpus scripts share (make_corpus_structured.py, make_corpus_n5.py): crops
of the real MR head and fuzz_zarr.c's container of a store's files. numpy alone."""
import os

import numpy as np

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MR = os.path.join(ROOT, "..", "shared", "data", "volumes", "HeadMRVolume.raw")


def head_crop(z=4, y=5, x=6):
    """A crop of the real MR head (z, y, x), or a ramp without the data."""
    if os.path.exists(MR):
        v = np.fromfile(MR, dtype=np.uint8).reshape(42, 62, 48)
        return v[20:20 + z, 30:30 + y, 20:20 + x].copy()
    g = np.mgrid[0:z, 0:y, 0:x]
    return ((g[2] + 3 * g[1] + 7 * g[0]) % 256).astype(np.uint8)


def pack_store(root, prelude="# zarr-python store\n"):
    """The store's files as fuzz_zarr.c's container."""
    names = []
    for d, _, files in os.walk(root):
        for f in files:
            names.append(os.path.relpath(os.path.join(d, f), root))
    names.sort(key=lambda n: (not n.startswith(".z"), n.count("/"), n))
    out = prelude.encode()
    for i, n in enumerate(names):
        with open(os.path.join(root, n), "rb") as f:
            body = f.read()
        out += f"--FILE {n}--\n".encode() + body + (b"\n" if i + 1 < len(names) else b"")
    return out
