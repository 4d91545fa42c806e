#!/usr/bin/env python3
"""Zarr v3 and OME-Zarr 0.5 stores written by the reference implementations, read by VolVis.

  zarr3_read_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test): zarr-python 3,
tensorstore, ome-zarr-py and ngff-zarr write, VolVis reads:

- zarr-python 3 arrays, one per codec chain: zstd, gzip with big-endian bytes,
  blosc (lz4 + shuffle, zstd + bitshuffle), gzip + crc32c, transpose +
  big-endian + gzip + crc32c; chunk keys "default" with "/" and "." and "v2"
  with "." and "/"; chunks that do not divide the shape; bool, int8 .. uint64,
  float32, float64; fill values NaN, "Infinity", "-Infinity" and hex bits with
  chunks left out; dimension_names t, c, z, y, x; sharded (index at the end
  and at the start, inner zstd, gzip, transpose + crc32c, inner chunks equal
  to the fill value left empty, nested shards);
- tensorstore zarr3 arrays, sharded (inner gzip, index with crc32c) and not;

each checked with `volvis convert STORE OUT.nrrd` voxel for voxel against
numpy (the NRRD read back here);

- an OME-Zarr 0.5 image (t, c, z, y, x, two levels, omero labels, colours and
  windows, scale and translation) written by ome-zarr-py: `volvis info` names
  2 time steps 40 ms apart, 3 channels with their labels and colours and
  2 levels; convert reads channel 1 at step 1 with the right spacing and origin;
- an OME-Zarr 0.5 image written by ngff-zarr (sharded, c, z, y, x) read alike;
- a sharded NGFF 0.5 pyramid rendered out of core (`--memory-limit 64M
  --level 0`) is the same pyramid written as unsharded Zarr v2 pixel for
  pixel, and within one step of the in-memory (unrefined) MIP;
- hostile stores: a bad crc32c in a chunk, an unknown codec, a data type we do
  not hold, a dataset path that leaves the store: one line naming the store,
  a non-zero exit, no output.
"""
import json
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import zarr
    from zarr.codecs import (BloscCodec, BytesCodec, Crc32cCodec, GzipCodec, ShardingCodec,
                             TransposeCodec, ZstdCodec)
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks, read_nrrd, run, write_stores  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
failures = check.failures


def volvis(*args):
    return run(VOLVIS, *args)


def read_back(store, *args):
    out = os.path.join(OUT, "back.nrrd")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("convert", store, out, "--quiet", *args)
    if p.returncode != 0:
        check(False, f"convert {os.path.basename(store)} {' '.join(args)}: {p.stderr.strip()}")
        return None, None, None
    return read_nrrd(out)


def same(got, want):
    if got is None:
        return False
    if got.shape != want.shape:
        return False
    if want.dtype.kind == "f":
        return bool(np.array_equal(got.astype(np.float64), want.astype(np.float64),
                                   equal_nan=True))
    return bool(np.array_equal(got.astype(np.float64), want.astype(np.float64)))


def expect_read(store, want, what, *args):
    got, _, _ = read_back(store, *args)
    check(same(got, want), f"{what}: voxels ({None if got is None else got.dtype}, "
          f"{None if got is None else got.shape})")


rng = np.random.default_rng(78)
Z, Y, X = 9, 11, 13


def data(dt):
    dt = np.dtype(dt)
    if dt.kind == "f":
        return rng.normal(0, 100, size=(Z, Y, X)).astype(dt)
    if dt.kind == "b":
        return rng.integers(0, 2, size=(Z, Y, X)).astype(bool)
    info = np.iinfo(dt)
    lo, hi = max(info.min, -(1 << 40)), min(info.max, 1 << 40)
    return rng.integers(lo, hi, size=(Z, Y, X), dtype=dt)


def zp3(name, dt, **kw):
    """A zarr-python 3 array at OUT/name of data(dt), chunks (4, 5, 6) unless given."""
    path = os.path.join(OUT, name)
    arr = data(dt)
    kw.setdefault("chunks", (4, 5, 6))
    z = zarr.create_array(path, shape=arr.shape, dtype=arr.dtype, zarr_format=3,
                          overwrite=True, **kw)
    z[:] = arr
    return path, arr


