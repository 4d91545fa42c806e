#!/usr/bin/env python3
"""A large sharded OME-Zarr 0.5 pyramid rendered out of core against the
same level rendered in memory, and the bytes the out-of-core render read
against the inner chunks it needed.

    .venv/bin/python bench/zarr3_ooc.py build/release/volvis [--size 1024] \
        [--limit 64M] [--out build/bench-out/zarr3_ooc]

Writes a SIZE^3 u16 volume as raw NRRD (a smooth field, noise and a few
bright spheres, so that MIP shows structure), converts it with `volvis
convert --ngff 0.5 --chunk 64 --shard 256 --compress zstd` (a pyramid of
sharded levels; tests/io/zarr3_write_cli.py checks that writer against
zarr-python 3, tensorstore and ome-zarr-py), then renders level 0 as a
MIP at 512x512 twice: in memory (the volume read whole) and with
`--memory-limit LIMIT` (out of core, inner chunk by inner chunk). Prints:

    anchor=volvis op=zarr3_ooc_psnr  ... unit=dB     (goal >= 60)
    anchor=volvis op=zarr3_ooc_bytes ... unit=ratio  (goal <= 1.2)

The bytes ratio is what the render read (its `MiB read`) over the
compressed bytes of the inner chunks it decoded: each shard's index (read
here with numpy, checked against its CRC-32C) gives every inner chunk's
size, and the level-0 chunk reads of the render's report times the mean
inner chunk size of the level is what those reads needed (the index reads
and any read of more than a chunk are the excess).
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys

import numpy as np
from PIL import Image


def make_volume(path, n):
    raw = path + ".raw"
    if os.path.exists(path) and os.path.getsize(raw) == 2 * n ** 3:
        return
    rng = np.random.default_rng(3)
    c = np.linspace(-1, 1, n, dtype=np.float32)
    centres = rng.uniform(-0.7, 0.7, (12, 3)).astype(np.float32)
    radii = rng.uniform(0.03, 0.12, 12).astype(np.float32)
    with open(raw, "wb") as f:
        for z0 in range(0, n, 32):
            z = c[z0:z0 + 32, None, None]
            r2 = z ** 2 + c[None, :, None] ** 2 + c[None, None, :] ** 2
            v = 8000 * np.exp(-3 * r2) + rng.integers(0, 256, (len(z), n, n))
            for (cx, cy, cz), r in zip(centres, radii):
                d2 = (z - cz) ** 2 + (c[None, :, None] - cy) ** 2 + (c[None, None, :] - cx) ** 2
                v = np.where(d2 < r * r, 30000 + 20000 * (1 - d2 / (r * r)), v)
            f.write(v.astype("<u2").tobytes())
    with open(path, "w") as f:
        f.write(f"NRRD0004\ntype: uint16\ndimension: 3\nsizes: {n} {n} {n}\n"
                f"spacings: 1 1 1\nendian: little\nencoding: raw\n"
                f"data file: {os.path.basename(raw)}\n\n")


def shard_chunk_bytes(level_dir):
    """The compressed size of every inner chunk of a sharded level (its
    shard indexes, index at the end: offset and size per chunk, then the
    CRC-32C), and their count."""
    import crc32c
    meta = json.load(open(os.path.join(level_dir, "zarr.json")))
    sh = [c for c in meta["codecs"] if c["name"] == "sharding_indexed"][0]["configuration"]
    shard = meta["chunk_grid"]["configuration"]["chunk_shape"]
    inner = sh["chunk_shape"]
    n = int(np.prod([s // i for s, i in zip(shard, inner)]))
    total, count = 0, 0
    for f in glob.glob(os.path.join(level_dir, "c", "*", "*", "*")):
        b = open(f, "rb").read()
        ix = b[-(16 * n + 4):]
        if crc32c.crc32c(ix[:-4]) != int.from_bytes(ix[-4:], "little"):
            sys.exit(f"zarr3_ooc: {f}: the shard index's CRC-32C does not match")
        e = np.frombuffer(ix[:-4], "<u8").reshape(n, 2)
        full = e[:, 0] != np.uint64(2 ** 64 - 1)
        total += int(e[full, 1].sum())
        count += int(full.sum())
    return total, count


def psnr(a, b):
    x = np.asarray(Image.open(a).convert("RGB"), np.float64)
    y = np.asarray(Image.open(b).convert("RGB"), np.float64)
    mse = ((x - y) ** 2).mean()
    return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("volvis")
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--limit", default="64M")
    ap.add_argument("--out", default="build/bench-out/zarr3_ooc")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    nrrd = os.path.join(a.out, f"u16_{a.size}.nhdr")
    store = os.path.join(a.out, f"u16_{a.size}_zstd_s256.ome.zarr")
    make_volume(nrrd, a.size)
    if not os.path.exists(os.path.join(store, "zarr.json")):
        subprocess.run([a.volvis, "convert", nrrd, store, "--ngff", "0.5", "--chunk", "64",
                        "--shard", "256", "--compress", "zstd", "-q"], check=True)
    how = ["--mode", "mip", "--tf", "0:50000", "--size", "512x512", "--level", "0"]
    mem = os.path.join(a.out, "in_memory.png")
    ooc = os.path.join(a.out, "out_of_core.png")
    subprocess.run([a.volvis, "render", store, *how, "-q", "-o", mem], check=True)
    r = subprocess.run([a.volvis, "render", store, *how, "--memory-limit", a.limit, "-o", ooc],
                       check=True, capture_output=True, text=True)
    report = r.stdout.strip()
    print("#", report)
    m = re.search(r"0: \d+ nodes (\d+) chunks", report)
    mib = re.search(r"([0-9.]+) MiB read", report)
    if not m or not mib:
        sys.exit(f"zarr3_ooc: no chunk count or bytes in the report: {report}")
    reads, read_bytes = int(m.group(1)), float(mib.group(1)) * 1048576
    total, count = shard_chunk_bytes(os.path.join(store, "0"))
    needed = reads * total / count
    p = psnr(mem, ooc)
    name = os.path.basename(store)
    print(f"anchor=volvis op=zarr3_ooc_psnr dataset={name} value={p:.2f} unit=dB")
    print(f"anchor=volvis op=zarr3_ooc_bytes dataset={name} value={read_bytes / needed:.4f} "
          f"unit=ratio")
    print(f"# level 0: {count} inner chunks, {total / 1048576:.1f} MiB compressed; the render "
          f"read {reads} chunks, {read_bytes / 1048576:.1f} MiB, for {needed / 1048576:.1f} MiB "
          f"of inner chunks; MIP in memory vs out of core {p:.2f} dB")


if __name__ == "__main__":
    main()
