#!/usr/bin/python3
"""OME-Zarr and Zarr v2 stores written by zarr-python, read by VolVis.

  zarr_read_cli.py VOLVIS OUTDIR

Writes with zarr-python and numcodecs (independent writers):

- OME-Zarr 0.4 stores with axes t, c, z, y, x (and c, z, y, x; t, z, y, x),
  one per chunk codec: Blosc (lz4 with byte shuffle, zstd with bit
  shuffle), zstd, zlib, gzip and none; "/" and "." separators; u1, >i2
  (big-endian), <u2, <f4 and <f8; chunks that do not divide the shape;
  scale and translation; omero channel labels and colours; a chunk left
  out (the fill value);
- a plain 3-D Zarr array (no OME metadata);

then checks:

- `volvis convert STORE OUT.nii --channel C --time T` read back with
  nibabel equals numpy's array at (T, C), voxel for voxel, with the spacing
  and origin of the level-0 transforms;
- `volvis info` names the channel and time counts, the labels and colours
  and the time between steps;
- a store VolVis wrote (`volvis convert X.nrrd Y.ome.zarr`) reads back as
  the voxels it was written from;
- bad input: a channel or a step out of range, a truncated chunk, a chunk
  of the wrong size, an unknown compressor, F order, a malformed .zarray:
  each one line naming the store and the problem, a non-zero exit and no
  output file.
"""
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import nibabel as nib
    import numcodecs
    import zarr
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-numpy, python3-nibabel, python3-zarr, python3-numcodecs)")
    sys.exit(77)

VOLVIS, OUT = sys.argv[1], sys.argv[2]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def volvis(*args):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True)


def read_back(store, c, t):
    """volvis convert --channel c --time t to NIfTI: (z, y, x) voxels and the affine."""
    nii = os.path.join(OUT, "back.nii")
    if os.path.exists(nii):
        os.remove(nii)
    p = volvis("convert", store, nii, "--channel", str(c), "--time", str(t), "--quiet")
    if p.returncode != 0:
        check(False, f"convert {os.path.basename(store)} --channel {c} --time {t}: "
              f"{p.stderr.strip()}")
        return None, None
    img = nib.load(nii)
    return np.asarray(img.dataobj).transpose(2, 1, 0), img.affine


def refused(args, needle, out_file, what):
    if os.path.exists(out_file):
        os.remove(out_file)
    p = volvis(*args)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode != 0 and len(lines) == 1 and needle in lines[0] and
          not os.path.exists(out_file), f"{what}: {lines[:2]} (exit {p.returncode})")


AXES = {"t": {"name": "t", "type": "time", "unit": "millisecond"},
        "c": {"name": "c", "type": "channel"},
        "z": {"name": "z", "type": "space", "unit": "micrometer"},
        "y": {"name": "y", "type": "space", "unit": "micrometer"},
        "x": {"name": "x", "type": "space", "unit": "micrometer"}}


def ome_store(name, arr, axes, chunks, compressor, sep, scale, trans, omero=None):
    path = os.path.join(OUT, name)
    g = zarr.open_group(path, mode="w")
    g.create_dataset("0", data=arr, chunks=chunks, compressor=compressor,
                     dimension_separator=sep)
    g.attrs["multiscales"] = [{
        "version": "0.4", "axes": [AXES[a] for a in axes],
        "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": scale}, {"type": "translation", "translation": trans}]}]}]
    if omero:
        g.attrs["omero"] = {"channels": omero}
    return path


rng = np.random.default_rng(29)
T, C, Z, Y, X = 3, 2, 9, 11, 13
cases = [
    ("blosc_lz4", numcodecs.Blosc("lz4", 5, numcodecs.Blosc.SHUFFLE), "/", "<u2"),
    ("blosc_zstd", numcodecs.Blosc("zstd", 3, numcodecs.Blosc.BITSHUFFLE), ".", ">i2"),
    ("zstd", numcodecs.Zstd(3), "/", "<f4"),
    ("zlib", numcodecs.Zlib(1), ".", "|u1"),
    ("gzip", numcodecs.GZip(5), "/", "<f8"),
    ("raw", None, ".", ">i2"),
]
for name, comp, sep, dt in cases:
    if dt[1] == "f":
        arr = rng.normal(0, 100, size=(T, C, Z, Y, X)).astype(dt)
    else:
        info = np.iinfo(np.dtype(dt))
        arr = rng.integers(info.min, info.max, size=(T, C, Z, Y, X), dtype=np.dtype(dt).newbyteorder("="))
        arr = arr.astype(dt)
    store = ome_store(name + ".ome.zarr", arr, "tczyx", (1, 1, 4, 5, 8), comp, sep,
                      [40.0, 1.0, 2.0, 0.5, 0.25], [0.0, 0.0, 10.0, -3.0, 7.5],
                      [{"label": "nuclei", "color": "FF00FF"}, {"label": "actin", "color": "00FF00"}])
    for c, t in ((0, 0), (1, 2), (0, 1)):
        got, aff = read_back(store, c, t)
        if got is None:
            continue
        check(np.array_equal(got, arr[t, c].astype(got.dtype)) and got.dtype == arr.dtype.newbyteorder("="),
              f"{name} ({dt}, '{sep}'): channel {c} step {t}: voxels ({got.dtype})")
    if got is not None:
        # NIfTI is RAS; the volume's axes are x, y, z with spacing (0.25, 0.5, 2)
        # and origin (7.5, -3, 10): VolVis writes its world as it is
        check(np.allclose(np.abs(np.diag(aff)[:3]), [0.25, 0.5, 2.0]) and
              np.allclose(np.abs(aff[:3, 3]), [7.5, 3.0, 10.0]),
              f"{name}: spacing and origin from the transforms ({np.diag(aff)[:3]}, {aff[:3, 3]})")

