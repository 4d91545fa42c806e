#!/usr/bin/env python3
"""Seeds of fuzz_n5 (tests/fuzz/corpus/n5/): N5 stores tensorstore writes, packed.

  .venv/bin/python tests/fuzz/make_corpus_n5.py      (from the repository root)

Each seed is an N5 store in fuzz_zarr.c's container ("--FILE <name>--" sections,
attributes.json first): datasets tensorstore's n5 driver writes (every compression:
raw, gzip, gzip with useZlib, bzip2, xz, blosc, zstd; every data type; blocks that do
not divide the dimensions; a 4-D dataset with named axes and resolution), multiscale
groups of datasets s0 .. s2 (the group's scales, resolution, units and axes, or
pixelResolution and each level's downsamplingFactors, or COSEM multiscales), and
hostile stores made from them (a block cut short, a varlength block, object mode, a
block of other dimensions or larger than blockSize, absurd sizes, a missing level).
The voxels are crops of the real MR head (../shared/data/volumes/HeadMRVolume.raw,
48 x 62 x 42 u8), so every seed is a few KB. Writes only tests/fuzz/corpus/n5/ts-*.
"""
import json
import os
import shutil
import sys
import tempfile

import numpy as np
import tensorstore as ts

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corpus_common import head_crop, pack_store  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
OUT = os.path.join(ROOT, "tests", "fuzz", "corpus", "n5")


def write(path, arr, block, comp=None, extra=None):
    meta = {"dimensions": list(arr.shape), "blockSize": list(block),
            "dataType": str(arr.dtype), "compression": comp or {"type": "gzip"}}
    t = ts.open({"driver": "n5", "kvstore": {"driver": "file", "path": path},
                 "metadata": meta, "create": True, "delete_existing": True}).result()
    t.write(arr).result()
    if extra:
        f = os.path.join(path, "attributes.json")
        with open(f) as fh:
            at = json.load(fh)
        at.update(extra)
        with open(f, "w") as fh:
            json.dump(at, fh)
    return path


def seed(name, root, prelude="# tensorstore n5\n"):
    """The store at ROOT packed (attributes.json first) as corpus/n5/ts-NAME."""
    with open(os.path.join(OUT, "ts-" + name), "wb") as f:
        f.write(pack_store(root, prelude))


def spoil_block(root, key, fn):
    p = os.path.join(root, key)
    with open(p, "rb") as f:
        b = bytearray(f.read())
    with open(p, "wb") as f:
        f.write(fn(b))