# ---- zarr-python 3: codecs, key encodings, types ----------------------------------------------
cases = [
    ("zstd_u2", "u2", dict(compressors=ZstdCodec(level=3))),
    ("gzip_big_i2", "i2", dict(serializer=BytesCodec(endian="big"), compressors=GzipCodec(level=5))),
    ("blosc_lz4_f4", "f4", dict(compressors=BloscCodec(cname="lz4", clevel=5, shuffle="shuffle",
                                                       typesize=4))),
    ("blosc_zstd_i4", "i4", dict(compressors=BloscCodec(cname="zstd", clevel=3,
                                                        shuffle="bitshuffle", typesize=4))),
    ("crc32c_u4", "u4", dict(compressors=[GzipCodec(), Crc32cCodec()])),
    ("transpose_u2", "u2", dict(filters=[TransposeCodec(order=(2, 0, 1))],
                                serializer=BytesCodec(endian="big"),
                                compressors=[GzipCodec(), Crc32cCodec()])),
    ("key_dot_f8", "f8", dict(chunk_key_encoding={"name": "default", "separator": "."})),
    ("key_v2_i1", "i1", dict(chunk_key_encoding={"name": "v2", "separator": "."})),
    ("key_v2_slash_u1", "u1", dict(chunk_key_encoding={"name": "v2", "separator": "/"})),
    ("raw_i8", "i8", dict(compressors=None)),
    ("raw_u8", "u8", dict(compressors=None)),
    ("bool", "bool", dict()),
    # sharded
    ("shard_zstd_u2", "u2", dict(shards=(8, 10, 12), compressors=ZstdCodec())),
    ("shard_start_i2", "i2", dict(chunks=(8, 10, 12), compressors=None, serializer=ShardingCodec(
        chunk_shape=(4, 5, 6), codecs=[BytesCodec(), GzipCodec()], index_location="start"))),
    ("shard_transpose_f4", "f4", dict(chunks=(8, 10, 12), compressors=None, serializer=ShardingCodec(
        chunk_shape=(4, 5, 6), codecs=[TransposeCodec(order=(1, 2, 0)), BytesCodec(endian="big"),
                                       Crc32cCodec()]))),
    ("shard_nested_u2", "u2", dict(chunks=(16, 20, 24), compressors=None, serializer=ShardingCodec(
        chunk_shape=(8, 10, 12), codecs=[ShardingCodec(chunk_shape=(4, 5, 6),
                                                       codecs=[BytesCodec(), ZstdCodec()])]))),
]
for name, dt, kw in cases:
    path, arr = zp3(name + ".zarr", dt, **kw)
    expect_read(path, arr, f"zarr-python 3 {name}")
    meta = json.load(open(os.path.join(path, "zarr.json")))
    if name == "transpose_u2":
        check([c["name"] for c in meta["codecs"]] == ["transpose", "bytes", "gzip", "crc32c"],
              "the transpose store has the chain it was asked for")
    if name == "shard_nested_u2":
        inner = meta["codecs"][0]["configuration"]["codecs"][0]["name"]
        check(inner == "sharding_indexed", f"the nested store is nested ({inner})")

# inner chunks equal to the fill value are left empty in the shard; chunks left out
path = os.path.join(OUT, "shard_fill_u2.zarr")
arr = data("u2")
arr[0:4, 0:5, 0:6] = 7
z = zarr.create_array(path, shape=arr.shape, dtype=arr.dtype, chunks=(4, 5, 6), shards=(8, 10, 12),
                      fill_value=7, zarr_format=3, overwrite=True)
z[:] = arr
idx = open(os.path.join(path, "c", "0", "0", "0"), "rb").read()[-(8 * 16 + 4):]
check(idx[:16] == b"\xff" * 16, "zarr-python left the fill-valued inner chunk empty")
expect_read(path, arr, "sharded, an empty inner chunk is the fill value 7")
z = zarr.create_array(os.path.join(OUT, "shard_part.zarr"), shape=arr.shape, dtype=arr.dtype,
                      chunks=(4, 5, 6), shards=(8, 10, 12), fill_value=3, zarr_format=3)
