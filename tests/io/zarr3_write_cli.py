#!/usr/bin/env python3
"""`volvis convert IN OUT.ome.zarr --ngff 0.5`: OME-NGFF 0.5 (Zarr v3) stores
judged by the reference implementations (the .venv's zarr-python 3,
tensorstore, ome-zarr-py and ome-zarr-models; vv_pypi_test).

  zarr3_write_cli.py VOLVIS OUTDIR

Checks:

- synthetic u16, float32 and int8 volumes (NRRD written here, sizes not a
  multiple of the chunk: edge chunks, and edge shards with inner chunks past
  the array) and the CT head of ../shared/data, with each codec (zstd, blosc,
  gzip, none), sharded (sharding_indexed, index at the end, crc32c) and not:
  zarr-python 3 (zarr.open_group) reads level 0 equal to the input voxel for
  voxel and every further level equal to numpy's 2x2x2 means of the level
  before (integers rounded half up); tensorstore (driver zarr3) reads every
  level equal to zarr-python's; ome-zarr-py's reader finds the image, its
  levels and axes; each level's scale and translation are the spacing and
  origin as the levels' factors make them; ome-zarr-models validates the
  group against the NGFF 0.5 schema; the metadata says what was asked
  (codec, chunk and shard shapes, dimension names); every shard's index ends
  with its CRC-32C (the crc32c package), names its inner chunks inside the
  file without overlap, and marks those past the array empty (all ones);
- a label volume: levels by the first voxel of each block, image-label;
- the out-of-core path: a raw u16 volume converted sharded under a memory
  budget of a quarter of it (VOLVIS_MAX_MEMORY) with a peak resident set
  under half of it, read back equal by tensorstore; and the box-by-box writer
  (an uncompressed NRRD) makes the same store, byte for byte, as the
  whole-volume writer (the same voxels as NIfTI);
- --ngff 0.4 still writes Zarr v2 (zarr_format 2, .zarray), read equal by
  zarr-python 3;
- an existing v2 store is replaced by a v3 one and back (no metadata of the
  old one left); a folder that is not a Zarr store is refused and left;
- bad options (--chunk 0, a shard not a multiple of the chunk, an unknown
  codec, --ngff 0.3, --shard with --ngff 0.4, zlib at 0.5, the options with
  another format): one line, exit 2, nothing written.
"""
import json
import os
import shutil
import struct
import subprocess
import sys
import time

try:
    import crc32c
    import numpy as np
    import tensorstore as ts
    import zarr
    from ome_zarr.io import parse_url
    from ome_zarr.reader import Reader
    import ome_zarr_models
    from ome_zarr_models import open_ome_zarr
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (the .venv of scripts/install-deps.sh test)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
HEAD = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
failures = check.failures


def volvis(*args, env=None):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True, env=env)


def write_nrrd(path, arr, ntype, spacing, origin):
    """An uncompressed NRRD of arr [k, j, i] with spacing and origin (x, y, z)."""
    cols = " ".join("(%s)" % ",".join(repr(float(x)) for x in np.eye(3)[:, c] * spacing[c])
                    for c in range(3))
    with open(path, "wb") as f:
        f.write(("NRRD0004\ntype: %s\ndimension: 3\nspace: left-posterior-superior\n"
                 "sizes: %d %d %d\nspace directions: %s\nspace origin: (%s)\n"
                 'space units: "mm" "mm" "mm"\nendian: little\nencoding: raw\n\n' %
                 (ntype, arr.shape[2], arr.shape[1], arr.shape[0], cols,
                  ",".join(repr(float(x)) for x in origin))).encode())
        f.write(arr.astype(arr.dtype.newbyteorder("<")).tobytes())


