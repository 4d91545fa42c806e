#!/usr/bin/env python3
"""Seeds of fuzz_zarr3.c (issue 78) from the stores zarr-python 3 and
tensorstore write.

  .venv/bin/python tests/fuzz/make_corpus_zarr3_struct.py [OUTDIR]

Each store (a plain array, or an OME-NGFF 0.5 group of one or two levels)
is written by the reference implementation, then described in
fuzz_zarr3.c's input structure: the 48-byte header says its shape, data
type, chunks, codec chains and shard layout; the tweaks carry each real
encoded inner chunk as "raw" bytes (13, u16 length, bytes), empty inner
chunks and absent chunk files as such (11), so the harness rebuilds the
shard indexes around the reference encoder's chunks. A second seed of each
store appends the real zarr.json after a line "--JSON--" (merged into the
generated one) and asks for vv_open whole too. The script checks that the header it wrote describes the
store (its mapping is the harness's parse_header, kept small enough that
the harness's caps change nothing). Written into OUTDIR (default
tests/fuzz/corpus/zarr3) as ref-<writer>-<name>[-json].
"""
import itertools
import json
import os
import struct
import sys
import tempfile

import numpy as np
import tensorstore as ts
import zarr
from zarr.codecs import (BloscCodec, BytesCodec, Crc32cCodec, GzipCodec, ShardingCodec,
                         TransposeCodec, ZstdCodec)

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "corpus", "zarr3")
DTYPES = ["bool", "uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64",
          "int64", "uint64", "float16"]
MAXSIDE = {2: 48, 3: 16, 4: 8, 5: 6}
CNAMES = ["lz4", "zstd", "blosclz", "zlib", "lz4hc"]
SHUFFLES = ["noshuffle", "shuffle", "bitshuffle"]
B2B = {"gzip": 0, "zstd": 1, "blosc": 2, "crc32c": 3}


def lehmer(order):
    left, sel, mul = list(range(len(order))), 0, 1
    for o in order:
        k = left.index(o)
        sel += k * mul
        mul *= len(left)
        left.remove(o)
    return sel


def describe(meta, ngff_levels=0):
    """The header of fuzz_zarr3.c for array metadata @meta (a dict)."""
    h = bytearray(48)
    shape = meta["shape"]
    nd = len(shape)
    assert 2 <= nd <= 5 and all(s <= MAXSIDE[nd] for s in shape), shape
    h[0] = nd - 2
    h[1] = DTYPES.index(meta["data_type"])
    for i, s in enumerate(shape):
        h[3 + i] = s - 1
    cs0 = meta["chunk_grid"]["configuration"]["chunk_shape"]
    for i, c in enumerate(cs0):
        assert c <= shape[i] + 1
        h[8 + i] = c - 1
    codecs, level, outer = meta["codecs"], 0, cs0
    while codecs[0]["name"] == "sharding_indexed":
        cfg = codecs[0]["configuration"]
        inner = cfg["chunk_shape"]
        for i in range(nd):
            divs = [d for d in range(1, outer[i] + 1) if outer[i] % d == 0]
            h[14 + 6 * level + i] = divs.index(inner[i])
        ic = cfg.get("index_codecs", [{"name": "bytes", "configuration": {"endian": "little"}}])
        endian = (ic[0].get("configuration") or {}).get("endian")
        h[14 + 6 * level + 5] = ((cfg.get("index_location", "end") == "start")
                                 | (any(c["name"] == "crc32c" for c in ic) << 1)
                                 | ((endian == "big") << 2) | ((endian is None) << 4))
        codecs, outer, level = cfg["codecs"], inner, level + 1
    h[13] = level
    b2b = []
    h[2] = 2
    for c in codecs:
        cfg = c.get("configuration") or {}
        if c["name"] == "transpose":
            h[32] = 1
            h[33] = lehmer(cfg["order"])
        elif c["name"] == "bytes":
            h[2] = {"little": 0, "big": 1, None: 2}[cfg.get("endian")]
        else:
            b2b.append(B2B[c["name"]])
            if c["name"] == "blosc":
                h[38] = CNAMES.index(cfg["cname"]) + 5 * SHUFFLES.index(cfg["shuffle"])
    assert len(b2b) <= 3
    h[34] = len(b2b)
    for i, k in enumerate(b2b):
        h[35 + i] = k
    ke = meta["chunk_key_encoding"]
    sep = ke.get("configuration", {}).get("separator", "/" if ke["name"] == "default" else ".")
    h[39] = {("default", "/"): 0, ("default", "."): 1, ("v2", "."): 2, ("v2", "/"): 3}[
        (ke["name"], sep)]
    fv = meta["fill_value"]
    if isinstance(fv, bool):
        h[40], h[41] = 5, int(fv)
    elif isinstance(fv, (int, float)) and float(fv).is_integer() and 0 <= fv < 256:
        h[40], h[41] = 0, int(fv)
    elif fv == "NaN":
        h[40] = 1
    else:
        h[40] = 6
    h[42] = (1 if meta.get("dimension_names") else 0) | (ngff_levels << 1)
    h[43] = 78
    return bytes(h), level