store = os.path.join(OUT, "blosc_lz4.ome.zarr")
p = volvis("info", store, "--channel", "1", "--time", "2")
lines = p.stdout.splitlines()
check(p.returncode == 0 and "channels:     2 (this is channel 1)" in lines and
      any(ln.startswith('  channel 0   "nuclei" #ff00ff range') for ln in lines) and
      any(ln.startswith('  channel 1   "actin" #00ff00 range') for ln in lines) and
      "time steps:   3 (this is step 2), 0.04 s apart" in lines,
      f"info: 2 named, coloured channels, 3 steps 40 ms apart ({p.stderr.strip()})")

# c, z, y, x and t, z, y, x; a chunk left out reads as the fill value
czyx = rng.integers(0, 1000, size=(3, Z, Y, X), dtype=np.uint16)
s2 = ome_store("czyx.ome.zarr", czyx, "czyx", (2, 4, 4, 4), numcodecs.Zlib(1), "/",
               [1, 1, 1, 1], [0, 0, 0, 0])
got, _ = read_back(s2, 2, 0)
check(got is not None and np.array_equal(got, czyx[2]), "c, z, y, x: channel 2 (chunks of 2 channels)")
tzyx = rng.integers(1, 1000, size=(4, Z, Y, X), dtype=np.int32)
s3 = ome_store("tzyx.ome.zarr", tzyx, "tzyx", (1, 4, 4, 4), None, "/", [1, 1, 1, 1], [0, 0, 0, 0])
z = zarr.open_array(os.path.join(s3, "0"), mode="r+")
z.fill_value  # noqa: B018 (the array's fill value is 0)
os.remove(os.path.join(s3, "0", "3", "0", "1", "2"))
got, _ = read_back(s3, 0, 3)
want = tzyx[3].copy()
want[0:4, 4:8, 8:12] = 0
check(got is not None and np.array_equal(got, want), "t, z, y, x: step 3, a missing chunk is the fill value 0")

# a plain 3-D Zarr array
plain = os.path.join(OUT, "plain.zarr")
zp = zarr.open_array(plain, mode="w", shape=(Z, Y, X), chunks=(5, 5, 5), dtype="<i2",
                     compressor=numcodecs.Zstd(1))
parr = rng.integers(-30000, 30000, size=(Z, Y, X), dtype=np.int16)
zp[:] = parr
got, _ = read_back(plain, 0, 0)
check(got is not None and np.array_equal(got, parr), "plain 3-D Zarr array: voxels")

# VolVis's own store reads back as its source
nrrd_src = os.path.join(OUT, "src.nii")
nib.save(nib.Nifti1Image(parr.transpose(2, 1, 0), np.diag([0.5, 0.5, 2, 1])), nrrd_src)
own = os.path.join(OUT, "own.ome.zarr")
p = volvis("convert", nrrd_src, own, "--quiet")
check(p.returncode == 0, f"convert to OME-Zarr: {p.stderr.strip()}")
got, aff = read_back(own, 0, 0)
check(got is not None and np.array_equal(got, parr) and np.allclose(np.diag(aff)[:3], [0.5, 0.5, 2]),
      "a store VolVis wrote reads back as its source")

# bad input: one line naming the store, no output file
bad_out = os.path.join(OUT, "bad.nii")
refused(["convert", store, bad_out, "--channel", "2", "-q"], "channel 2 asked", bad_out,
        "a channel out of range")
refused(["convert", store, bad_out, "--time", "3", "-q"], "time step 3 asked", bad_out,
        "a step out of range")


def broken(name, edit):
    path = os.path.join(OUT, name + ".ome.zarr")
    shutil.copytree(os.path.join(OUT, "zlib.ome.zarr"), path)
    edit(path)
    return path


def truncate(path):
    f = os.path.join(path, "0", "0.0.0.0.0")
    with open(f, "r+b") as fh:
        fh.truncate(os.path.getsize(f) // 2)


def set_zarray(key, value):
    def edit(path):
        import json
        za = os.path.join(path, "0", ".zarray")
        with open(za) as fh:
            j = json.load(fh)
        j[key] = value
        with open(za, "w") as fh:
            json.dump(j, fh)
    return edit


def garbage(path):
    with open(os.path.join(path, "0", ".zarray"), "w") as fh:
        fh.write('{"zarr_format": 2, "shape": [3, 2')


refused(["convert", broken("trunc", truncate), bad_out, "-q"], "does not decode", bad_out,
        "a truncated chunk")
refused(["convert", broken("shape", set_zarray("chunks", [1, 1, 4, 5, 9])), bad_out, "-q"],
        "does not decode", bad_out, "chunks of another size than stored")
refused(["convert", broken("lzma", set_zarray("compressor", {"id": "lzma"})), bad_out, "-q"],
        'compressor "lzma"', bad_out, "an unknown compressor")
refused(["convert", broken("forder", set_zarray("order", "F")), bad_out, "-q"],
        'order "F"', bad_out, "F order")
refused(["convert", broken("garbage", garbage), bad_out, "-q"], ".zarray", bad_out,
        "a malformed .zarray")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
