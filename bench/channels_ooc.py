#!/usr/bin/env python3
"""Issue 89's speed targets (docs/rendering.md, "Channels out of core"): a 3-channel
1024 x 1024 x 512 u16 OME-NGFF 0.5 pyramid (3 GiB at level 0; chunks of one channel x 64^3
in shards of 256^3, zstd; levels down to 64 voxels a side; written by zarr-python 3),
drawn by level of detail under --memory-limit 512M at 1000x800, in one run:

- the first progressive image (what the GUI, the browser view and a notebook show first):
  `volvis.World.open(STORE, memory_limit="512M", lod=True)` (every channel) and the first
  `volvis.render(w, progressive=True)`, in a process of its own (goal <= 1 s);
- the converged 3-channel frame against its three channels drawn one after another (what
  a user did before: `volvis render STORE --channel C --memory-limit 512M` three times),
  processes of their own, alternated, medians (goal <= 0.7x);
- the frame drawn again with its chunks in the cache (`--repeat 2 --stats`): the 3-channel
  second frame against one channel's second frame (goal <= 1.6x: one pass, not three);
- bytes read against the distinct chunks the frame needs: the store served by nginx on
  loopback, rendered by URL, nginx's access log (every response body) against the bytes
  of the distinct chunk ranges asked (goal <= 1.2x).

    .venv/bin/python bench/channels_ooc.py [--repeat 3] [--out build/bench-out/channels_ooc]
        [--build build/release] [--make-only]

The store is made once and kept in OUT/www (about 1 GB on disk). Prints anchor lines and
one summary line per target with its goal.
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

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "io"))
from http_common import access_bytes, start_nginx, stop_server  # noqa: E402

NX, NY, NZ, NC = 1024, 1024, 512, 3
SIZE = "1000x800"
LIMIT = "512M"

# The first progressive image, in a process of its own: STORE.
PROGRESSIVE = r"""
import json, sys, time
import volvis
store = sys.argv[1]
t0 = time.perf_counter()
w = volvis.World.open(store, memory_limit="512M", lod=True, size=(1000, 800))
t_open = time.perf_counter() - t0
img, info = volvis.render(w, progressive=True, return_lod=True)
t_first = time.perf_counter() - t0
print(json.dumps({"open": t_open, "first": t_first, "channels": w.opened["n_channels"],
                  "pending": info["pending"]}))