z[0:8, 0:10, 0:12] = arr[0:8, 0:10, 0:12]
want = np.full_like(arr, 3)
want[0:8, 0:10, 0:12] = arr[0:8, 0:10, 0:12]
expect_read(os.path.join(OUT, "shard_part.zarr"), want, "sharded, shards left out are the fill value")

# fill values: NaN, Infinity, -Infinity, hex bits; chunks left out
for fill, value in [("NaN", np.nan), ("Infinity", np.inf), ("-Infinity", -np.inf),
                    ("0x7fc00000", np.nan), ("0x40490fdb", np.float32(3.1415927))]:
    path = os.path.join(OUT, f"fill_{fill.strip('-')}{'_neg' if fill[0] == '-' else ''}.zarr")
    arr = data("f4")
    z = zarr.create_array(path, shape=arr.shape, dtype=arr.dtype, chunks=(4, 5, 6),
                          fill_value=0.0, zarr_format=3, overwrite=True)
    z[0:4] = arr[0:4]
    meta = json.load(open(os.path.join(path, "zarr.json")))
    meta["fill_value"] = fill
    json.dump(meta, open(os.path.join(path, "zarr.json"), "w"))
    want = arr.copy()
    want[4:] = value
    expect_read(path, want, f"fill_value \"{fill}\" for the chunks left out")

# dimension_names name the axes (no OME metadata): t, c, z, y, x
path = os.path.join(OUT, "tczyx.zarr")
arr5 = rng.integers(0, 60000, size=(3, 2, Z, Y, X), dtype=np.uint16)
z = zarr.create_array(path, shape=arr5.shape, dtype=arr5.dtype, chunks=(1, 2, 4, 5, 6),
                      shards=(1, 2, 8, 10, 12), dimension_names=["t", "c", "z", "y", "x"],
                      zarr_format=3)
z[:] = arr5
expect_read(path, arr5[2, 1], "dimension_names t, c, z, y, x: channel 1 at step 2",
            "--channel", "1", "--time", "2")
p = volvis("info", path)
check(p.returncode == 0 and "channels:     2 (this is channel 0)" in p.stdout and
      "time steps:   3 (this is step 0)" in p.stdout,
      f"info of a plain 5-D array: 2 channels, 3 steps ({p.stderr.strip()})")

# ---- tensorstore --------------------------------------------------------------------------------
try:
    import tensorstore as ts
except ImportError as e:  # pragma: no cover
    ts = None
    check(False, f"tensorstore is importable ({e})")
if ts:
    for name, codecs in [
        ("ts_shard_gzip", [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [4, 5, 6],
            "codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                       {"name": "gzip", "configuration": {"level": 6}}],
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                             {"name": "crc32c"}]}}]),
        ("ts_shard_start_big", [{"name": "sharding_indexed", "configuration": {
            "chunk_shape": [4, 5, 6], "index_location": "start",
            "codecs": [{"name": "bytes", "configuration": {"endian": "big"}},
                       {"name": "zstd", "configuration": {"level": 3}}],
            "index_codecs": [{"name": "bytes", "configuration": {"endian": "little"}},
                             {"name": "crc32c"}]}}]),
        ("ts_blosc", [{"name": "bytes", "configuration": {"endian": "little"}},
                      {"name": "blosc", "configuration": {"cname": "zstd", "clevel": 5,
                                                          "shuffle": "shuffle", "typesize": 2}}]),
    ]:
        path = os.path.join(OUT, name + ".zarr")
        arr = data("i2")
        grid = [4, 5, 6] if name == "ts_blosc" else [8, 10, 12]
        t = ts.open({"driver": "zarr3", "kvstore": {"driver": "file", "path": path},
                     "metadata": {"shape": list(arr.shape), "data_type": "int16",
                                  "chunk_grid": {"name": "regular",
                                                 "configuration": {"chunk_shape": grid}},
                                  "codecs": codecs}},
                    create=True, delete_existing=True).result()
        t.write(arr).result()
        expect_read(path, arr, f"tensorstore {name}")

