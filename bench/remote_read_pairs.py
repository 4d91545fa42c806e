#!/usr/bin/env python3
"""Same-run pairs over HTTP: one Zarr v3 level read whole by URL from nginx on
loopback, by VolVis (bench_zarr_read given the URL) and by zarr-python 3 through
fsspec/aiohttp (`zarr.open_array(URL)[...]`), median of REPEAT reads each (default 3).

Run with the virtual environment's Python (scripts/install-deps.sh bench):

    .venv/bin/python bench/remote_read_pairs.py build/release/bench/bench_zarr_read \\
        [--size 256] [--chunk 32] [--shard 128] [--threads 2] [--repeat 3] \\
        [--out build/bench-out/remote_read]

Writes a SIZE^3 u16 store (a smooth field plus noise, zstd 3, CHUNK^3 chunks in
SHARD^3 shards; --shard 0: not sharded) with zarr-python 3 as bench/zarr_read_pairs.py
does, and serves its folder with Debian's nginx (one worker, a configuration of its own,
a free loopback port, no added latency). Each reader reads once untimed (connections
made, the files in the page cache), then REPEAT times. VolVis runs with
VOLVIS_HTTP_STATS=1 and reports how many requests it made and the most it had in
flight at once. zarr-python runs with its defaults for a remote store (fsspec's
HTTPFileSystem over aiohttp, zarr's async.concurrency 10) and threading.max_workers
THREADS. The voxel sums must agree, or the run fails. Prints
anchor lines and the ratio zarr-python / VolVis (above 1: VolVis is faster).
"""
import argparse
import os
import re
import sys

import numpy as np
import zarr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "io"))
from http_common import start_nginx, stop_server  # noqa: E402
from pairs_common import make_store, run_bench, time_it  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("bench")
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--chunk", type=int, default=32)
    ap.add_argument("--shard", type=int, default=128)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="build/bench-out/remote_read")
    a = ap.parse_args()
    out = os.path.abspath(a.out)
    www = os.path.join(out, "www")
    os.makedirs(www, exist_ok=True)
    name = f"u16_{a.size}_zstd_c{a.chunk}_s{a.shard}.zarr"
    make_store(os.path.join(www, name), a.size, a.chunk, a.shard, "zstd")
    nginx, port, _ = start_nginx(out, www, "remote_read_pairs")
    url = f"http://127.0.0.1:{port}/{name}"
    env = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
    env["VOLVIS_HTTP_STATS"] = "1"
    for k in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY"):
        os.environ.pop(k, None)
    try:
        zarr.config.set({"threading.max_workers": a.threads})
        t_zarr, _, v = time_it(lambda: zarr.open_array(url, mode="r")[...], a.repeat)
        sum_zarr = float(v.astype(np.float64).sum())
        del v
        vals, err = run_bench("remote_read_pairs", a.bench, url, a.threads, a.repeat, env=env)
    finally:
        stop_server(nginx)
    t_vv, sum_vv = vals["zarr_read"], vals["zarr_read_sum"]
    m = re.search(r"(\d+) requests, at most (\d+) in flight", err)
    if sum_vv != sum_zarr:
        sys.exit(f"remote_read_pairs: the readers disagree: volvis {sum_vv}, zarr-python "
                 f"{sum_zarr}")
    for who, t in (("zarr-python", t_zarr), ("volvis", t_vv)):
        print(f"anchor={who} op=remote_read dataset={name} value={t:.4f} unit=s", flush=True)
    print(f"# {name} by URL (nginx, loopback), {a.threads} threads, median of {a.repeat}: "
          f"volvis {t_vv:.3f} s, zarr-python + fsspec {t_zarr:.3f} s "
          f"({t_zarr / t_vv:.2f}x); volvis: "
          f"{m.group(1) if m else '?'} requests in all, at most "
          f"{m.group(2) if m else '?'} in flight")


if __name__ == "__main__":
    main()
