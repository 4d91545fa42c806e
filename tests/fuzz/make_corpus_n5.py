#!/usr/bin/env python3
"""Seeds of fuzz_n5 and fuzz_precomputed: N5 stores and precomputed volumes tensorstore writes.

  .venv/bin/python tests/fuzz/make_corpus_n5.py [precomputed]   (from the repository root;
  precomputed: its seeds alone)

Each seed is an N5 store in fuzz_zarr.c's container ("--FILE <name>--" sections,
attributes.json first): datasets tensorstore's n5 driver writes (every compression:
raw, gzip, gzip with useZlib, bzip2, xz, blosc, zstd; every data type; blocks that do
not divide the dimensions; a 4-D dataset with named axes and resolution), multiscale
groups of datasets s0 .. s2 (the group's scales, resolution, units and axes, or
pixelResolution and each level's downsamplingFactors, or COSEM multiscales), and
hostile stores made from them (a block cut short, a varlength block, object mode, a
block of other dimensions or larger than blockSize, absurd sizes, a missing level).
The voxels are crops of the real MR head (../shared/data/volumes/HeadMRVolume.raw,
48 x 62 x 42 u8), so every seed is a few KB.

tests/fuzz/corpus/precomputed/: Neuroglancer precomputed volumes tensorstore's
neuroglancer_precomputed driver writes (raw in two scales with a voxel_offset, chunks
cut at the end; three channels; jpeg; a segmentation; raw chunks as gzip streams; a
sharded and a compressed_segmentation scale, which the reader refuses), and hostile
infos and chunks made from them. Writes only the ts-* seeds of those two folders.
"""
import gzip
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
PC_OUT = os.path.join(ROOT, "tests", "fuzz", "corpus", "precomputed")


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


def seed(name, root, prelude="# tensorstore n5\n", out=OUT):
    """The store at ROOT packed (attributes.json or info first) as OUT/ts-NAME."""
    with open(os.path.join(out, "ts-" + name), "wb") as f:
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


def pc_write(path, arr, res, chunk, offset=(0, 0, 0), encoding="raw", mtype="image",
             create=True, **scale):
    spec = {"driver": "neuroglancer_precomputed", "kvstore": {"driver": "file", "path": path},
            "scale_metadata": {"size": list(arr.shape[:3]), "resolution": list(res),
                               "encoding": encoding, "chunk_size": list(chunk),
                               "voxel_offset": list(offset), **scale},
            "create": True, "open": not create}
    if create:
        spec["multiscale_metadata"] = {"type": mtype, "data_type": str(arr.dtype),
                                       "num_channels": int(arr.shape[3])}
    t = ts.open(spec).result()
    t[...] = arr
    return path


def pc_seed(name, root):
    seed(name, root, "# tensorstore precomputed\n", PC_OUT)