def mean_down(x, dtype):
    """2x2x2 means of x [k, j, i] over the voxels inside (integers rounded
    half up, as the writer's doubles round), in dtype."""
    shape = [(n + 1) // 2 * 2 if n > 1 else 1 for n in x.shape]
    pad = np.zeros(shape)
    cnt = np.zeros(shape)
    pad[:x.shape[0], :x.shape[1], :x.shape[2]] = x
    cnt[:x.shape[0], :x.shape[1], :x.shape[2]] = 1
    f = [2 if n > 1 else 1 for n in x.shape]
    r = lambda a: a.reshape(shape[0] // f[0], f[0], shape[1] // f[1], f[1],  # noqa: E731
                            shape[2] // f[2], f[2]).sum(axis=(1, 3, 5))
    m = r(pad) / r(cnt)
    if np.dtype(dtype).kind in "ui":
        m = np.floor(m + 0.5)
    return m.astype(dtype)


def levels_close(got, want, dtype):
    """Integers equal; floats within the rounding of a float32 mean."""
    if got.shape != want.shape:
        return False
    if np.dtype(dtype).kind in "ui":
        return np.array_equal(got, want)
    return np.allclose(got, want, rtol=1e-6, atol=1e-6)


def shard_files(level_dir):
    for d, _, names in os.walk(os.path.join(level_dir, "c")):
        for n in names:
            yield os.path.join(d, n)


def check_shards(store, tag):
    """Every shard of every level: the index at the end with its CRC-32C,
    entries inside the file without overlap, empty ones all ones; returns
    (shards, empty inner chunks)."""
    n_shards = n_empty = 0
    ok = True
    for lvl in sorted(os.listdir(store)):
        meta_p = os.path.join(store, lvl, "zarr.json")
        if not os.path.isfile(meta_p):
            continue
        meta = json.load(open(meta_p))
        cfg = meta["codecs"][0]["configuration"]
        outer = meta["chunk_grid"]["configuration"]["chunk_shape"]
        inner = cfg["chunk_shape"]
        n_in = int(np.prod([o // i for o, i in zip(outer, inner)]))
        for p in shard_files(os.path.join(store, lvl)):
            data = open(p, "rb").read()
            idx = data[len(data) - 16 * n_in - 4:len(data) - 4]
            crc = struct.unpack("<I", data[-4:])[0]
            if crc != crc32c.crc32c(idx):
                ok = False
                print(f"  {p}: index CRC-32C {crc:08x} != {crc32c.crc32c(idx):08x}")
                continue
            spans = []
            for e in range(n_in):
                off, size = struct.unpack_from("<QQ", idx, 16 * e)
                if off == size == 2**64 - 1:
                    n_empty += 1
                    continue
                if off + size > len(data) - 16 * n_in - 4:
                    ok = False
                spans.append((off, size))
            spans.sort()
            if any(a[0] + a[1] > b[0] for a, b in zip(spans, spans[1:])):
                ok = False
            n_shards += 1
    check(ok and n_shards > 0, f"{tag}: {n_shards} shards, each index CRC-32C'd, entries inside "
          f"the file without overlap ({n_empty} empty inner chunks)")
    return n_shards, n_empty


def judge(store, src, spacing, origin, tag, codec, chunk, shard, label=False, unit="millimeter"):
    """The store against src [k, j, i] by every reference reader."""
    dtype = src.dtype
    try:
        g = zarr.open_group(store, mode="r")
    except Exception as e:  # noqa: BLE001
        check(False, f"{tag}: zarr-python opens the group ({e})")
        return
    ome = g.attrs.get("ome", {})
    ms = ome.get("multiscales", [{}])[0]
    sets = ms.get("datasets", [])
    check(g.metadata.zarr_format == 3 and ome.get("version") == "0.5" and len(sets) >= 1 and
          [a["name"] for a in ms["axes"]] == ["z", "y", "x"] and
          all(a["type"] == "space" and a.get("unit") == unit for a in ms["axes"]),
          f"{tag}: a Zarr v3 group, ome version 0.5, axes z y x in {unit} ({len(sets)} levels)")
    # voxels: level 0 exactly, each next level numpy's 2x2x2 reduction
    prev = None
    factor = np.ones(3)
    for li, ds in enumerate(sets):
        a = g[ds["path"]]
        try:
            got = a[:]
        except Exception as e:  # noqa: BLE001
            check(False, f"{tag}: zarr-python reads level {li} ({type(e).__name__}: {e})")
            return
        if li == 0:
            check(a.dtype == dtype and np.array_equal(got, src),
                  f"{tag}: level 0 equals the input voxel for voxel ({a.dtype}, {a.shape})")
        else:
            want = prev[::2, ::2, ::2] if label else mean_down(prev, dtype)
            ok = np.array_equal(got, want) if label else levels_close(got, want, dtype)
            check(ok, f"{tag}: level {li} {a.shape} is the 2x2x2 "
                  f"{'first voxels' if label else 'means'} of level {li - 1}")
            factor *= [2 if n > 1 else 1 for n in prev.shape]
        prev = got
        # metadata of the array as asked
        meta = a.metadata
        cod = [c.to_dict()["name"] for c in meta.codecs]
        if shard:
            inner = meta.codecs[0].to_dict()["configuration"]
            cod = [c["name"] for c in inner["codecs"]]
            grid = inner["chunk_shape"]
        else:
            grid = meta.chunk_grid.chunk_shape
        want_c = ["bytes"] + ([] if codec == "none" else [codec])
        want_chunk = [min(c, n) for c, n in zip(chunk[::-1], a.shape)]
        check(cod == want_c and list(grid) == want_chunk and
              list(meta.dimension_names) == ["z", "y", "x"] and
              (not shard or meta.codecs[0].to_dict()["name"] == "sharding_indexed"),
              f"{tag}: level {li} codecs {cod}, chunk {list(grid)}"
              f"{', sharded ' + str(list(meta.chunk_grid.chunk_shape)) if shard else ''}")
        # scale and translation
        tr = {t["type"]: t for t in ds["coordinateTransformations"]}
        want_scale = (np.array(spacing) * factor)[::-1]
        want_tr = (np.array(origin) + (0 if label else 0.5) * (factor - 1) * np.array(spacing))[::-1]
        check(np.allclose(tr["scale"]["scale"], want_scale) and
              np.allclose(tr["translation"]["translation"], want_tr),
              f"{tag}: level {li} scale {tr['scale']['scale']} and translation "
              f"{tr['translation']['translation']}")
        # tensorstore reads the same
        t = ts.open({"driver": "zarr3",
                     "kvstore": {"driver": "file",
                                 "path": os.path.join(os.path.abspath(store), ds["path"])}},
                    read=True).result()
        check(np.array_equal(t.read().result(), got),
              f"{tag}: tensorstore reads level {li} as zarr-python does")
    # ome-zarr-py
    try:
        nodes = list(Reader(parse_url(store))())
        node = nodes[0]
        data = node.data
        ok = len(data) == len(sets) and np.array_equal(np.asarray(data[0]), src) and \
            [a["name"] for a in node.metadata["axes"]] == ["z", "y", "x"]
        check(ok, f"{tag}: ome-zarr-py reads {len(data)} levels, level 0 the input, axes z y x")
    except Exception as e:  # noqa: BLE001
        check(False, f"{tag}: ome-zarr-py reads it ({type(e).__name__}: {e})")
    # ome-zarr-models: the NGFF 0.5 schema
    try:
        m = open_ome_zarr(zarr.open_group(store, mode="r"))
        check(type(m).__module__.startswith("ome_zarr_models.v05") and
              type(m).__name__ in ("Image", "ImageLabel", "Labels"),
              f"{tag}: ome-zarr-models validates it as {type(m).__module__}.{type(m).__name__}")
    except Exception as e:  # noqa: BLE001
        msg = str(e).replace("\n", " ")[:300]
        check(False, f"{tag}: ome-zarr-models validates it ({type(e).__name__}: {msg})")
    if shard:
        check_shards(store, tag)


rng = np.random.default_rng(78)
CODECS = ["zstd", "blosc", "gzip", "none"]
# (name, array [k, j, i], NRRD type, spacing, origin, chunk, shard) -- sizes
# not multiples of the chunk; the shards leave inner chunks past the array
z, y, x = np.mgrid[0:37, 0:45, 0:70]
VOLS = [
    ("u16", ((x * 37 + y * 11 + z * 101) % 4099 + rng.integers(0, 40, x.shape)).astype(np.uint16),
     "ushort", (0.5, 0.75, 2.0), (10.0, -4.5, 3.25), (16, 16, 16), (32, 48, 32)),
    ("f32", (np.sin(x / 7) * np.cos(y / 11) * 1000 + z * 3).astype(np.float32)[:29, :37, :50],
     "float", (1.0, 1.0, 1.5), (0.0, 0.0, -7.0), (16, 8, 16), (32, 16, 48)),
    ("i8", rng.integers(-128, 127, (23, 30, 41), endpoint=True).astype(np.int8),
     "signed char", (0.3, 0.3, 0.3), (1.0, 2.0, 3.0), (8, 16, 8), (16, 32, 24)),
]
for name, arr, ntype, sp, org, chunk, shard in VOLS:
    src = os.path.join(OUT, name + ".nrrd")
    write_nrrd(src, arr, ntype, sp, org)
    cs = "%dx%dx%d" % chunk
    for codec in CODECS:
        for sh in (None, shard):
            tag = f"{name} {codec}{' sharded' if sh else ''}"
            dst = os.path.join(OUT, f"{name}_{codec}{'_s' if sh else ''}.ome.zarr")
            args = ["convert", src, dst, "--ngff", "0.5", "--chunk", cs, "--compress", codec]
            if sh:
                args += ["--shard", "%dx%dx%d" % sh]
            p = volvis(*args)
            check(p.returncode == 0 and not p.stderr, f"{tag}: converted ({p.stderr.strip()})")
            if p.returncode == 0:
                judge(dst, arr, sp, org, tag, codec, chunk, sh)

# the default: 0.5 with zstd, 64^3 chunks, no sharding
dflt = os.path.join(OUT, "default.ome.zarr")
p = volvis("convert", os.path.join(OUT, "u16.nrrd"), dflt, "--quiet")
meta = json.load(open(os.path.join(dflt, "0", "zarr.json"))) if p.returncode == 0 else {}
check(p.returncode == 0 and meta.get("zarr_format") == 3 and
      [c["name"] for c in meta.get("codecs", [])] == ["bytes", "zstd"] and
      meta["chunk_grid"]["configuration"]["chunk_shape"] == [37, 45, 64],
      f"by default OME-NGFF 0.5, zstd, 64^3 chunks clipped to the level {p.stderr.strip()}")

# the CT head (i16 256 x 256 x 108, gzip NRRD read slab by slab): sharded
# shards of 128^3 with the default 64^3 chunks, and unsharded blosc
head_np = None
for codec, sh in (("zstd", (128, 128, 128)), ("blosc", None)):
    dst = os.path.join(OUT, f"head_{codec}.ome.zarr")
    args = ["convert", HEAD, dst, "--compress", codec] + (["--shard", "128"] if sh else [])
    p = volvis(*args)
    check(p.returncode == 0, f"CT head {codec}: converted {p.stderr.strip()}")
    if head_np is None:
        nii = os.path.join(OUT, "head.nrrd")
        volvis("convert", HEAD, nii, "--no-compress", "--quiet")
        with open(nii, "rb") as f:
            raw = f.read()
        head_np = np.frombuffer(raw[raw.index(b"\n\n") + 2:], dtype="<i2").reshape(108, 256, 256)
        hdr = raw[:raw.index(b"\n\n")].decode()
        check("sizes: 256 256 108" in hdr, "CT head: its uncompressed NRRD twin")
    g = zarr.open_group(dst, mode="r")
    ms = g.attrs["ome"]["multiscales"][0]
    sp = ms["datasets"][0]["coordinateTransformations"][0]["scale"][::-1]
    judge(dst, head_np, sp, (0, 0, 0), f"CT head {codec}", codec, (64, 64, 64), sh,
          unit=None)  # the CT head's NRRD names no unit

# a label volume: the first voxel of each block, image-label
lab = ((x // 9 + y // 13 + z // 5) % 7).astype(np.uint8)
write_nrrd(os.path.join(OUT, "lab.nrrd"), lab, "uchar", (1, 1, 1), (0, 0, 0))
dst = os.path.join(OUT, "lab.ome.zarr")
p = volvis("convert", os.path.join(OUT, "lab.nrrd"), dst, "--label", "--chunk", "16",
           "--shard", "32")
check(p.returncode == 0, f"label volume converted {p.stderr.strip()}")
if p.returncode == 0:
    judge(dst, lab, (1, 1, 1), (0, 0, 0), "label", "zstd", (16, 16, 16), (32, 32, 32), label=True)
    check("image-label" in zarr.open_group(dst, mode="r").attrs["ome"],
          "label: attributes.ome has image-label")

# ---- the box-by-box writer makes the whole-volume writer's store --------------------------
def tree(path):
    out = {}
    for d, _, names in os.walk(path):
        for n in names:
            p = os.path.join(d, n)
            with open(p, "rb") as f:
                out[os.path.relpath(p, path)] = f.read()
    return out


u16 = VOLS[0][1]
for codec in ("zstd", "none"):
    a, b = os.path.join(OUT, f"stream_{codec}.ome.zarr"), os.path.join(OUT, f"whole_{codec}.ome.zarr")
    nii = os.path.join(OUT, "u16.mha")  # MetaImage: read whole, the geometry kept
    opts = ["--chunk", "16", "--shard", "32x48x32", "--compress", codec]
    p1 = volvis("convert", os.path.join(OUT, "u16.nrrd"), a, *opts)
    p2 = volvis("convert", os.path.join(OUT, "u16.nrrd"), nii, "--quiet")
    p3 = volvis("convert", nii, b, *opts)
    ta, tb = tree(a), tree(b)
    diff = sorted(k for k in set(ta) | set(tb) if ta.get(k) != tb.get(k))
    # the stores are named after their folders: the names differ, nothing else
    diff = [k for k in diff if k != "zarr.json" or
            ta[k].replace(b"stream_", b"whole_") != tb[k]]
    check(p1.returncode == 0 and "chunk by chunk" in p1.stdout and p3.returncode == 0 and
          "chunk by chunk" not in p3.stdout and len(ta) > 5 and not diff,
          f"{codec} sharded: the box-by-box writer's store is the whole-volume writer's, byte for "
          f"byte ({len(ta)} files{', differing: ' + ', '.join(diff[:5]) if diff else ''})")

# ---- out of core, bounded memory -------------------------------------------------------
def convert_peak(*args, budget):
    proc = subprocess.Popen([VOLVIS, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=dict(os.environ, VOLVIS_MAX_MEMORY=str(budget)))
    peak = 0
    while proc.poll() is None:
        try:
            with open(f"/proc/{proc.pid}/status") as f:
                for line in f:
                    if line.startswith("VmHWM:"):
                        peak = max(peak, int(line.split()[1]))
        except OSError:
            pass
        time.sleep(0.005)
    out, err = proc.communicate()
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err), peak


SANITIZER = bool(os.environ.get("VV_SANITIZER"))
side = (256, 256, 256) if SANITIZER else (512, 512, 256)  # x, y, z; u16: 32 or 128 MiB
big = os.path.join(OUT, "big.raw")
vol = (np.arange(side[0] * side[1], dtype=np.uint32) % 3001).astype(np.uint16)
with open(big, "wb") as f:
    for k in range(side[2]):
        (vol + k).tofile(f)
budget = side[0] * side[1] * side[2] * 2 // 4
bstore = os.path.join(OUT, "big.ome.zarr")
p, peak = convert_peak("convert", "--raw", "%dx%dx%d:u16" % side, big, bstore, "--shard", "128",
                       budget=budget)
size_mib = os.path.getsize(big) / 2**20
check(p.returncode == 0 and "chunk by chunk" in p.stdout,
      f"a {size_mib:.0f} MiB raw volume converted sharded chunk by chunk under a memory budget of "
      f"{budget / 2**20:.0f} MiB {p.stderr.strip()}")
if SANITIZER:
    print(f"note peak resident set {peak / 1024:.0f} MiB: not bounded under the sanitizers")
else:
    check(0 < peak / 1024 < size_mib / 2,
          f"peak resident set {peak / 1024:.0f} MiB < half the volume's {size_mib:.0f} MiB")
if p.returncode == 0:
    want = np.fromfile(big, dtype="<u2").reshape(side[2], side[1], side[0])
    t0 = ts.open({"driver": "zarr3", "kvstore": {"driver": "file",
                                                  "path": os.path.join(bstore, "0")}}).result()
    check(np.array_equal(t0.read().result(), want), "the big volume: tensorstore reads level 0 "
          "equal to the raw input")
    t1 = ts.open({"driver": "zarr3", "kvstore": {"driver": "file",
                                                  "path": os.path.join(bstore, "1")}}).result()
    check(levels_close(t1.read().result(), mean_down(want, np.uint16), np.uint16),
          "the big volume: level 1 is the 2x2x2 means of the input")
    del want
os.remove(big)
shutil.rmtree(bstore, ignore_errors=True)

# ---- 0.4 still writes Zarr v2 ------------------------------------------------------------
v2 = os.path.join(OUT, "v2.ome.zarr")
p = volvis("convert", os.path.join(OUT, "u16.nrrd"), v2, "--ngff", "0.4", "--compress", "zstd",
           "--chunk", "16")
g = zarr.open_group(v2, mode="r") if p.returncode == 0 else None
check(p.returncode == 0 and g.metadata.zarr_format == 2 and
      os.path.isfile(os.path.join(v2, "0", ".zarray")) and
      not os.path.exists(os.path.join(v2, "zarr.json")) and
      g.attrs["multiscales"][0]["version"] == "0.4" and np.array_equal(g["0"][:], u16) and
      g["0"].chunks == (16, 16, 16),
      f"--ngff 0.4: a Zarr v2 store (.zarray, multiscales 0.4, zstd, 16^3 chunks) read equal "
      f"{p.stderr.strip()}")

# ---- replacing stores --------------------------------------------------------------------
p = volvis("convert", os.path.join(OUT, "i8.nrrd"), v2, "--quiet")
names = set(os.listdir(v2)) if os.path.isdir(v2) else set()
check(p.returncode == 0 and "zarr.json" in names and ".zattrs" not in names and
      ".zgroup" not in names and np.array_equal(zarr.open_group(v2, mode="r")["0"][:], VOLS[2][1]),
      f"a v2 store replaced by a v3 one, nothing of the old left ({sorted(names)})")
p = volvis("convert", os.path.join(OUT, "u16.nrrd"), v2, "--quiet", "--ngff", "0.4")
names = set(os.listdir(v2)) if os.path.isdir(v2) else set()
check(p.returncode == 0 and "zarr.json" not in names and ".zattrs" in names,
      f"and a v3 store by a v2 one ({sorted(names)})")
keep = os.path.join(OUT, "notzarr")
os.makedirs(keep)
with open(os.path.join(keep, "mine.txt"), "w") as f:
    f.write("keep")
p = volvis("convert", os.path.join(OUT, "u16.nrrd"), keep, "--format", "zarr")
check(p.returncode != 0 and os.listdir(keep) == ["mine.txt"],
      f"a folder that is not a Zarr store is left as it is: {p.stderr.strip()}")

# ---- bad options: one line, exit 2, nothing written -------------------------------------
src = os.path.join(OUT, "u16.nrrd")
for args, what in [
        (["--chunk", "0"], "--chunk 0"),
        (["--chunk", "16x16"], "--chunk of two numbers"),
        (["--chunk", "32", "--shard", "48"], "a shard not a multiple of the chunk"),
        (["--shard", "100"], "a shard not a multiple of the default chunk"),
        (["--compress", "lz5"], "an unknown codec"),
        (["--compress", "zlib"], "zlib at 0.5 (not a v3 codec)"),
        (["--ngff", "0.3"], "--ngff 0.3"),
        (["--ngff", "0.4", "--shard", "128"], "sharding at 0.4"),
]:
    bad = os.path.join(OUT, "bad.ome.zarr")
    p = volvis("convert", src, bad, *args)
    err = p.stderr.strip()
    check(p.returncode == 2 and err.count("\n") == 0 and err and not os.path.exists(bad),
          f"{what}: one line, exit 2, nothing written ({err})")
p = volvis("convert", src, os.path.join(OUT, "bad.nrrd"), "--shard", "64")
check(p.returncode == 2 and p.stderr.strip().count("\n") == 0 and
      not os.path.exists(os.path.join(OUT, "bad.nrrd")),
      f"--shard with NRRD output: one line, exit 2 ({p.stderr.strip()})")
left = [n for n in os.listdir(OUT) if ".tmp-" in n]
check(not left, f"no temporary folder left ({left})")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
