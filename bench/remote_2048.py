#!/usr/bin/env python3
"""Issue 79's speed targets (docs/formats.md, "Remote data"): a SIDE^3 u16
zstd-sharded OME-NGFF 0.5 pyramid (64^3 chunks in 256^3 shards, `volvis
convert`) served by Debian's nginx behind bench/throttle_proxy.py (LATENCY
added to each request and to each new connection, MBIT shared by every
connection), measured through the proxy in one run:

- open, the first image and the converged frame, as the GUI, the browser
  view and a notebook see them (a process of its own, the build tree's
  Python package, a 4 GiB cache): `volvis.Pyramid(URL)` and its World at
  1000x800 (the metadata and the coarsest level: "open"), the first
  progressive frame (drawn from what is resident: "first image"), then
  `Pyramid.wait` and a progressive frame again until no node is pending
  (the loader fetching the frame's chunks in the background, coarse levels
  first, then front to back: "converged"), requests and the most in flight
  (VOLVIS_HTTP_STATS=1);
- bytes fetched against the chunks the frame needs: nginx's access log of
  that run (every response body's bytes) against the bytes of the
  distinct chunk ranges asked (metadata, shard indexes and anything asked
  twice are the overhead);
- reading the 256^3 level whole by URL: bench_zarr_read against
  zarr-python 3 with fsspec/aiohttp (`zarr.open_array(URL)[...]`, 2
  worker threads), median of REPEAT each, the voxel sums equal.

    .venv/bin/python bench/remote_2048.py [--side 2048] [--noise] [--repeat 3]
        [--out build/bench-out/remote_2048] [--build build/release]
        [--latency 0.05] [--mbit 100]

The store is made once (bench_ooc --generate: the phantom of ooc_2048.sh in
u16, or with --noise a scanner's noise inside it so that it compresses
about 3-fold, not 30-fold; a raw file of SIDE^3 x 2 bytes on the way,
deleted) and kept in OUT/www for the next run. Prints anchor lines and one
summary line per target with its goal.
"""
import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np
import zarr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "tests", "io"))
from http_common import access_bytes, start_nginx, stop_server  # noqa: E402
from pairs_common import run_bench, time_it  # noqa: E402


# The progressive session, in a process of its own: URL, PNG.
PROGRESSIVE = r"""
import json, sys, time
import volvis
url, png = sys.argv[1], sys.argv[2]
t0 = time.perf_counter()
volvis.memory_limit("4G")
pyr = volvis.Pyramid(url)
w = pyr.world(size=(1000, 800))
t_open = time.perf_counter() - t0
img, info = volvis.render(w, progressive=True, return_lod=True)
t_first = time.perf_counter() - t0
frames = 1
while info["pending"] and not info["stalled"]:
    pyr.wait(1.0)
    img, info = volvis.render(w, progressive=True, return_lod=True)
    frames += 1
stalled = info["pending"] > 0
if stalled:
    img = volvis.render(w)
t_conv = time.perf_counter() - t0
volvis.save_png(img, png)
print(json.dumps({"open": t_open, "first": t_first, "conv": t_conv, "frames": frames,
                  "nodes": info["nodes"], "stalled": stalled}))
"""


def make(a, www, build):
    name = "p%d%s.ome.zarr" % (a.side, "n" if a.noise else "")
    store = os.path.join(www, name)
    if os.path.exists(os.path.join(store, ".made")):
        return name
    shutil.rmtree(store, ignore_errors=True)
    raw = os.path.join(www, "gen.raw")
    t0 = time.perf_counter()
    subprocess.run([os.path.join(build, "bench", "bench_ooc"), "--generate", str(a.side), raw,
                    "u16noise" if a.noise else "u16"], check=True)
    t1 = time.perf_counter()
    subprocess.run([os.path.join(build, "volvis"), "convert", "-q", "--raw",
                    "%dx%dx%d:u16" % ((a.side,) * 3), raw, store, "--chunk", "64", "--shard",
                    "256", "--compress", "zstd"], check=True)
    os.remove(raw)
    size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(store) for f in fs)
    print("# made %s: generated in %.0f s, converted in %.0f s, %.2f GB on disk"
          % (name, t1 - t0, time.perf_counter() - t1, size / 1e9), flush=True)
    open(os.path.join(store, ".made"), "w").write("made\n")
    return name