def chunk_key(meta, pos):
    ke = meta["chunk_key_encoding"]
    sep = ke.get("configuration", {}).get("separator", "/" if ke["name"] == "default" else ".")
    parts = [str(p) for p in pos]
    return sep.join((["c"] if ke["name"] == "default" else []) + parts)


def shard_tweaks(meta, blob, codecs, outer):
    """The tweaks of one shard (its bytes @blob) of codecs @codecs."""
    cfg = codecs[0]["configuration"]
    inner = cfg["chunk_shape"]
    per = [o // i for o, i in zip(outer, inner)]
    count = int(np.prod(per))
    ic = cfg.get("index_codecs", [])
    crc = any(c["name"] == "crc32c" for c in ic)
    endian = ">" if any((c.get("configuration") or {}).get("endian") == "big" for c in ic) else "<"
    ib = 16 * count + (4 if crc else 0)
    start = cfg.get("index_location", "end") == "start"
    raw = blob[:ib] if start else blob[len(blob) - ib:]
    ent = struct.unpack(f"{endian}{2 * count}Q", raw[:16 * count])
    out = bytearray([0])  # the shard as encoded
    for q in range(count):
        o, n = ent[2 * q], ent[2 * q + 1]
        if o == 2 ** 64 - 1:
            out += bytes([11])  # an empty inner chunk; nested: an empty inner shard
            if cfg["codecs"][0]["name"] == "sharding_indexed":
                out[-1:] = b""
                out += empty_shard(cfg["codecs"], inner)
            continue
        sub = blob[o:o + n]
        if cfg["codecs"][0]["name"] == "sharding_indexed":
            out += shard_tweaks(meta, sub, cfg["codecs"], inner)
        else:
            assert n < 65536
            out += bytes([13]) + struct.pack("<H", n) + sub
    return bytes(out)


def empty_shard(codecs, outer):
    """A nested shard the writer left out: one whose inner chunks are all
    absent (the harness always writes a nested shard)."""
    cfg = codecs[0]["configuration"]
    inner = cfg["chunk_shape"]
    count = int(np.prod([o // i for o, i in zip(outer, inner)]))
    if cfg["codecs"][0]["name"] == "sharding_indexed":
        return bytes([0]) + b"".join(empty_shard(cfg["codecs"], inner) for _ in range(count))
    return bytes([0]) + bytes([11]) * count


def array_tweaks(root, meta):
    shape, cs = meta["shape"], meta["chunk_grid"]["configuration"]["chunk_shape"]
    grid = [(s + c - 1) // c for s, c in zip(shape, cs)]
    sharded = meta["codecs"][0]["name"] == "sharding_indexed"
    out = bytearray()
    for pos in itertools.product(*[range(g) for g in grid]):
        p = os.path.join(root, *chunk_key(meta, pos).split("/"))
        if not os.path.exists(p):
            out += bytes([11])
            continue
        blob = open(p, "rb").read()
        if sharded:
            out += shard_tweaks(meta, blob, meta["codecs"], cs)
        else:
            assert len(blob) < 65536
            out += bytes([13]) + struct.pack("<H", len(blob)) + blob
    return bytes(out)


def seeds_of(root, name):
    """The seeds of the store at @root: a plain array, or an NGFF group."""
    top = json.load(open(os.path.join(root, "zarr.json")))
    if top["node_type"] == "array":
        head, _ = describe(top)
        body, meta0 = array_tweaks(root, top), top
    else:
        paths = [d["path"] for d in top["attributes"]["ome"]["multiscales"][0]["datasets"]]
        assert paths == [str(i) for i in range(len(paths))] and len(paths) <= 2
        metas = [json.load(open(os.path.join(root, p, "zarr.json"))) for p in paths]
        head, _ = describe(metas[0], len(paths))
        body = b"".join(array_tweaks(os.path.join(root, p), m) for p, m in zip(paths, metas))
        meta0 = metas[0]
    seed = head + body
    with open(os.path.join(OUT, f"ref-{name}"), "wb") as f:
        f.write(seed)
    with open(os.path.join(OUT, f"ref-{name}-json"), "wb") as f:
        f.write(head[:42] + bytes([head[42] | 8]) + seed[43:] + b"\n--JSON--\n" + json.dumps(meta0, separators=(",", ":")).encode())


rng = np.random.default_rng(78)
ZP = {  # zarr-python 3: shape, dtype, create_array keywords
    "zstd": ((5, 6, 7), "uint16", dict(chunks=(2, 3, 3), compressors=ZstdCodec(level=1))),
    "gzip-big": ((5, 6, 7), "int16", dict(chunks=(2, 3, 4), serializer=BytesCodec(endian="big"),
                                          compressors=GzipCodec(level=1))),
    "blosc": ((4, 6, 6), "float32", dict(chunks=(2, 3, 3), compressors=BloscCodec(
        cname="lz4", clevel=1, shuffle="shuffle", typesize=4))),
    "blosc-zstd-bit": ((4, 5, 6), "uint8", dict(chunks=(4, 5, 3), compressors=BloscCodec(
        cname="zstd", clevel=1, shuffle="bitshuffle", typesize=1))),
    "transpose-crc": ((5, 6, 7), "uint16", dict(chunks=(2, 3, 3),
                                                filters=[TransposeCodec(order=(2, 0, 1))],
                                                compressors=[GzipCodec(level=1), Crc32cCodec()])),
    "key-v2": ((5, 6, 7), "int32", dict(chunks=(3, 3, 3), compressors=None,
                                        chunk_key_encoding={"name": "v2", "separator": "."})),
    "key-dot": ((5, 6), "float64", dict(chunks=(2, 4), compressors=None,
                                        chunk_key_encoding={"name": "default", "separator": "."})),
    "2d-u64": ((9, 11), "uint64", dict(chunks=(4, 4), compressors=ZstdCodec(level=1))),
    "4d-i64": ((2, 3, 4, 5), "int64", dict(chunks=(1, 2, 2, 5), compressors=None)),
    "bool": ((4, 5, 6), "bool", dict(chunks=(2, 5, 3), compressors=None)),
    "shard": ((5, 6, 7), "uint16", dict(chunks=(2, 3, 3), shards=(4, 6, 6), compressors=None)),
    "shard-zstd-crc": ((6, 6, 6), "uint8", dict(chunks=(2, 3, 3), shards=(6, 6, 6),
                                                compressors=[ZstdCodec(level=1), Crc32cCodec()])),
    "shard-start": ((5, 6, 7), "uint16", dict(
        chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
            chunk_shape=(2, 3, 3), codecs=[BytesCodec(), ZstdCodec(level=1)],
            index_location="start"))),
    "shard-transpose": ((4, 6, 6), "int16", dict(
        chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
            chunk_shape=(2, 3, 3), codecs=[TransposeCodec(order=(1, 2, 0)),
                                           BytesCodec(endian="big"), GzipCodec(level=1)]))),
    "shard-nested": ((5, 6, 7), "uint16", dict(
        chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
            chunk_shape=(2, 6, 6), codecs=[ShardingCodec(chunk_shape=(2, 3, 3),
                                                         codecs=[BytesCodec()])]))),
    "shard-nested-start-crc": ((4, 6, 6), "float32", dict(
        chunks=(4, 6, 6), compressors=None, serializer=ShardingCodec(
            chunk_shape=(2, 6, 6), index_location="start", codecs=[ShardingCodec(
                chunk_shape=(2, 3, 3), codecs=[BytesCodec(), Crc32cCodec()],
                index_location="start")]))),
}
TS = {  # tensorstore's zarr3 driver: shape, dtype, codecs, chunks
    "ts-shard": ((5, 6, 7), "uint16", (4, 6, 6), [{"name": "sharding_indexed", "configuration": {
        "chunk_shape": [2, 3, 3], "codecs": [{"name": "bytes", "configuration": {
            "endian": "little"}}, {"name": "zstd", "configuration": {"level": 1}}],
        "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                         {"name": "crc32c"}], "index_location": "end"}}]),
    "ts-shard-start-gzip": ((6, 6, 6), "int32", (6, 6, 6), [{
        "name": "sharding_indexed", "configuration": {
            "chunk_shape": [3, 3, 3], "codecs": [{"name": "transpose", "configuration": {
                "order": [2, 1, 0]}}, {"name": "bytes", "configuration": {"endian": "big"}},
                {"name": "gzip", "configuration": {"level": 1}}],
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                             {"name": "crc32c"}], "index_location": "start"}}]),
    "ts-blosc": ((5, 6, 7), "float32", (3, 3, 4), [
        {"name": "bytes", "configuration": {"endian": "little"}},
        {"name": "blosc", "configuration": {"cname": "lz4", "clevel": 1, "shuffle": "shuffle",
                                            "typesize": 4, "blocksize": 0}}]),
    "ts-nested": ((4, 6, 6), "uint8", (4, 6, 6), [{"name": "sharding_indexed", "configuration": {
        "chunk_shape": [2, 6, 6], "codecs": [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [2, 3, 3], "codecs": [{"name": "bytes"}],
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                             {"name": "crc32c"}]}}],
        "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                         {"name": "crc32c"}]}}]),
}


def data(shape, dtype):
    if dtype == "bool":
        return rng.integers(0, 2, size=shape).astype(bool)
    return rng.integers(0, 100, size=shape).astype(dtype)


os.makedirs(OUT, exist_ok=True)
n = 0
with tempfile.TemporaryDirectory() as tmp:
    for name, (shape, dt, kw) in ZP.items():
        root = os.path.join(tmp, name)
        z = zarr.create_array(root, shape=shape, dtype=dt, zarr_format=3, fill_value=0,
                              dimension_names=["t", "c", "z", "y", "x"][5 - len(shape):], **kw)
        a = data(shape, dt)
        z[:] = a
        if "shard" in name or name == "zstd":
            z[tuple(slice(0, c) for c in kw["chunks"])] = 0  # an empty (inner) chunk
        seeds_of(root, "zarr-python-" + name)
        n += 2
    for name, (shape, dt, chunks, codecs) in TS.items():
        root = os.path.join(tmp, name)
        t = ts.open({"driver": "zarr3", "kvstore": {"driver": "file", "path": root},
                     "metadata": {"shape": list(shape), "data_type": dt, "codecs": codecs,
                                  "chunk_grid": {"name": "regular", "configuration": {
                                      "chunk_shape": list(chunks)}},
                                  "fill_value": 0}}, create=True).result()
        a = data(shape, dt)
        a[0:2, 0:3, 0:3] = 0
        t[...] = a
        seeds_of(root, "tensorstore-" + name[3:])
        n += 2
    # NGFF 0.5 groups by zarr-python: two levels, sharded; one level, plain
    for name, (lv, shards) in {"ngff05": (2, (1, 2, 4, 6, 6)), "ngff05-one": (1, None)}.items():
        root = os.path.join(tmp, name)
        g = zarr.open_group(root, mode="w")
        a5 = data((2, 2, 4, 6, 6), "uint8")
        ds = []
        for k in range(lv):
            a = a5[:, :, ::2 ** k, ::2 ** k, ::2 ** k]
            g.create_array(str(k), shape=a.shape, dtype=a.dtype, chunks=(1, 1, 2, 3, 3),
                           shards=shards, fill_value=0,
                           dimension_names=["t", "c", "z", "y", "x"])[:] = a
            ds.append({"path": str(k), "coordinateTransformations": [
                {"type": "scale", "scale": [1.0, 1.0] + [2.0 ** k] * 3}]})
        g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
            {"name": "t", "type": "time"}, {"name": "c", "type": "channel"}] + [
            {"name": x, "type": "space"} for x in "zyx"], "datasets": ds}]}
        seeds_of(root, "zarr-python-" + name)
        n += 2
# hand-made: zarr.json refusals only the merged JSON can make (the header
# always describes a valid chain), over the zarr-python "shard" seed
B = {"name": "bytes", "configuration": {"endian": "little"}}
G = {"name": "gzip", "configuration": {"level": 1}}


def nest(k):
    c = [B]
    for _ in range(k):
        c = [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [4, 6, 6], "codecs": c, "index_codecs": [B]}}]
    return c


