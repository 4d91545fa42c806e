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
import sys

import numpy as np
import tensorstore as ts
import zarr

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pairs_common import make_store, run_bench, time_it  # noqa: E402


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
    vals, _ = run_bench("zarr_read_pairs", a.bench, path, a.threads, a.repeat)
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