# ---- OME-Zarr 0.5: ome-zarr-py ------------------------------------------------------------------
T, C = 2, 3
img = rng.integers(0, 4000, size=(T, C, 16, 20, 24), dtype=np.uint16)
try:
    from ome_zarr.format import FormatV05
    from ome_zarr.writer import write_image
except ImportError as e:  # pragma: no cover
    write_image = None
    check(False, f"ome-zarr-py is importable ({e})")
if write_image:
    path = os.path.join(OUT, "omezarr.ome.zarr")
    g = zarr.open_group(path, mode="w")
    write_image(img, g, scale_factors=[2], axes="tczyx", fmt=FormatV05(),
                scale={"t": 40.0, "c": 1.0, "z": 2.0, "y": 0.5, "x": 0.25},
                axes_units={"t": "millisecond", "z": "micrometer", "y": "micrometer",
                            "x": "micrometer"},
                storage_options={"chunks": (1, 1, 8, 10, 12)})
    g.attrs["ome"] = {**g.attrs["ome"], "omero": {"channels": [
        {"label": "nuclei", "color": "FF00FF", "window": {"min": 0, "max": 4000, "start": 10,
                                                          "end": 3000}},
        {"label": "actin", "color": "00FF00", "window": {"min": 0, "max": 4000, "start": 0,
                                                         "end": 4000}},
        {"label": "dna", "color": "0000FF", "window": {"min": 0, "max": 4000, "start": 0,
                                                       "end": 4000}}]}}
    root = json.load(open(os.path.join(path, "zarr.json")))
    check(root["attributes"]["ome"]["version"] == "0.5" and not os.path.exists(
        os.path.join(path, ".zattrs")), "ome-zarr-py wrote NGFF 0.5 (Zarr v3)")
    p = volvis("info", path, "--channel", "1", "--time", "1")
    lines = p.stdout.splitlines()
    check(p.returncode == 0 and "channels:     3 (this is channel 1)" in lines and
          any(ln.startswith('  channel 0   "nuclei" #ff00ff') for ln in lines) and
          any(ln.startswith('  channel 1   "actin" #00ff00') for ln in lines) and
          any(ln.startswith('  channel 2   "dna" #0000ff') for ln in lines) and
          "time steps:   2 (this is step 1), 0.04 s apart" in lines,
          f"info of ome-zarr-py's 0.5 image: 3 named, coloured channels, 2 steps 40 ms apart "
          f"({p.stderr.strip()} {[ln for ln in lines if 'channel' in ln or 'step' in ln]})")
    got, spacing, origin = read_back(path, "--channel", "1", "--time", "1")
    check(same(got, img[1, 1]), "ome-zarr-py 0.5: channel 1 at step 1, voxels")
    check(spacing is not None and np.allclose(spacing, [0.25, 0.5, 2.0]) and
          np.allclose(origin, [0, 0, 0]),
          f"ome-zarr-py 0.5: spacing and origin from the transforms ({spacing}, {origin})")
    # ome-zarr-py halves y and x only
    got, spacing, origin = read_back(path, "--channel", "2", "--time", "0", "--level", "1")
    check(got is not None and got.shape == (16, 10, 12) and np.allclose(spacing, [0.5, 1.0, 2.0])
          and np.allclose(origin, [0.125, 0.25, 0]),
          f"ome-zarr-py 0.5: level 1 ({None if got is None else got.shape}, {spacing}, {origin})")

# ---- OME-Zarr 0.5: ngff-zarr (sharded) ---------------------------------------------------------
try:
    import ngff_zarr as nz
except ImportError as e:  # pragma: no cover
    nz = None
    check(False, f"ngff-zarr is importable ({e})")
