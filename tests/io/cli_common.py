"""Helpers shared by the CLI tests of tests/io that the pinned .venv runs
(zarr3_read_cli.py, zarr3_write_cli.py, zarr_labels_plate_cli.py): the checks and their
summary, running volvis, and reading back a NRRD VolVis wrote."""
import gzip
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
