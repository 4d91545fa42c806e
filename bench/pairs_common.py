"""Helpers of the same-run Zarr read pairs, bench/zarr_read_pairs.py (a local store) and
bench/remote_read_pairs.py (the store by URL from nginx): the store both read, the timing
of a Python reader, and bench_zarr_read's run and anchor values."""
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import zarr
from zarr.codecs import BloscCodec, BytesCodec, GzipCodec, ZstdCodec


def make_store(path, size, chunk, shard, codec):
    """A SIZE^3 u16 Zarr v3 array at PATH written by zarr-python 3 (a smooth field plus
    noise, so that it compresses as scans do): CHUNK^3 chunks inside SHARD^3 shards (0:
    not sharded), CODEC zstd (level 3), blosc (lz4, shuffle), gzip (level 1) or none.
    Kept when PATH/.made says it was made with the same options."""
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
    """FN() once untimed (warm: the files in the page cache, the connections made, the
    reader's set-up done), then REPEAT times: (median wall seconds, median CPU seconds of
    this process, all threads, the last call's result)."""
    fn()
    times, cpus, out = [], [], None
    for _ in range(repeat):
        out = None
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return statistics.median(times), statistics.median(cpus), out


def run_bench(who, bench, target, threads, repeat, env=None):
    """bench_zarr_read (BENCH) reading TARGET (a path or a URL) whole at THREADS threads,
    REPEAT times: ({op: value} of its anchor lines, its stderr). Exits with one line
    "WHO: BENCH failed: ..." when it fails."""
    r = subprocess.run([bench, target, "--threads", str(threads), "--repeat", str(repeat)],
                       capture_output=True, text=True, env=env)
    if r.returncode != 0:
        sys.exit(f"{who}: {bench} failed: {r.stderr.strip()}")
    vals = {}
    for line in r.stdout.splitlines():
        f = dict(kv.split("=", 1) for kv in line.split())
        vals[f["op"]] = float(f["value"])
    return vals, r.stderr