def start_proxy(upstream, a):
    p = subprocess.Popen([sys.executable, os.path.join(HERE, "throttle_proxy.py"), str(upstream),
                          "--latency", str(a.latency), "--mbit", str(a.mbit)],
                         stdout=subprocess.PIPE, text=True)
    line = p.stdout.readline().split()
    if len(line) != 2 or line[0] != "listening":
        p.kill()
        sys.exit("remote_2048: the proxy did not start")
    return p, int(line[1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--side", type=int, default=2048)
    ap.add_argument("--noise", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="build/bench-out/remote_2048")
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--latency", type=float, default=0.05)
    ap.add_argument("--mbit", type=float, default=100.0)
    ap.add_argument("--make-only", action="store_true", help="make the store and stop")
    a = ap.parse_args()
    out, build = os.path.abspath(a.out), os.path.abspath(a.build)
    www = os.path.join(out, "www")
    os.makedirs(www, exist_ok=True)
    name = make(a, www, build)
    if a.make_only:
        return
    volvis = os.path.join(build, "volvis")
    log = os.path.join(out, "access.log")
    nginx, port, _ = start_nginx(out, www, "remote_2048", access_log=log)
    proxy, pport = start_proxy(port, a)
    url = "http://127.0.0.1:%d/%s" % (pport, name)
    env = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
    env["VOLVIS_HTTP_STATS"] = "1"
    for k in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY"):
        os.environ.pop(k, None)
    link = "%g ms a request, %g Mbit/s" % (a.latency * 1e3, a.mbit)
    print("# %s load: %s; %s through a proxy of %s" % (
        time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        " ".join(open("/proc/loadavg").read().split()[:3]), url, link), flush=True)
    try:
        # ---- open, the first image, the converged frame
        open(log, "w").close()
        penv = dict(env)
        penv["PYTHONPATH"] = os.path.join(build, "python")
        r = subprocess.run([sys.executable, "-c", PROGRESSIVE, url, os.path.join(out, "frame.png")],
                           env=penv, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("remote_2048: the progressive render failed: " + r.stderr.strip())
        res = json.loads(r.stdout.splitlines()[-1])
        t_open, t_first, t_conv = res["open"], res["first"], res["conv"]
        m = re.search(r"(\d+) requests, at most (\d+) in flight", r.stderr)
        reqs, most = (int(m.group(1)), int(m.group(2))) if m else (-1, -1)
        time.sleep(0.5)  # nginx's log written
        fetched, needed = access_bytes(log)
        # ---- the 256^3 level read whole
        level = 0
        while a.side >> level > 256:
            level += 1
        lurl = "%s/%d" % (url, level)
        zarr.config.set({"threading.max_workers": 2})
        t_zarr, _, v = time_it(lambda: zarr.open_array(lurl, mode="r")[...], a.repeat)
        sum_zarr = float(v.astype(np.float64).sum())
        del v
        vals, _ = run_bench("remote_2048", os.path.join(build, "bench", "bench_zarr_read"), lurl,
                            2, a.repeat, env=env)
        t_vv, sum_vv = vals["zarr_read"], vals["zarr_read_sum"]
        if sum_vv != sum_zarr:
            sys.exit("remote_2048: the readers disagree: volvis %s, zarr-python %s"
                     % (sum_vv, sum_zarr))
    finally:
        proxy.terminate()
        proxy.wait()
        stop_server(nginx)
    ds = name.replace(".ome.zarr", "")
    ratio = fetched / needed if needed else float("nan")
    for op, val in (("open", t_open), ("first_image", t_first), ("converged", t_conv)):
        print("anchor=volvis op=remote_%s dataset=%s value=%.3f unit=s" % (op, ds, val))
    for who, t in (("zarr-python", t_zarr), ("volvis", t_vv)):
        print("anchor=%s op=remote_level_read dataset=%s_L%d value=%.4f unit=s"
              % (who, ds, level, t))
    print("# open %.2f s (goal <= 1 s); first image %.2f s (goal <= 2 s); converged "
          "%.2f s (goal <= 15 s), %d progressive frames, nodes per level %s%s; %d requests, "
          "at most %d in flight (goal >= 16); fetched %.1f MB for %.1f MB of distinct chunk "
          "ranges: %.3fx (goal <= 1.2x); level %d (%d^3) by URL: volvis %.3f s, zarr-python "
          "+ fsspec %.3f s: %.2fx (goal >= 2x)"
          % (t_open, t_first, t_conv, res["frames"], res["nodes"],
             " (stalled: the cache was full, the rest streamed)" if res["stalled"] else "",
             reqs, most, fetched / 1e6, needed / 1e6, ratio, level, a.side >> level, t_vv,
             t_zarr, t_zarr / t_vv), flush=True)


if __name__ == "__main__":
    main()