"""


def blobs(rng, n, rmin, rmax, near=None, spread=0.0):
    """N Gaussian spots (cells, nuclei): centres (z, y, x), sigmas and peaks; with NEAR
    (another channel's spots) each beside one of those, SPREAD voxels away."""
    if near is None:
        c = rng.random((n, 3)) * np.array([NZ, NY, NX])
    else:
        pick = rng.integers(0, len(near[0]), n)
        c = near[0][pick] + rng.normal(0, spread, (n, 3))
    sig = rng.uniform(rmin, rmax, n) / 2.0
    peak = rng.uniform(900, 3200, n)
    return c, sig, peak


def paint(slab, z0, spots):
    """The spots' Gaussians into SLAB (float32 z, y, x; its slice 0 is slice z0), each the
    maximum with what is there."""
    c, sig, peak = spots
    nz = slab.shape[0]
    for (cz, cy, cx), s, p in zip(c, sig, peak):
        r = 3.0 * s
        if cz + r < z0 or cz - r >= z0 + nz:
            continue
        zs = np.arange(max(int(cz - r), z0), min(int(cz + r) + 1, z0 + nz))
        ys = np.arange(max(int(cy - r), 0), min(int(cy + r) + 1, NY))
        xs = np.arange(max(int(cx - r), 0), min(int(cx + r) + 1, NX))
        if not len(zs) or not len(ys) or not len(xs):
            continue
        g = (p * np.exp(-(zs - cz) ** 2 / (2 * s * s)).astype(np.float32)[:, None, None] *
             np.exp(-(ys - cy) ** 2 / (2 * s * s)).astype(np.float32)[None, :, None] *
             np.exp(-(xs - cx) ** 2 / (2 * s * s)).astype(np.float32)[None, None, :])
        sub = slab[zs[0] - z0:zs[-1] - z0 + 1, ys[0]:ys[-1] + 1, xs[0]:xs[-1] + 1]
        np.maximum(sub, g, out=sub)


def make(www):
    """The store (kept when OUT/www/c3.ome.zarr/.made exists), a fluorescence stack of
    three channels: nuclei (14000 spots 10 to 16 voxels across), a marker beside them
    (14000 spots 5 to 9 across, 12 voxels from a nucleus) and a protein elsewhere (6000
    spots 6 to 12 across, at places of their own), on a dim noisy background (100 + 0..23),
    written a slab of 64 slices at a time; levels of 2x2x2 means (zarr-python 3)."""
    import zarr
    from zarr.codecs import ZstdCodec
    store = os.path.join(www, "c3.ome.zarr")
    if os.path.exists(os.path.join(store, ".made")):
        return store
    shutil.rmtree(store, ignore_errors=True)
    t0 = time.perf_counter()
    rng = np.random.default_rng(89)
    nuclei = blobs(rng, 14000, 10, 16)
    spots = [nuclei, blobs(rng, 14000, 5, 9, near=nuclei, spread=12.0), blobs(rng, 6000, 6, 12)]
    g = zarr.open_group(store, mode="w")
    levels, shape = [], (NC, NZ, NY, NX)
    while True:
        levels.append(shape)
        if max(shape[1:]) <= 64:
            break
        shape = (NC,) + tuple(max(1, s // 2) for s in shape[1:])
    arrays = [g.create_array(str(k), shape=s, dtype=np.uint16, chunks=(1, 64, 64, 64),
                             shards=(1, 256, 256, 256), compressors=ZstdCodec(level=1))
              for k, s in enumerate(levels)]
    slab = 64
    for z0 in range(0, NZ, slab):
        block = np.empty((NC, slab, NY, NX), np.uint16)
        for c in range(NC):
            f = np.zeros((slab, NY, NX), np.float32)
            paint(f, z0, spots[c])
            f += 100 + rng.integers(0, 24, size=f.shape).astype(np.float32)
            block[c] = np.minimum(f, 65535).astype(np.uint16)
        arrays[0][:, z0:z0 + slab] = block
        lv = block
        for k in range(1, len(levels)):
            s = [d // 2 * 2 for d in lv.shape[1:]]
            lv = np.rint(lv[:, :s[0], :s[1], :s[2]].astype(np.float32).reshape(
                NC, s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(2, 4, 6))).astype(
                np.uint16)
            z = z0 >> k
            arrays[k][:, z:z + lv.shape[1]] = lv
        print("# made slices %d..%d" % (z0, z0 + slab - 1), flush=True)
    ds = [{"path": str(k), "coordinateTransformations": [
        {"type": "scale", "scale": [1.0] + [0.5 * 2 ** k] * 3},
        {"type": "translation", "translation": [0.0] + [0.5 * (2 ** k - 1) / 2] * 3}]}
        for k in range(len(levels))]
    colors = ["FF00FF", "00FF00", "00FFFF"]
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": "c", "type": "channel"}] + [
        {"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"], "datasets": ds}],
        "omero": {"channels": [{"label": name, "color": colors[c], "active": True,
                                "window": {"min": 0, "max": 3600, "start": 400, "end": 2800}}
                               for c, name in enumerate(("nuclei", "marker", "protein"))]}}
    size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(store) for f in fs)
    print("# made %s in %.0f s, %.2f GB on disk" % (store, time.perf_counter() - t0, size / 1e9),
          flush=True)
    open(os.path.join(store, ".made"), "w").write("made\n")
    return store


def render(volvis, store, *args):
    """One `volvis render` process: (wall seconds, its stdout)."""
    t0 = time.perf_counter()
    p = subprocess.run([volvis, "render", store, "--size", SIZE, "--memory-limit", LIMIT, *args],
                       capture_output=True, text=True)
    t = time.perf_counter() - t0
    if p.returncode != 0:
        sys.exit("channels_ooc: render %s failed: %s" % (" ".join(args), p.stderr.strip()))
    return t, p.stdout


