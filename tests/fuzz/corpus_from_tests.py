#!/usr/bin/python3
"""The hostile files of the error-path tests as fuzz inputs.

  tests/fuzz/corpus_from_tests.py [TEST_OUT] [CORPUS]

The tests of every refusal of our own parsers (tests/io/test_errors_*.c,
tests/scene/test_errors.c, tests/manipulate/test_errors.c,
tests/input/test_errors.c) write their hand-made files under
build/release/test-out/ (TEST_OUT); this copies each into the working
corpus of the harness that reads it, build/fuzz/corpus/<format>/ (CORPUS),
in that harness's input format (a Zarr store packed into fuzz_zarr's
container, an HDF5 file described for fuzz_bdv, a PLOT3D pair joined by
--DATA--). A long run then mutates from every refusal the tests know;
libFuzzer's -merge=1 keeps those that add coverage. Needs the release
tests run first, and python3-h5py for the HDF5 files.
"""
import hashlib
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_corpus_structured as mcs  # noqa: E402  (pack_store, describe_h5)

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
MAX = 65536  # scripts/fuzz.sh's -max_len


def put(corpus, fmt, data):
    if not data or len(data) > MAX:
        return 0
    d = os.path.join(corpus, fmt)
    os.makedirs(d, exist_ok=True)
    name = "t-" + hashlib.sha1(data).hexdigest()[:16]
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)
    return 1


def read(p):
    with open(p, "rb") as f:
        return f.read()


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build/release/test-out")
    corpus = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "build/fuzz/corpus")
    n = {}

    def add(fmt, data):
        n[fmt] = n.get(fmt, 0) + put(corpus, fmt, data)

    by_ext = {
        "errors_volumes": {".slc": "slc", ".vtk": "vtk", ".mha": "mhd", ".mhd": "mhd"},
        "io_slc_bad": {".slc": "slc"},
        "errors_grids": {".vtk": "grid", ".dx": "grid"},
        "errors_vvc_vvb": {".vvb": "vvb", ".vvc": "vvc"},
        "scene_errors": {".json": "scene"},
        "animation_errors": {".json": "animation"},
        "input_errors": {".vvin": "replay", ".rec": "replay"},
    }
    for folder, exts in by_ext.items():
        base = os.path.join(out, folder)
        if not os.path.isdir(base):
            continue
        for f in sorted(os.listdir(base)):
            p = os.path.join(base, f)
            ext = os.path.splitext(f)[1].lower()
            if os.path.isfile(p) and not os.path.islink(p) and ext in exts:
                add(exts[ext], read(p))
            # PLOT3D: the grid file, --DATA--, the solution file
            if folder == "errors_grids" and ext == ".xyz" and os.path.isfile(p):
                q = os.path.splitext(p)[0] + ".q"
                add("grid", read(p) + b"\n--DATA--\n" + (read(q) if os.path.isfile(q) else b""))
    zdir = os.path.join(out, "errors_zarr")
    if os.path.isdir(zdir):
        for f in sorted(os.listdir(zdir)):
            p = os.path.join(zdir, f)
            if os.path.isdir(p) and not os.path.islink(p):
                # only stores of regular files: a FIFO would block the read
                special = any(not os.path.isfile(os.path.join(d, x)) or os.path.islink(os.path.join(d, x))
                              for d, _, xs in os.walk(p) for x in xs)
                size = sum(os.path.getsize(os.path.join(d, x)) for d, _, xs in os.walk(p) for x in xs
                           if os.path.isfile(os.path.join(d, x)))
                if special or size > MAX:
                    continue
                try:
                    add("zarr", mcs.pack_store(p, prelude="# a refusal of test_io_errors_zarr\n"))
                except OSError:
                    pass  # a FIFO or a link the test left: not a file to pack
    bdir = os.path.join(out, "errors_bdv_hdf5")
    if os.path.isdir(bdir):
        h5s = {}
        for f in sorted(os.listdir(bdir)):
            p = os.path.join(bdir, f)
            if f.endswith((".h5", ".ims")) and os.path.isfile(p) and not os.path.islink(p):
                try:
                    h5s[f] = mcs.describe_h5(p)
                except Exception:  # noqa: BLE001  (a file the test made unreadable on purpose)
                    continue
                add("bdv", ("--H5--\n" + h5s[f]).encode())
        for f in sorted(os.listdir(bdir)):
            p = os.path.join(bdir, f)
            if f.endswith(".xml") and os.path.isfile(p) and not os.path.islink(p):
                xml = read(p).decode("utf-8", "replace")
                h5 = next((h for h in h5s if h in xml), None)
                add("bdv", (xml + "\n--H5--\n" + (h5s[h5] if h5 else "")).encode())
    for fmt in sorted(n):
        print(f"{fmt}: {n[fmt]} inputs from the tests")
    return 0


if __name__ == "__main__":
    sys.exit(main())
