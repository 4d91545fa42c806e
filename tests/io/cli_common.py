"""Helpers shared by the CLI tests of tests/io that the pinned .venv runs
(zarr3_read_cli.py, zarr3_write_cli.py, zarr_labels_plate_cli.py, the remote-store
tests): the checks and their summary, running volvis, reading back a NRRD VolVis wrote,
and the sharded pyramid zarr-python 3 writes."""
import gzip
import os
import subprocess
import sys

import numpy as np

NRRD_TYPES = {"unsigned char": "u1", "signed char": "i1", "unsigned short": "u2", "short": "i2",
              "unsigned int": "u4", "int": "i4", "float": "f4", "double": "f8"}


class Checks:
    """Named checks: each prints ok or FAIL; finish() exits 1 naming the failures."""

    def __init__(self):
        self.failures = []

    def __call__(self, cond, what):
        print(("ok   " if cond else "FAIL ") + what)
        if not cond:
            self.failures.append(what)

    def finish(self, name):
        if self.failures:
            print(f"{name}: {len(self.failures)} check(s) failed: {self.failures}")
            sys.exit(1)
        print(f"{name}: every check passed")


def run(volvis, *args):
    """volvis ARGS..., its output captured as text."""
    return subprocess.run([volvis, *args], capture_output=True, text=True)


def render_png(volvis, out_dir, check, name, src, *args):
    """volvis render SRC -o OUT_DIR/NAME.png ARGS...: the image's path, or None after a
    failed check naming the exit status and stderr."""
    out = os.path.join(out_dir, name + ".png")
    p = run(volvis, "render", src, "-o", out, *args)
    ok = p.returncode == 0 and os.path.exists(out)
    if not ok:
        check(False, f"render {name}: exit {p.returncode}: {p.stderr.strip()}")
    return out if ok else None


def read_nrrd(path):
    """(voxels z, y, x; spacing x, y, z; origin x, y, z) of a NRRD VolVis wrote."""
    with open(path, "rb") as f:
        raw = f.read()
    head, _, body = raw.partition(b"\n\n")
    h = {}
    for ln in head.decode().splitlines()[1:]:
        if ln.startswith("#") or ": " not in ln:
            continue
        k, v = ln.split(": ", 1)
        h[k] = v
    sizes = [int(x) for x in h["sizes"].split()]
    dt = np.dtype(("<" if h.get("endian", "little") == "little" else ">") + NRRD_TYPES[h["type"]])
    if h["encoding"] == "gzip":
        body = gzip.decompress(body)
    arr = np.frombuffer(body, dtype=dt, count=int(np.prod(sizes))).reshape(sizes[::-1])
    dirs = [[float(c) for c in d.strip("()").split(",")] for d in
            h.get("space directions", " ".join(["(1,0,0)", "(0,1,0)", "(0,0,1)"])).split()]
    spacing = [float(np.linalg.norm(d)) for d in dirs]
    origin = [float(c) for c in h.get("space origin", "(0,0,0)").strip("()").split(",")]
    return arr, spacing, origin


def write_stores(out, n=96, rng=None, names=("pyr3.ome.zarr", "pyr2.ome.zarr")):
    """The stores under OUT that zarr-python 3 writes: names[0] (NGFF 0.5, Zarr v3, 3
    levels of a ball of N^3 u16 plus noise from RNG (default: seed 7), shards of 32^3
    holding inner chunks of 16^3, zstd) and names[1] (the same levels as Zarr v2, OME-Zarr
    0.4, chunks of 16^3). Returns (v3 path, v2 path)."""
    import os

    import zarr
    from zarr.codecs import ZstdCodec
    rng = np.random.default_rng(7) if rng is None else rng
    zz, yy, xx = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    ball = (1000 * np.exp(-((zz - 40) ** 2 + (yy - 50) ** 2 + (xx - 45) ** 2) / 600))
    ball = ball.astype(np.uint16) + rng.integers(0, 50, size=ball.shape, dtype=np.uint16)
    v3 = os.path.join(out, names[0])
    g = zarr.open_group(v3, mode="w")
    lv, ds = ball, []
    for k in range(3):
        a = g.create_array(str(k), shape=lv.shape, dtype=lv.dtype, chunks=(16, 16, 16),
                           shards=(32, 32, 32), compressors=ZstdCodec(level=3))
        a[:] = lv
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [2.0 ** k] * 3},
            {"type": "translation", "translation": [(2.0 ** k - 1) / 2] * 3}]})
        s = [d // 2 * 2 for d in lv.shape]
        lv = np.rint(lv[:s[0], :s[1], :s[2]].astype(np.float64).reshape(
            s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(1, 3, 5))).astype(np.uint16)
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"], "datasets": ds}]}
    v2 = os.path.join(out, names[1])
    g2 = zarr.open_group(v2, mode="w", zarr_format=2)
    for k in range(3):
        a = g[str(k)][:]
        g2.create_array(str(k), shape=a.shape, dtype=a.dtype, chunks=(16, 16, 16))[:] = a
    g2.attrs["multiscales"] = [{"version": "0.4", **g.attrs["ome"]["multiscales"][0]}]
    return v3, v2