if nz:
    cz = rng.integers(0, 255, size=(2, 32, 40, 48), dtype=np.uint8)
    image = nz.to_ngff_image(cz, dims=["c", "z", "y", "x"], scale={"z": 2.0, "y": 0.5, "x": 0.5},
                             translation={"z": 4.0, "y": 1.0, "x": -2.0},
                             axes_units={"z": "micrometer", "y": "micrometer", "x": "micrometer"})
    ms = nz.to_multiscales(image, scale_factors=[2], chunks=8)
    path = os.path.join(OUT, "ngff.ome.zarr")
    nz.to_ngff_zarr(path, ms, version="0.5", chunks_per_shard=2)
    arrmeta = json.load(open(os.path.join(path, "scale0", "image", "zarr.json"))) \
        if os.path.exists(os.path.join(path, "scale0", "image", "zarr.json")) else None
    if arrmeta is None:
        root = json.load(open(os.path.join(path, "zarr.json")))
        p0 = root["attributes"]["ome"]["multiscales"][0]["datasets"][0]["path"]
        arrmeta = json.load(open(os.path.join(path, p0, "zarr.json")))
    check(arrmeta["codecs"][0]["name"] == "sharding_indexed", "ngff-zarr wrote shards")
    got, spacing, origin = read_back(path, "--channel", "1")
    check(same(got, cz[1]), "ngff-zarr 0.5 (sharded): channel 1, voxels")
    check(spacing is not None and np.allclose(spacing, [0.5, 0.5, 2.0]) and
          np.allclose(origin, [-2.0, 1.0, 4.0]),
          f"ngff-zarr 0.5: spacing and origin ({spacing}, {origin})")

# ---- a sharded pyramid out of core ------------------------------------------------------------
# and the same levels as Zarr v2 (OME-Zarr 0.4, unsharded): the reader VolVis had
path, v2 = write_stores(OUT, 96, rng, ("pyramid.ome.zarr", "pyramid_v2.ome.zarr"))
mem, ooc, ooc2 = (os.path.join(OUT, f"pyr_{x}.png") for x in ("mem", "ooc", "ooc_v2"))
how = ["--size", "128x128", "--mode", "mip", "--tf", "50:1000"]
p1 = volvis("render", path, "-o", mem, *how, "--set", "refinement=off")
p2 = volvis("render", path, "-o", ooc, *how, "--memory-limit", "64M", "--level", "0")
p3 = volvis("render", v2, "-o", ooc2, *how, "--memory-limit", "64M", "--level", "0")
check(p1.returncode == 0 and p2.returncode == 0 and p3.returncode == 0 and
      "out of core" in p2.stdout,
      f"a sharded NGFF 0.5 pyramid renders in memory and out of core at 64M "
      f"({p1.stderr.strip()} {p2.stderr.strip()} {p3.stderr.strip()} {p2.stdout.strip()})")
if p1.returncode == 0 and p2.returncode == 0 and p3.returncode == 0:
    from PIL import Image
    a, b, c = (np.asarray(Image.open(x).convert("RGB")).astype(np.int64) for x in (mem, ooc, ooc2))
    check(np.array_equal(b, c) and b.max() > 0,
          "out of core, the sharded v3 pyramid is the v2 one pixel for pixel")
    # region renders differ from the whole-frame one by a rounding step at most
    # (the v2 pyramid alike)
    check(a.shape == b.shape and int(np.abs(a - b).max()) <= 1,
          f"out of core against in memory: {int(np.abs(a - b).max())} <= 1 apart")
p = volvis("info", path)
check(p.returncode == 0 and "levels" in p.stdout.lower(), f"info of the pyramid ({p.stderr.strip()})")
# a pyramid whose level 0 is more than info reads (a quarter of a 4 MiB budget here;
# 256 MiB by default): level 0's header and the levels listed, the statistics of the
# finest level that fits, against zarr-python's read of that level; --level 0 reads
# level 0 whole


def info_stats(out):
    rng = [ln.split(":", 1)[1].split("..") for ln in out.splitlines() if ln.startswith("range:")]
    mean = [ln.split()[1] for ln in out.splitlines() if ln.startswith("mean:")]
    return ((float(rng[0][0]), float(rng[0][1])) if rng else None,
            float(mean[0]) if mean else None)