def precomputed():
    os.makedirs(PC_OUT, exist_ok=True)
    tmp = tempfile.mkdtemp(prefix="pcseeds")
    try:
        big = np.ascontiguousarray(head_crop(8, 10, 12).transpose(2, 1, 0))[..., None]
        d = pc_write(os.path.join(tmp, "raw"), big.astype(np.uint16) * 50, (8, 8, 20), (8, 8, 4),
                     (3, 5, 1))
        pc_write(d, big[::2, ::2, ::2].astype(np.uint16) * 50, (16, 16, 40), (8, 8, 4),
                 (1, 2, 0), create=False)
        pc_seed("raw-two-scales", d)
        seed("raw-two-scales-level1", d, "# tensorstore precomputed\n1\n", PC_OUT)
        c3 = np.concatenate([big, 255 - big, big // 2], axis=3)
        pc_seed("channels3", pc_write(os.path.join(tmp, "c3"), c3, (4, 4, 4), (8, 8, 8)))
        seed("channels3-c2", os.path.join(tmp, "c3"), "# tensorstore precomputed\n0 2\n",
             PC_OUT)
        pc_seed("jpeg", pc_write(os.path.join(tmp, "jpeg"), big, (4, 4, 4), (8, 8, 4),
                                 encoding="jpeg"))
        pc_seed("jpeg-rgb", pc_write(os.path.join(tmp, "jpegrgb"), c3, (4, 4, 4), (8, 8, 4),
                                     encoding="jpeg"))
        seg = (big.astype(np.uint32) // 40)
        pc_seed("segmentation", pc_write(os.path.join(tmp, "seg"), seg, (4, 4, 4), (8, 8, 8),
                                         mtype="segmentation"))
        pc_seed("segmentation-u64", pc_write(os.path.join(tmp, "seg64"), seg.astype(np.uint64),
                                             (4, 4, 4), (8, 8, 8), mtype="segmentation"))
        pc_seed("cseg", pc_write(os.path.join(tmp, "cseg"), seg, (4, 4, 4), (8, 8, 8),
                                 encoding="compressed_segmentation", mtype="segmentation",
                                 compressed_segmentation_block_size=[4, 4, 4]))
        pc_seed("sharded", pc_write(os.path.join(tmp, "shard"), big, (4, 4, 4), (8, 8, 8),
                                    sharding={"@type": "neuroglancer_uint64_sharded_v1",
                                              "preshift_bits": 0, "hash": "identity",
                                              "minishard_bits": 0, "shard_bits": 0,
                                              "minishard_index_encoding": "gzip",
                                              "data_encoding": "gzip"}))
        for n, h, enc, pre, mini, sh in (("sharded-murmur-gzip", "murmurhash3_x86_128", "gzip",
                                          1, 1, 1),
                                         ("sharded-identity-raw", "identity", "raw", 0, 2, 0)):
            pc_seed(n, pc_write(os.path.join(tmp, n), big, (4, 4, 4), (4, 4, 4),
                                sharding={"@type": "neuroglancer_uint64_sharded_v1",
                                          "preshift_bits": pre, "hash": h,
                                          "minishard_bits": mini, "shard_bits": sh,
                                          "minishard_index_encoding": enc,
                                          "data_encoding": enc}))
        # raw chunks as gzip streams
        g = os.path.join(tmp, "gz")
        shutil.copytree(os.path.join(tmp, "c3"), g)
        sd = os.path.join(g, "4_4_4")
        for f in os.listdir(sd):
            with open(os.path.join(sd, f), "rb") as fh:
                b = fh.read()
            with open(os.path.join(sd, f), "wb") as fh:
                fh.write(gzip.compress(b))
        pc_seed("raw-gzip", g)
        # hostile
        for n, fn in {"size-negative": lambda i: i["scales"][0].update(size=[-1, 5, 5]),
                      "size-huge": lambda i: i["scales"][0].update(size=[2 ** 45] * 3),
                      "chunk-zero": lambda i: i["scales"][0].update(chunk_sizes=[[0, 8, 8]]),
                      "no-scales": lambda i: i.update(scales=[]),
                      "key-dotdot": lambda i: i["scales"][0].update(key="../x"),
                      "channels-huge": lambda i: i.update(num_channels=1 << 30),
                      "type-float16": lambda i: i.update(data_type="float16"),
                      "offset-huge": lambda i: i["scales"][0].update(
                          voxel_offset=[2 ** 62, 0, 0])}.items():
            d = os.path.join(tmp, "bad-" + n)
            shutil.copytree(os.path.join(tmp, "c3"), d)
            f = os.path.join(d, "info")
            with open(f) as fh:
                info = json.load(fh)
            fn(info)
            with open(f, "w") as fh:
                json.dump(info, fh)
            pc_seed("bad-" + n, d)
        d = os.path.join(tmp, "bad-short-chunk")
        shutil.copytree(os.path.join(tmp, "c3"), d)
        sd = os.path.join(d, "4_4_4")
        f = os.path.join(sd, sorted(os.listdir(sd))[0])
        with open(f, "rb") as fh:
            b = fh.read()
        with open(f, "wb") as fh:
            fh.write(b[:77])
        pc_seed("bad-short-chunk", d)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    if sys.argv[1:] != ["precomputed"]:
        main()
    precomputed()
