#!/usr/bin/env python3
"""Seeds of fuzz_zarr.c for Zarr v3 and OME-Zarr 0.5 (issue 78).

  .venv/bin/python tests/fuzz/make_corpus_zarr3.py [OUTDIR]

Writes small stores with zarr-python 3 (the .venv of scripts/install-deps.sh
test; Debian's python3-zarr writes v2 only, see make_corpus_structured.py):
every codec chain the reader takes (bytes either endian, transpose, gzip,
zstd, blosc, crc32c), sharded with the index at the end and at the start,
nested shards, empty inner chunks, both chunk key encodings, fill values,
dimension_names and an NGFF 0.5 group of two levels; each packed as
fuzz_zarr.c's container ("--FILE <name>--" sections) into OUTDIR
(default tests/fuzz/corpus/zarr) as v3-<name>.
"""
import os
import sys
import tempfile

import numpy as np
import zarr
from zarr.codecs import (BloscCodec, BytesCodec, Crc32cCodec, GzipCodec, ShardingCodec,
                         TransposeCodec, ZstdCodec)

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "corpus", "zarr")


def pack_store(root, prelude="# zarr-python 3 store\n"):
    """The store's files as fuzz_zarr.c's container (metadata first)."""
    names = []
    for d, _, files in os.walk(root):
        for f in files:
            names.append(os.path.relpath(os.path.join(d, f), root))
    names.sort(key=lambda n: (not n.endswith("zarr.json"), n.count("/"), n))
    out = prelude.encode()
    for i, n in enumerate(names):
        with open(os.path.join(root, n), "rb") as f:
            body = f.read()
        out += f"--FILE {n}--\n".encode() + body + (b"\n" if i + 1 < len(names) else b"")
    return out


rng = np.random.default_rng(78)
arr = (rng.integers(0, 200, size=(5, 6, 7))).astype(np.uint16)
CASES = {
    "zstd": dict(compressors=ZstdCodec(level=1)),
    "gzip-big": dict(serializer=BytesCodec(endian="big"), compressors=GzipCodec(level=1)),
    "blosc": dict(compressors=BloscCodec(cname="lz4", clevel=1, shuffle="shuffle", typesize=2)),
    "transpose-crc": dict(filters=[TransposeCodec(order=(2, 0, 1))],
                          compressors=[GzipCodec(level=1), Crc32cCodec()]),
    "key-v2": dict(chunk_key_encoding={"name": "v2", "separator": "."}, compressors=None),
    "key-dot": dict(chunk_key_encoding={"name": "default", "separator": "."}, compressors=None),
    "shard": dict(shards=(4, 6, 6), compressors=None),
    "shard-start": dict(chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
        chunk_shape=(2, 3, 3), codecs=[BytesCodec(), ZstdCodec(level=1)], index_location="start")),
    "shard-nested": dict(chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
        chunk_shape=(2, 6, 6), codecs=[ShardingCodec(chunk_shape=(2, 3, 3),
                                                     codecs=[BytesCodec()])])),
}
os.makedirs(OUT, exist_ok=True)
with tempfile.TemporaryDirectory() as tmp:
    for name, kw in CASES.items():
        root = os.path.join(tmp, name)
        kw.setdefault("chunks", (2, 3, 3))
        z = zarr.create_array(root, shape=arr.shape, dtype=arr.dtype, zarr_format=3,
                              dimension_names=["z", "y", "x"], **kw)
        z[:] = arr
        if name == "shard":
            z[0:2, 0:3, 0:3] = 0  # an empty inner chunk (the fill value)
        with open(os.path.join(OUT, f"v3-{name}"), "wb") as f:
            f.write(pack_store(root))
    # an NGFF 0.5 group: two levels, t and c axes, omero
    root = os.path.join(tmp, "ngff")
    g = zarr.open_group(root, mode="w")
    a5 = rng.integers(0, 200, size=(2, 2, 4, 6, 6)).astype(np.uint8)
    ds = []
    for k, a in enumerate([a5, a5[:, :, ::2, ::2, ::2]]):
        g.create_array(str(k), shape=a.shape, dtype=a.dtype, chunks=(1, 1, 2, 3, 3),
                       shards=(1, 2, 4, 6, 6), fill_value=0)[:] = a
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [1.0, 1.0] + [2.0 ** k] * 3}]})
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": "t", "type": "time", "unit": "second"}, {"name": "c", "type": "channel"}] + [
        {"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"], "datasets": ds}],
        "omero": {"channels": [{"label": "a", "color": "FF0000",
                                "window": {"min": 0, "max": 200, "start": 0, "end": 200}},
                               {"label": "b", "color": "00FF00",
                                "window": {"min": 0, "max": 200, "start": 0, "end": 200}}]}}
    with open(os.path.join(OUT, "v3-ngff05"), "wb") as f:
        f.write(pack_store(root, "0 1 1\n"))
print(f"wrote {len(CASES) + 1} seeds to {OUT}")