def frame_ms(text):
    """The ms= of each --stats line."""
    return [float(x) for x in re.findall(r"\bms=([0-9.]+)", text)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="build/bench-out/channels_ooc")
    ap.add_argument("--build", default="build/release")
    ap.add_argument("--make-only", action="store_true")
    a = ap.parse_args()
    out, build = os.path.abspath(a.out), os.path.abspath(a.build)
    www = os.path.join(out, "www")
    os.makedirs(www, exist_ok=True)
    store = make(www)
    if a.make_only:
        return
    volvis = os.path.join(build, "volvis")
    png = os.path.join(out, "frame.png")
    print("# %s load: %s; %s, %s, --memory-limit %s" % (
        time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        " ".join(open("/proc/loadavg").read().split()[:3]), store, SIZE, LIMIT), flush=True)
    # ---- the first progressive image
    env = dict(os.environ, PYTHONPATH=os.path.join(build, "python"))
    firsts, opens = [], []
    for _ in range(a.repeat):
        r = subprocess.run([sys.executable, "-c", PROGRESSIVE, store], env=env,
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("channels_ooc: the progressive render failed: " + r.stderr.strip())
        res = json.loads(r.stdout.splitlines()[-1])
        if res["channels"] != NC:
            sys.exit("channels_ooc: World.open saw %s channels" % res["channels"])
        firsts.append(res["first"])
        opens.append(res["open"])
    # ---- the converged frame: 3 channels at once against 3 one at a time, alternated
    render(volvis, store, "-o", png, "-q")  # warm: the files in the page cache
    all3, one_by_one, second3, second1 = [], [], [], []
    for _ in range(a.repeat):
        t, text = render(volvis, store, "-o", png, "-q", "--repeat", "2", "--stats")
        ms = frame_ms(text)
        all3.append(ms[0] / 1e3)
        second3.append(ms[1])
        tt = 0.0
        for c in range(NC):
            t, text = render(volvis, store, "-o", os.path.join(out, "c%d.png" % c), "-q",
                             "--channel", str(c), "--repeat", "2", "--stats")
            ms = frame_ms(text)
            tt += ms[0] / 1e3
            if c == 0:
                second1.append(ms[1])
        one_by_one.append(tt)
    t3, t1x3 = statistics.median(all3), statistics.median(one_by_one)
    s3, s1 = statistics.median(second3), statistics.median(second1)
    _, text = render(volvis, store, "-o", png)
    line = text.strip().splitlines()[-1] if text.strip() else ""
    # ---- bytes: the store by URL from nginx on loopback
    log = os.path.join(out, "access.log")
    nginx, port, _ = start_nginx(out, www, "channels_ooc", access_log=log)
    try:
        open(log, "w").close()
        url = "http://127.0.0.1:%d/c3.ome.zarr" % port
        renv = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
        p = subprocess.run([volvis, "render", url, "-o", os.path.join(out, "url.png"), "-q",
                            "--size", SIZE, "--memory-limit", LIMIT], env=renv,
                           capture_output=True, text=True)
        if p.returncode != 0:
            sys.exit("channels_ooc: the render by URL failed: " + p.stderr.strip())
        time.sleep(0.5)  # nginx's log written
        fetched, needed = access_bytes(log)
    finally:
        stop_server(nginx)
    ds = "c3_1024x1024x512_u16"
    print("anchor=volvis op=channels_ooc_first_image dataset=%s value=%.3f unit=s"
          % (ds, statistics.median(firsts)))
    print("anchor=volvis op=channels_ooc_frame dataset=%s value=%.3f unit=s" % (ds, t3))
    print("anchor=volvis op=channels_ooc_one_by_one dataset=%s value=%.3f unit=s" % (ds, t1x3))
    print("anchor=volvis op=channels_ooc_second_frame dataset=%s value=%.1f unit=ms" % (ds, s3))
    print("anchor=volvis op=channels_ooc_one_second_frame dataset=%s value=%.1f unit=ms"
          % (ds, s1))
    print("# %s" % line)
    print("# first progressive image %.2f s (open %.2f s; goal <= 1 s); converged 3-channel "
          "frame %.2f s against its channels one after another %.2f s: %.2fx (goal <= 0.7x); "
          "drawn again %.0f ms against one channel's %.0f ms: %.2fx (goal <= 1.6x); by URL "
          "fetched %.1f MB for %.1f MB of distinct chunk ranges: %.3fx (goal <= 1.2x)"
          % (statistics.median(firsts), statistics.median(opens), t3, t1x3, t3 / t1x3, s3, s1,
             s3 / s1, fetched / 1e6, needed / 1e6, fetched / needed if needed else float("nan")),
          flush=True)


if __name__ == "__main__":
    main()
