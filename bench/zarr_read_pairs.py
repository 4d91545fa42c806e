#!/usr/bin/env python3
"""Same-run pairs: one level of a Zarr v3 store read whole into memory by
VolVis (bench_zarr_read), zarr-python 3 and tensorstore, each at the same
number of threads (default 2), median of REPEAT reads (default 3).

Run with the virtual environment's Python (scripts/install-deps.sh bench
makes .venv with the pinned zarr 3 and tensorstore):

    .venv/bin/python bench/zarr_read_pairs.py build/release/bench/bench_zarr_read \
        [--size 512] [--chunk 64] [--shard 256] [--codec zstd] [--threads 2] \
        [--repeat 3] [--out build/bench-out/zarr_read]

Writes a SIZE^3 u16 store (a smooth field plus noise, so that it compresses
as scans do) with zarr-python 3: chunks CHUNK^3 inside shards SHARD^3
(--shard 0: not sharded), the codec CODEC (zstd level 3, blosc lz4 with
shuffle, gzip 1 or none). The files are read once by each reader before
timing (all read from the page cache). Every reader's voxel sum is compared:
a reader that reads other voxels fails the run. Prints the anchor lines of
../shared/BENCHMARKS.md and the ratios volvis / peer (time of the peer over
VolVis's: above 1, VolVis is faster), in wall seconds and in CPU seconds
(the process's, all threads, and for VolVis its reader processes too:
what a loaded machine distorts least).
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import tensorstore as ts
import zarr
from zarr.codecs import BloscCodec, BytesCodec, GzipCodec, ZstdCodec


def make_store(path, size, chunk, shard, codec):
    stamp = os.path.join(path, ".made")
    want = f"{size} {chunk} {shard} {codec}\n"
    if os.path.exists(stamp) and open(stamp).read() == want:
        return
    rng = np.random.default_rng(7)
    z = np.linspace(-1, 1, size, dtype=np.float32)
    compressors = {
        "zstd": [ZstdCodec(level=3)],
        "blosc": [BloscCodec(cname="lz4", clevel=5, shuffle="shuffle")],
        "gzip": [GzipCodec(level=1)],
        "none": [],
    }[codec]
    kw = dict(shape=(size,) * 3, chunks=(chunk,) * 3, dtype="uint16", compressors=compressors,
              serializer=BytesCodec(endian="little"), fill_value=0, zarr_format=3,
              dimension_names=["z", "y", "x"])
    if shard:
        kw["shards"] = (shard,) * 3
    arr = zarr.create_array(store=path, overwrite=True, **kw)
    for k0 in range(0, size, chunk):
        zz = z[k0:k0 + chunk, None, None]
        slab = (np.sqrt(zz ** 2 + z[None, :, None] ** 2 + z[None, None, :] ** 2) * 2000
                + rng.integers(0, 64, (len(zz), size, size))).astype(np.uint16)
        arr[k0:k0 + chunk] = slab
    open(stamp, "w").write(want)


def time_it(fn, repeat):
    """Median wall seconds and median CPU seconds (the process's, all threads) of a read."""
    fn()  # warm: the files in the page cache, the readers' set-up done
    times, cpus, out = [], [], None
    for _ in range(repeat):
        out = None
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(times), statistics.median(cpus), out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bench")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--chunk", type=int, default=64)
    ap.add_argument("--shard", type=int, default=256)
    ap.add_argument("--codec", default="zstd", choices=["zstd", "blosc", "gzip", "none"])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="build/bench-out/zarr_read")
    a = ap.parse_args()
    name = f"u16_{a.size}_{a.codec}_c{a.chunk}_s{a.shard}.zarr"
    path = os.path.join(a.out, name)
    os.makedirs(a.out, exist_ok=True)
    make_store(path, a.size, a.chunk, a.shard, a.codec)

    zarr.config.set({"threading.max_workers": a.threads, "async.concurrency": 2 * a.threads})
    t_zarr, c_zarr, v = time_it(lambda: zarr.open_array(path, mode="r")[...], a.repeat)
    sum_zarr = float(v.astype(np.float64).sum())
    del v
    ctx = ts.Context({"data_copy_concurrency": {"limit": a.threads},
                      "file_io_concurrency": {"limit": a.threads}})
    spec = {"driver": "zarr3", "kvstore": {"driver": "file", "path": path}}
    t_ts, c_ts, v = time_it(lambda: ts.open(spec, context=ctx, read=True).result().read().result(),
                      a.repeat)
    sum_ts = float(v.astype(np.float64).sum())
    del v
    r = subprocess.run([a.bench, path, "--threads", str(a.threads), "--repeat", str(a.repeat)],
                       capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"zarr_read_pairs: {a.bench} failed: {r.stderr.strip()}")
    vals = {}
    for line in r.stdout.splitlines():
        f = dict(kv.split("=", 1) for kv in line.split())
        vals[f["op"]] = float(f["value"])
    t_vv, c_vv, sum_vv = vals["zarr_read"], vals["zarr_read_cpu"], vals["zarr_read_sum"]
    if not (sum_vv == sum_zarr == sum_ts):
        sys.exit(f"zarr_read_pairs: the readers disagree: volvis {sum_vv}, zarr-python "
                 f"{sum_zarr}, tensorstore {sum_ts}")
    for who, t, c in (("zarr-python", t_zarr, c_zarr), ("tensorstore", t_ts, c_ts),
                      ("volvis", t_vv, c_vv)):
        print(f"anchor={who} op=zarr_read dataset={name} value={t:.4f} unit=s", flush=True)
        print(f"anchor={who} op=zarr_read_cpu dataset={name} value={c:.4f} unit=s", flush=True)
    print(f"# {name}, {a.threads} threads, median of {a.repeat}: wall: volvis {t_vv:.3f} s, "
          f"zarr-python {t_zarr:.3f} s ({t_zarr / t_vv:.2f}x), tensorstore {t_ts:.3f} s "
          f"({t_ts / t_vv:.2f}x); CPU: volvis {c_vv:.3f} s, zarr-python {c_zarr:.3f} s "
          f"({c_zarr / c_vv:.2f}x), tensorstore {c_ts:.3f} s ({c_ts / c_vv:.2f}x)")


if __name__ == "__main__":
    main()