grp = zarr.open_group(path, mode="r")
lv = {L: grp[str(L)][...] for L in (0, 1)}
p = volvis("--max-memory", "4M", "info", path)
(rng, mean) = info_stats(p.stdout) if p.returncode == 0 else (None, None)
check(p.returncode == 0 and "dimensions:   96 x 96 x 96" in p.stdout and
      "level 1: 48 x 48 x 48, spacing 2 x 2 x 2 (the statistics below)" in p.stdout and
      "statistics:   of level 1 (48 x 48 x 48): level 0 is more than info reads" in p.stdout and
      rng == (float(lv[1].min()), float(lv[1].max())) and mean is not None and
      abs(mean - lv[1].astype(np.float64).mean()) < 1e-3,
      f"info of a pyramid larger than it reads: level 0's header, level 1's statistics "
      f"({rng}, {mean}; {p.stderr.strip()})")
p = volvis("--max-memory", "4M", "info", "--level", "0", path)
(rng, mean) = info_stats(p.stdout) if p.returncode == 0 else (None, None)
check(p.returncode == 0 and "(the statistics below)" in p.stdout and
      "level 0: 96 x 96 x 96, spacing 1 x 1 x 1 (the statistics below)" in p.stdout and
      rng == (float(lv[0].min()), float(lv[0].max())) and
      abs(mean - lv[0].astype(np.float64).mean()) < 1e-3,
      f"info --level 0 reads level 0 whole ({rng}, {mean}; {p.stderr.strip()})")

# ---- hostile stores ----------------------------------------------------------------------------


def refused(args, needle, what):
    out = args[2] if len(args) > 2 else None
    if out and os.path.exists(out):
        os.remove(out)
    p = volvis(*args)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode != 0 and len(lines) == 1 and needle in lines[0] and
          (not out or not os.path.exists(out)), f"{what}: {lines[:2]} (exit {p.returncode})")


bad_out = os.path.join(OUT, "bad.nrrd")
src = os.path.join(OUT, "crc32c_u4.zarr")
bad = os.path.join(OUT, "bad_crc.zarr")
shutil.copytree(src, bad)
f = os.path.join(bad, "c", "0", "0", "0")
b = bytearray(open(f, "rb").read())
b[-1] ^= 0xFF
open(f, "wb").write(bytes(b))
refused(["convert", bad, bad_out, "-q"], "c/0/0/0: crc32c checksum mismatch", "a damaged crc32c")
bad = os.path.join(OUT, "bad_codec.zarr")
shutil.copytree(os.path.join(OUT, "zstd_u2.zarr"), bad)
m = json.load(open(os.path.join(bad, "zarr.json")))
m["codecs"].append({"name": "lzma"})
json.dump(m, open(os.path.join(bad, "zarr.json"), "w"))
refused(["convert", bad, bad_out, "-q"], "zarr.json: codecs: codec \"lzma\"", "an unknown codec")
m["codecs"] = m["codecs"][1:2]
json.dump(m, open(os.path.join(bad, "zarr.json"), "w"))
refused(["convert", bad, bad_out, "-q"], "before the array-to-bytes codec",
        "a codec chain without bytes")
m["codecs"] = [{"name": "bytes", "configuration": {"endian": "little"}}]
m["data_type"] = "complex128"
json.dump(m, open(os.path.join(bad, "zarr.json"), "w"))
refused(["convert", bad, bad_out, "-q"], "zarr.json: data_type \"complex128\"", "complex128")
bad = os.path.join(OUT, "bad_path.ome.zarr")
shutil.copytree(os.path.join(OUT, "pyramid.ome.zarr"), bad)
m = json.load(open(os.path.join(bad, "zarr.json")))
m["attributes"]["ome"]["multiscales"][0]["datasets"][2]["path"] = "/etc"
json.dump(m, open(os.path.join(bad, "zarr.json"), "w"))
refused(["info", bad], "zarr.json: dataset 2: path \"/etc\" leaves the store",
        "info of a 0.5 store whose level 2 leaves it")

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