HAND = {
    "order": {"codecs": [G, B]},
    "two-a2b": {"codecs": [B, B]},
    "transpose-late": {"codecs": [B, {"name": "transpose", "configuration": {
        "order": [0, 1, 2]}}]},
    "many-codecs": {"codecs": [B] + [{"name": "crc32c"}] * 9},
    "nest-5": {"codecs": nest(5)},
    "inner-many": {"shape": [64, 64, 128], "chunk_grid": {"name": "regular", "configuration": {
        "chunk_shape": [64, 64, 128]}}, "codecs": [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [1, 1, 1], "codecs": [B], "index_codecs": [B]}}]},
    "shard-wrapped": {"codecs": nest(1) + [G]},
    "index-gzip": {"codecs": [{"name": "sharding_indexed", "configuration": {
        "chunk_shape": [2, 3, 3], "codecs": [B], "index_codecs": [B, G]}}]},
    "index-sharded": {"codecs": [{"name": "sharding_indexed", "configuration": {
        "chunk_shape": [2, 3, 3], "codecs": [B], "index_codecs": nest(1)}}]},
    "blosc-cname": {"codecs": [B, {"name": "blosc", "configuration": {"cname": "nope"}}]},
    "codec-unknown": {"codecs": [B, {"name": "bz2"}]},
    "storage-transformers": {"storage_transformers": [{"type": "indexed"}]},
    "fill-hex": {"fill_value": "0x12zz"},
    "fill-null": {"fill_value": None},
}
base = open(os.path.join(OUT, "ref-zarr-python-shard"), "rb").read()
for name, merge in HAND.items():
    with open(os.path.join(OUT, f"hand-{name}"), "wb") as f:
        f.write(base + b"\n--JSON--\n" + json.dumps(merge, separators=(",", ":")).encode())
    n += 1