def main():
    os.makedirs(OUT, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="n5seeds")
    try:
        xyz = np.ascontiguousarray(head_crop(4, 5, 6).transpose(2, 1, 0))  # x, y, z
        comps = {"raw": {"type": "raw"}, "gzip": {"type": "gzip"},
                 "zlib": {"type": "gzip", "useZlib": True}, "bzip2": {"type": "bzip2"},
                 "xz": {"type": "xz"}, "blosc": {"type": "blosc", "cname": "lz4",
                                                 "clevel": 5, "shuffle": 1},
                 "zstd": {"type": "zstd"}}
        for n, c in comps.items():
            d = write(os.path.join(tmp, n), xyz.astype(np.uint16) * 97, (4, 3, 3), c)
            seed(f"comp-{n}", d)
        for dt in ("uint8", "int8", "int16", "uint32", "int32", "float32", "float64", "int64",
                   "uint64"):
            d = write(os.path.join(tmp, dt), xyz.astype(dt), (6, 5, 2), {"type": "raw"})
            seed(f"type-{dt}", d)
        a4 = np.stack([xyz, 255 - xyz], axis=-1)
        d = write(os.path.join(tmp, "xyzc"), a4, (4, 4, 4, 1), {"type": "raw"},
                  {"axes": ["x", "y", "z", "c"], "resolution": [0.5, 0.5, 2.0, 1.0],
                   "units": ["um", "um", "um", ""]})
        seed("xyzc", d, "# tensorstore n5\n0 1 -1\n")
        # multiscale groups
        big = np.ascontiguousarray(head_crop(8, 10, 12).transpose(2, 1, 0))
        lv = [big, big[::2, ::2, ::2].copy(), big[::4, ::4, ::4].copy()]

        def group(name, gattrs, lattrs):
            g = os.path.join(tmp, name)
            for i, a in enumerate(lv):
                write(os.path.join(g, f"s{i}"), a, (8, 8, 8), {"type": "raw"}, lattrs(i))
            with open(os.path.join(g, "attributes.json"), "w") as f:
                json.dump(gattrs, f)
            return g

        g = group("viewer", {"n5": "4.0.0", "scales": [[1, 1, 1], [2, 2, 2], [4, 4, 4]],
                             "resolution": [0.96, 0.96, 1.5], "units": ["mm"] * 3,
                             "axes": ["x", "y", "z"]},
                  lambda i: {"downsamplingFactors": [2 ** i] * 3})
        seed("group-viewer", g)
        seed("group-viewer-level2", g, "# tensorstore n5\n2\n")
        g = group("pixelres", {"n5": "4.0.0",
                               "pixelResolution": {"dimensions": [1, 1, 2], "unit": "um"}},
                  lambda i: {"downsamplingFactors": [2 ** i] * 3})
        seed("group-pixelres", g)
        g = group("ratio", {"n5": "4.0.0"}, lambda i: {})
        seed("group-ratio", g)
        cosem = {"multiscales": [{"datasets": [
            {"path": f"s{i}", "transform": {"axes": ["z", "y", "x"], "units": ["nm"] * 3,
                                            "scale": [4.0 * 2 ** i] * 3,
                                            "translate": [2.0 * (2 ** i - 1)] * 3}}
            for i in range(3)]}]}
        g = group("cosem", cosem, lambda i: {})
        seed("group-cosem", g)
        # hostile: made from the gzip dataset and the viewer group
        base = os.path.join(tmp, "gzip")
        bad = {
            "short-block": ("0/0/0", lambda b: b[:9]),
            "varlength": ("0/0/0", lambda b: b"\x00\x01" + b[2:16] + b"\x00\x00\x00\x24" +
                          b[16:]),
            "object-mode": ("0/0/0", lambda b: b"\x00\x02" + b[2:]),
            "ndim": ("0/0/0", lambda b: b[:2] + b"\x00\x05" + b[4:]),
            "big-block": ("0/0/0", lambda b: b[:4] + b"\x7f\xff\xff\xff" + b[8:]),
            "zero-block": ("0/0/0", lambda b: b[:8] + b"\x00\x00\x00\x00" + b[12:]),
        }
        for n, (key, fn) in bad.items():
            d = os.path.join(tmp, "bad-" + n)
            shutil.copytree(base, d)
            spoil_block(d, key, fn)
            seed("bad-" + n, d)
        for n, change in {"dims-negative": {"dimensions": [-6, 5, 4]},
                          "dims-huge": {"dimensions": [2 ** 45, 2 ** 45, 2 ** 45]},
                          "block-zero": {"blockSize": [0, 3, 3]},
                          "compression-lz4": {"compression": {"type": "lz4"}},
                          "type-string": {"dataType": "string"},
                          "compression-old": {"compression": None, "compressionType": "gzip"}
                          }.items():
            d = os.path.join(tmp, "bad-" + n)
            shutil.copytree(base, d)
            f = os.path.join(d, "attributes.json")
            with open(f) as fh:
                at = json.load(fh)
            for k, v in change.items():
                if v is None:
                    at.pop(k, None)
                else:
                    at[k] = v
            with open(f, "w") as fh:
                json.dump(at, fh)
            seed("bad-" + n, d)
        d = os.path.join(tmp, "bad-missing-level")
        shutil.copytree(os.path.join(tmp, "viewer"), d)
        shutil.rmtree(os.path.join(d, "s1"))
        seed("bad-missing-level", d)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
