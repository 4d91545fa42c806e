#!/usr/bin/python3
"""OME-Zarr pyramids written by zarr-python, rendered out of core by level.

  zarr_pyramid_cli.py VOLVIS OUTDIR

Writes with zarr-python and numcodecs (independent writers) three-level
pyramids of 2x2x2 means, each level with its OME-NGFF scale and the
translation of its voxel centres:

- the CT head (256x256x108, int16) in 32^3 chunks, Blosc lz4 with byte
  shuffle, "/" separator, the omero window's min and max the data's;
- an analytic phantom (128^3 uint8: a ball of 200 inside a ball of 100 in
  a background of 0, so every level keeps the range 0..200) in 64^3
  chunks, once each with zstd and "." separator, zlib, and no compressor;

then checks:

- `volvis convert STORE OUT.nii --level L` equals zarr-python's level L,
  voxel for voxel, with the level's spacing and origin (every level, every
  store);
- out of core (`volvis render STORE --memory-limit 4M --level 0`, every
  box assembled from cached chunks) against the in-memory render of level
  0: composite >= 50 dB, MIP >= 55 dB (and the unrefined in-memory MIP, refinement=off,
  bit-identical), X-ray and the isosurface bit-identical; the cache never above the
  limit; with a limit that holds the frame's chunks (16M) each chunk is
  read once a frame (the counts the render prints);
- the phantom at levels 1 and 2 out of core (4M) against the in-memory
  render of the same level: MIP bit-identical (the boxes of coarser
  levels, their placement);
- nodes rendered two at a time (a thread each) make the image one thread
  makes in turn, byte for byte;
- progressive frames (--progressive 40 chunks a step): the first step from
  the coarsest level, each step no farther from the converged image (PSNR
  non-decreasing), the last (and OUT) the converged image bit for bit;
- level of detail: a perspective view with --lod 2.5 mixes levels 0 and
  1; against the same view at level 1 everywhere it has no crack (no pixel
  opaque in one and empty in the other) and is close (PSNR >= 25 dB); an
  isosurface across levels 0 and 1 has no hole inside the surface that
  both levels, each rendered alone in memory, show;
- the chunks decoded by the long-lived sandboxed readers (the default) and
  in-process (VOLVIS_SANDBOX=0) make one image; a reader that crashes
  (VOLVIS_SANDBOX_INJECT=abort) is one line naming the store;
- bad stores out of core: a chunk that decodes to the wrong size, an
  unknown compressor, inconsistent multiscales (a level of another dtype,
  a level larger than level 0): one line naming the store, a non-zero
  exit and no PNG; a missing chunk is the fill value, as zarr-python reads
  it.
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
    from PIL import Image  # noqa: F401 (pyramid_common's)
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-numpy, python3-nibabel, python3-zarr, python3-numcodecs, "
          "python3-pil)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pyramid_common  # noqa: E402
from pyramid_common import cracks, psnr, stats, write_ome_zarr  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
HEAD = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def volvis(*args, env=None):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True,
                          env=dict(os.environ, **(env or {})))


def pyramid(name, arr, spacing, chunks, compressor, sep, n=3, window=True):
    """An OME-Zarr 0.4 store of n levels in OUT; returns (path, levels)."""
    root = os.path.join(OUT, name)
    return root, write_ome_zarr(root, arr, spacing, chunks, compressor, sep, n, window)


def read_level(store, level):
    """volvis convert --level to NIfTI: (z, y, x) voxels and the affine."""
    nii = os.path.join(OUT, "level.nii")
    p = volvis("convert", store, nii, "--level", str(level), "--quiet")
    if p.returncode != 0:
        return None, None, p.stderr.strip()
    img = nib.load(nii)
    return np.asarray(img.dataobj).transpose(2, 1, 0), img.affine, ""


def render(store, out, *args, env=None):
    return volvis("render", store, "-o", out, "--size", "256x256", *args, env=env)


# ---- the stores -------------------------------------------------------------------------
head_nii = os.path.join(OUT, "head.nii")
p = volvis("convert", HEAD, head_nii, "--quiet")
check(p.returncode == 0, f"the CT head converted for numpy ({p.stderr.strip()})")
hi = nib.load(head_nii)
head = np.ascontiguousarray(np.asarray(hi.dataobj).transpose(2, 1, 0))
head_sp = [float(z) for z in hi.header.get_zooms()[::-1]]
head_store, head_lv = pyramid("head.zarr", head, head_sp, (32, 32, 32),
                              numcodecs.Blosc("lz4", shuffle=numcodecs.Blosc.SHUFFLE), "/")

z, y, x = np.mgrid[0:128, 0:128, 0:128].astype(np.float64)
r = np.sqrt((x - 60) ** 2 + (y - 66) ** 2 + (z - 63) ** 2)
phantom = np.where(r < 24, 200, np.where(r < 48, 100, 0)).astype(np.uint8)
phantoms = {
    "zstd": pyramid("ph_zstd.zarr", phantom, [1.0, 1.0, 1.0], (64, 64, 64),
                    numcodecs.Zstd(level=3), "."),
    "zlib": pyramid("ph_zlib.zarr", phantom, [1.0, 1.0, 1.0], (64, 64, 64),
                    numcodecs.Zlib(level=1), "/"),
    "raw": pyramid("ph_raw.zarr", phantom, [1.0, 1.0, 1.0], (64, 64, 64), None, "."),
}

# ---- every level's voxels -----------------------------------------------------------------
for name, (store, lv) in [("head", (head_store, head_lv))] + list(phantoms.items()):
    for k, want in enumerate(lv):
        got, aff, err = read_level(store, k)
        same = got is not None and got.shape == want.shape and np.array_equal(got, want)
        check(same, f"{name} level {k}: volvis reads zarr-python's voxels {want.shape} {err}")
        if got is not None:
            f = 2 ** k
            sp = (head_sp if name == "head" else [1.0, 1.0, 1.0])[::-1]
            check(np.allclose(np.abs(np.diag(aff)[:3]), [s * f for s in sp], rtol=1e-5),
                  f"{name} level {k}: spacing {np.abs(np.diag(aff)[:3])}")
got, _, err = read_level(head_store, 3)
check(got is None and "level 3" in err and "3" in err,
      f"a level past the store's is refused: {err}")

# ---- out of core against in memory ----------------------------------------------------------
TF = ["--tf", "100:1500"]
for mode in ["composite", "mip", "iso", "xray"]:
    mem = os.path.join(OUT, f"head_{mode}_mem.png")
    ooc = os.path.join(OUT, f"head_{mode}_ooc.png")
    how = ["--iso", "600"] if mode == "iso" else ["--mode", mode, *TF]
    p1 = render(head_store, mem, *how)
    p2 = render(head_store, ooc, *how, "--memory-limit", "4M", "--level", "0")
    check(p1.returncode == 0 and p2.returncode == 0,
          f"head {mode}: rendered in memory and out of core ({p1.stderr.strip()} "
          f"{p2.stderr.strip()})")
    if p1.returncode or p2.returncode:
        continue
    peak, most, _ = stats(p2)
    print(f"     {p2.stdout.strip()}")
    check(peak is not None and peak <= 4.0, f"head {mode} at 4M: peak cache {peak} MiB <= 4 MiB")
    q = psnr(mem, ooc)
    if mode == "mip":
        # region renders cast every pixel: the unrefined in-memory MIP bit for bit, and within
        # 55 dB of the refined default (docs/rendering.md, "Quality and adaptive refinement")
        plain = os.path.join(OUT, f"head_{mode}_mem_unrefined.png")
        p3 = render(head_store, plain, *how, "--set", "refinement=off")
        qp = psnr(plain, ooc) if p3.returncode == 0 else 0
        check(qp == 99.0, f"head mip out of core (4 MiB) is the unrefined in-memory image bit "
              f"for bit ({qp})")
        check(q >= 55, f"head mip out of core (4 MiB): {q:.1f} dB >= 55 against in memory (measured 60.9)")
    elif mode != "composite":
        check(q == 99.0,
              f"head {mode} out of core (4 MiB) is the in-memory image bit for bit ({q})")
    else:
        check(q >= 50, f"head composite out of core (4 MiB): {q:.1f} dB >= 50 against in memory")
# the nodes rendered two at a time, one a thread (64 MiB holds two nodes' working sets beside
# the cache), make the image one thread makes in turn, byte for byte
one = os.path.join(OUT, "head_one_thread.png")
two = os.path.join(OUT, "head_two_threads.png")
ps = [render(head_store, out, *TF, "--memory-limit", "64M", "--lod", "0.7", env=env)
      for out, env in [(one, {"OMP_NUM_THREADS": "1"}), (two, {"OMP_NUM_THREADS": "2"})]]
check(all(q.returncode == 0 for q in ps) and open(one, "rb").read() == open(two, "rb").read(),
      f"composite out of core: 1 and 2 threads make the same image "
      f"({' '.join(q.stderr.strip() for q in ps)})")
p = render(head_store, os.path.join(OUT, "head_16m.png"), *TF, "--memory-limit", "16M",
           "--level", "0")
peak, most, _ = stats(p)
check(p.returncode == 0 and most == 1,
      f"head at 16M: each chunk read once a frame ({p.stdout.strip()} {p.stderr.strip()})")

for k in (1, 2):
    mem = os.path.join(OUT, f"ph_l{k}_mem.png")
    ooc = os.path.join(OUT, f"ph_l{k}_ooc.png")
    store = phantoms["zstd"][0]
    p1 = render(store, mem, "--mode", "mip", "--tf", "50:250", "--level", str(k))
    p2 = render(store, ooc, "--mode", "mip", "--tf", "50:250", "--level", str(k),
                "--memory-limit", "4M", "--azimuth", "0")
    ok = p1.returncode == 0 and p2.returncode == 0
    check(ok and psnr(mem, ooc) == 99.0,
          f"phantom level {k}: out-of-core MIP is the in-memory one bit for bit "
          f"({p1.stderr.strip()} {p2.stderr.strip()})")

# ---- progressive frames ------------------------------------------------------------------
for mode in ["composite", "mip"]:
    conv = os.path.join(OUT, f"prog_{mode}_conv.png")
    prog = os.path.join(OUT, f"prog_{mode}.png")
    p1 = render(head_store, conv, "--mode", mode, *TF, "--memory-limit", "16M")
    p2 = render(head_store, prog, "--mode", mode, *TF, "--memory-limit", "16M", "--progressive",
                "40")
    steps = sorted(f for f in os.listdir(OUT) if f.startswith(f"prog_{mode}_p"))
    ok = p1.returncode == 0 and p2.returncode == 0 and len(steps) >= 3
    check(ok, f"head {mode} --progressive 40: {len(steps)} steps {p2.stderr.strip()}")
    if not ok:
        continue
    q = [psnr(os.path.join(OUT, f), conv) for f in steps]
    print(f"     PSNR of each step against the converged image: {[round(x, 1) for x in q]}")
    check(all(b >= a for a, b in zip(q, q[1:])),
          f"head {mode}: each step closer to the converged image (PSNR non-decreasing)")
    check(q[-1] == 99.0 and psnr(prog, conv) == 99.0,
          f"head {mode}: the last step and OUT are the converged image bit for bit")
    check(q[0] < 40, f"head {mode}: the first step is drawn from the coarsest level ({q[0]:.1f} dB)")

# ---- level of detail without cracks ---------------------------------------------------------
store = phantoms["zlib"][0]
view = ["--azimuth", "35", "--elevation", "20", "--tf", "50:250", "--alpha", "--memory-limit",
        "4M"]
mixed = os.path.join(OUT, "lod_mixed_a.png")
coarse = os.path.join(OUT, "lod_coarse_a.png")
p1 = render(store, mixed, *view, "--lod", "2.5")
p2 = render(store, coarse, *view, "--level", "1")
_, _, nodes = stats(p1)
print(f"     {p1.stdout.strip()}")
check(p1.returncode == 0 and len(nodes) >= 2 and nodes[0] > 0 and nodes[1] > 0,
      f"--lod 2.5 mixes levels 0 and 1 (nodes per level {nodes}) {p1.stderr.strip()}")
if p1.returncode == 0 and p2.returncode == 0:
    n = cracks(mixed, coarse)
    check(n == 0, f"no crack between levels: {n} pixels opaque in one, empty in the other")
    q = psnr(mixed, coarse)
    check(q >= 25, f"mixed levels against level 1 everywhere: {q:.1f} dB >= 25")

# an isosurface across levels: the inner ball (200 in 100) at 150 from nodes of levels 0 and 1;
# a pixel inside the surface of both levels rendered alone (in memory; its 3x3 neighbourhood
# surface in both) shows it mixed too. On the silhouette a grazing ray may cross the surface
# of one level in one node and of the other in another and miss both: counted, not a crack.
iso_view = ["--azimuth", "35", "--elevation", "20", "--iso", "150", "--alpha"]
mixed = os.path.join(OUT, "lod_mixed_iso_a.png")
p1 = render(store, mixed, *iso_view, "--memory-limit", "4M", "--lod", "2.5")
_, _, nodes = stats(p1)
ok = p1.returncode == 0 and len(nodes) >= 2 and nodes[0] > 0 and nodes[1] > 0
check(ok, f"iso --lod 2.5 mixes levels 0 and 1 (nodes per level {nodes}) {p1.stderr.strip()}")
both = []
for k in (0, 1):
    both.append(os.path.join(OUT, f"lod_iso_l{k}_mem_a.png"))
    p = render(store, both[-1], *iso_view, "--level", str(k))
    ok = ok and p.returncode == 0
if ok:
    a, l0, l1 = (pyramid_common.image(f)[..., 3] for f in [mixed] + both)
    surf = (l0 > 128) & (l1 > 128)
    inner = surf.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(surf, dy, 0), dx, 1)
    holes = int(np.sum(inner & (a < 8)))
    rim = int(np.sum(surf & ~inner & (a < 8)))
    seen = int(np.sum(a > 128))
    check(holes == 0 and seen > 1000,
          f"no crack in the mixed-level isosurface: {holes} holes inside, {seen} pixels of "
          f"surface ({rim} silhouette pixels missed by grazing rays)")

# ---- bad stores ----------------------------------------------------------------------------


def broken(name, edit):
    src = phantoms["zstd"][0]
    dst = os.path.join(OUT, name)
    shutil.rmtree(dst, ignore_errors=True)
    shutil.copytree(src, dst)
    edit(dst)
    return dst


def refused(store, needle, what):
    png = os.path.join(OUT, "bad.png")
    if os.path.exists(png):
        os.remove(png)
    p = render(store, png, "--memory-limit", "4M", "--level", "0")
    err = p.stderr.strip()
    check(p.returncode != 0 and len(err.splitlines()) == 1 and os.path.basename(store) in err
          and needle in err and not os.path.exists(png), f"{what}: {err}")


def wrong_size(d):
    c = zarr.open_array(os.path.join(d, "0"), mode="r")
    with open(os.path.join(d, "0", "1.1.0"), "wb") as f:
        f.write(numcodecs.Zstd().encode(np.zeros(1000, np.uint8).tobytes()))
    del c


refused(broken("bad_size.zarr", wrong_size), "1.1.0", "a chunk that decodes to the wrong size")


def set_key(level, key, value):
    def edit(d):
        import json
        path = os.path.join(d, level, ".zarray")
        meta = json.load(open(path))
        meta[key] = value
        json.dump(meta, open(path, "w"))
    return edit


refused(broken("bad_codec.zarr", set_key("0", "compressor", {"id": "lzma"})), "lzma",
        "an unknown compressor")
refused(broken("bad_dtype.zarr", set_key("1", "dtype", "<u2")), "inconsistent",
        "a level of another dtype")
refused(broken("bad_shape.zarr", set_key("2", "shape", [256, 256, 256])), "inconsistent",
        "a level larger than level 0")


def drop_chunk(d):
    os.remove(os.path.join(d, "0", "0.0.0"))


store = broken("missing.zarr", drop_chunk)
want = zarr.open_array(os.path.join(store, "0"), mode="r")[...]
got, _, err = read_level(store, 0)
check(got is not None and np.array_equal(got, want),
      f"a missing chunk reads as zarr-python reads it (the fill value) {err}")
mem, ooc = os.path.join(OUT, "missing_mem.png"), os.path.join(OUT, "missing_ooc.png")
p1 = render(store, mem, "--mode", "mip", "--tf", "50:250")
p2 = render(store, ooc, "--mode", "mip", "--tf", "50:250", "--memory-limit", "4M", "--level", "0")
check(p1.returncode == 0 and p2.returncode == 0 and psnr(mem, ooc) == 99.0,
      f"a missing chunk out of core: the fill value, as in memory {p2.stderr.strip()}")

# ---- the sandboxed readers ------------------------------------------------------------------
# the chunks decoded by the long-lived sandboxed readers (the default) and in this process
# (VOLVIS_SANDBOX=0) make one image; a reader that crashes is one line
sbx, local = os.path.join(OUT, "sbx.png"), os.path.join(OUT, "local.png")
p1 = render(head_store, sbx, *TF, "--memory-limit", "4M", "--level", "0")
p2 = render(head_store, local, *TF, "--memory-limit", "4M", "--level", "0",
            env={"VOLVIS_SANDBOX": "0"})
check(p1.returncode == 0 and p2.returncode == 0 and psnr(sbx, local) == 99.0,
      f"sandboxed readers and in-process decoding give one image {p1.stderr.strip()}")
png = os.path.join(OUT, "crash.png")
p = render(head_store, png, *TF, "--memory-limit", "4M", env={"VOLVIS_SANDBOX_INJECT": "abort"})
err = p.stderr.strip()
check(p.returncode != 0 and len(err.splitlines()) == 1 and "head.zarr" in err
      and "crashed (SIGABRT)" in err and not os.path.exists(png),
      f"a chunk reader that crashes: {err}")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