# hand-made, issue 89: several channels out of core at once (header bytes
# 45, 46) and hostile "omero" blocks (merged into the group after a line
# "--GROUP--"), over the zarr-python NGFF seed (two channels, two levels)
ngff = bytearray(open(os.path.join(OUT, "ref-zarr-python-ngff05"), "rb").read())


def chans(which):
    h = bytearray(ngff)
    h[45] = len(which)
    h[46] = sum(c << (2 * k) for k, c in enumerate(which))
    return bytes(h)


def omero(*windows):
    return {"omero": {"channels": [{"label": f"c{k}", "color": "00FF00", "active": True,
                                    "window": w} for k, w in enumerate(windows)]}}


W = {"min": 0, "max": 255, "start": 10, "end": 200}
CHANNELS = {
    "two": (chans([1, 0]), {}, omero(W, W)),
    "past": (chans([1, 0, 3]), {}, {}),
    "four-same": (chans([0, 1, 0, 1]), {}, {}),
    "many": (chans([0, 1]), {"shape": [2, 17, 4, 6, 6]}, {}),
    "chunks-differ": (chans([0, 1]), {"chunk_grid": {"name": "regular", "configuration": {
        "chunk_shape": [1, 1, 4, 6, 6]}}}, {}),
    "window-inverted": (chans([0, 1]), {}, omero({"min": 255, "max": 0, "start": 200, "end": 10},
                                                 W)),
    "window-absurd": (chans([0, 1]), {}, omero({"min": -1e308, "max": 1e308, "start": 1e300,
                                                "end": -1e300}, {"start": "a", "end": [1]})),
    "window-missing": (chans([1, 0]), {}, omero({}, {"start": 3})),
    "omero-more": (chans([0, 1]), {}, omero(W, W, W)),
    "omero-one": (chans([0, 1]), {}, omero(W)),
    "omero-bad": (chans([0, 1]), {}, {"omero": {"channels": {"a": 1}}}),
    "inactive": (chans([0, 1]), {}, {"omero": {"channels": [{"active": False, "window": W},
                                                            {"active": "no"}]}}),
}
for name, (head, level0, group) in CHANNELS.items():
    with open(os.path.join(OUT, f"hand-channels-{name}"), "wb") as f:
        f.write(head + b"\n--JSON--\n" + json.dumps(level0, separators=(",", ":")).encode() +
                b"\n--GROUP--\n" + json.dumps(group, separators=(",", ":")).encode())
    n += 1
print(f"wrote {n} seeds to {OUT}")
