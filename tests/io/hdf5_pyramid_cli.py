#!/usr/bin/python3
"""BigDataViewer and Imaris HDF5 pyramids written by h5py, read and rendered by level.

  hdf5_pyramid_cli.py VOLVIS OUTDIR

Writes with h5py (an independent writer) three-level pyramids of 2x2x2
means:

- BigDataViewer (t00000/s<SS>/<level>/cells, s<SS>/resolutions,
  s<SS>/subdivisions; gzip-compressed 32^3 chunks): the CT head as uint16
  (setup s00) and an analytic phantom (128^3: a ball of 40000 inside a
  ball of 20000) stored as int16, the format's convention for unsigned
  16-bit voxels (setup s01);
- Imaris 5.5 (DataSet/ResolutionLevel L/TimePoint 0/Channel 0/Data, its
  datasets padded to a multiple of 32 voxels, ImageSizeX/Y/Z and
  DataSetInfo/Image's ExtMin/ExtMax, Unit and the channel's
  HistogramMin/Max as arrays of one-byte strings, as Imaris writes them):
  the CT head (int16) with its spacing;

then checks:

- `volvis info` names the format and its 3 levels; `volvis convert FILE
  OUT.nii --level L [--channel C]` equals h5py's level L voxel for voxel
  (every level, both files, both BigDataViewer setups; the Imaris padding
  cut off; the phantom's int16 bits read as uint16), with the level's
  spacing (BigDataViewer: the factors; Imaris: the extent over the size);
- out of core (`volvis render FILE --memory-limit 4M --level 0`: chunks
  read by libhdf5 in the long-lived sandboxed reader) against the
  in-memory render of level 0: MIP >= 55 dB (the unrefined one,
  refinement=off, bit-identical), composite >= 50 dB; the
  same with VOLVIS_SANDBOX=0 (libhdf5 in-process) bit for bit; each chunk
  read once a frame at 16M; the phantom at level 1 MIP bit-identical;
- level of detail: --lod 2.5 mixes levels without cracks against level 1
  everywhere;
- bad files: an HDF5 file of neither layout, a "cells" dataset of rank 2,
  a level larger than level 0 and a level of another type (inconsistent
  multiscales), a chunk whose compressed bytes are corrupted, a truncated
  file, and a reader that crashes (VOLVIS_SANDBOX_INJECT=abort): one line
  naming the file, a non-zero exit and no PNG.
"""
import os
import re
import shutil
import subprocess
import sys

try:
    import h5py
    import nibabel as nib
    import numpy as np
    from PIL import Image  # noqa: F401 (pyramid_common's)
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-h5py, python3-numpy, python3-nibabel, python3-pil)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pyramid_common import cracks, levels_of, psnr, stats  # noqa: E402

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


def chars(s):
    """An attribute as Imaris writes it: an array of one-byte strings."""
    return np.array(list(str(s)), dtype="S1")


def bdv(path, setups, stored_dtype=None):
    """A BigDataViewer HDF5 file, one setup per (levels) entry of @p setups."""
    with h5py.File(path, "w") as f:
        for s, lv in enumerate(setups):
            f[f"s{s:02d}/resolutions"] = np.array([[2.0 ** k] * 3 for k in range(len(lv))])
            f[f"s{s:02d}/subdivisions"] = np.array([[32, 32, 32]] * len(lv), dtype=np.int32)
            for k, a in enumerate(lv):
                data = a if stored_dtype is None else a.view(stored_dtype[s] or a.dtype)
                f.create_dataset(f"t00000/s{s:02d}/{k}/cells", data=data,
                                 chunks=tuple(min(32, d) for d in a.shape), compression="gzip")


def ims(path, lv, spacing):
    """An Imaris 5.5 file of one channel and time point, datasets padded to 32."""
    with h5py.File(path, "w") as f:
        z, y, x = lv[0].shape
        img = f.create_group("DataSetInfo/Image")
        img.attrs["Unit"] = chars("mm")
        for k, (n, s) in enumerate(zip((x, y, z), spacing[::-1])):
            img.attrs[f"ExtMin{k}"] = chars("0")
            img.attrs[f"ExtMax{k}"] = chars(f"{n * s:.6f}")
        for k, a in enumerate(lv):
            g = f.create_group(f"DataSet/ResolutionLevel {k}/TimePoint 0/Channel 0")
            pad = np.zeros([-(-d // 32) * 32 for d in a.shape], a.dtype)
            pad[:a.shape[0], :a.shape[1], :a.shape[2]] = a
            g.create_dataset("Data", data=pad, chunks=(32, 32, 32), compression="gzip")
            for name, n in zip(("ImageSizeX", "ImageSizeY", "ImageSizeZ"), a.shape[::-1]):
                g.attrs[name] = chars(n)
            g.attrs["HistogramMin"] = chars(f"{a.min():.3f}")
            g.attrs["HistogramMax"] = chars(f"{a.max():.3f}")


def read_level(path, level, *extra, env=None):
    """volvis convert --level to NIfTI: (z, y, x) voxels and the affine."""
    nii = os.path.join(OUT, "level.nii")
    p = volvis("convert", path, nii, "--level", str(level), "--quiet", *extra, env=env)
    if p.returncode != 0:
        return None, None, p.stderr.strip()
    img = nib.load(nii)
    return np.asarray(img.dataobj).transpose(2, 1, 0), img.affine, ""


def render(path, out, *args, env=None):
    return volvis("render", path, "-o", out, "--size", "256x256", *args, env=env)


# ---- the files ---------------------------------------------------------------------------
head_nii = os.path.join(OUT, "head.nii")
p = volvis("convert", HEAD, head_nii, "--quiet")
check(p.returncode == 0, f"the CT head converted for numpy ({p.stderr.strip()})")
hi = nib.load(head_nii)
head = np.ascontiguousarray(np.asarray(hi.dataobj).transpose(2, 1, 0))
head_sp = [float(s) for s in hi.header.get_zooms()[::-1]]  # z, y, x
head_u16 = np.clip(head, 0, None).astype(np.uint16)

z, y, x = np.mgrid[0:128, 0:128, 0:128].astype(np.float64)
r = np.sqrt((x - 60) ** 2 + (y - 66) ** 2 + (z - 63) ** 2)
phantom = np.where(r < 24, 40000, np.where(r < 48, 20000, 0)).astype(np.uint16)

bdv_path = os.path.join(OUT, "head_phantom.h5")
head_lv, ph_lv = levels_of(head_u16), levels_of(phantom)
bdv(bdv_path, [head_lv, ph_lv], stored_dtype=[None, np.int16])
ims_path = os.path.join(OUT, "head.ims")
ims_lv = levels_of(head)
ims(ims_path, ims_lv, head_sp)

p = volvis("info", ims_path)
check(p.returncode == 0 and re.search(r"format:\s+hdf5", p.stdout)
      and re.search(r"levels:\s+3", p.stdout) and re.search(r"unit:\s+mm", p.stdout),
      f"volvis info names the Imaris file's format, 3 levels and unit {p.stdout} {p.stderr}")

# ---- every level's voxels -----------------------------------------------------------------
cases = [("bdv s00 (head)", bdv_path, head_lv, [], [1.0, 1.0, 1.0]),
         ("bdv s01 (phantom, int16 bits)", bdv_path, ph_lv, ["--channel", "1"], [1.0, 1.0, 1.0]),
         ("ims (head)", ims_path, ims_lv, [], head_sp)]
for name, path, lv, extra, sp in cases:
    for k, want in enumerate(lv):
        got, aff, err = read_level(path, k, *extra)
        same = got is not None and got.shape == want.shape and np.array_equal(got, want)
        check(same, f"{name} level {k}: volvis reads h5py's voxels {want.shape} {err}")
        if got is not None:
            # Imaris: the extent over the level's size; BigDataViewer: the factors
            want_sp = ([sp[i] * lv[0].shape[i] / want.shape[i] for i in range(3)][::-1]
                       if "ims" in name else [2.0 ** k] * 3)
            check(np.allclose(np.abs(np.diag(aff)[:3]), want_sp, rtol=1e-4),
                  f"{name} level {k}: spacing {np.abs(np.diag(aff)[:3])} (want {want_sp})")
got, _, err = read_level(ims_path, 3)
check(got is None and "level 3" in err, f"a level past the file's is refused: {err}")

# ---- out of core against in memory ----------------------------------------------------------
TF = ["--tf", "100:1500"]
for mode in ["composite", "mip"]:
    mem = os.path.join(OUT, f"ims_{mode}_mem.png")
    ooc = os.path.join(OUT, f"ims_{mode}_ooc.png")
    p1 = render(ims_path, mem, "--mode", mode, *TF)
    p2 = render(ims_path, ooc, "--mode", mode, *TF, "--memory-limit", "4M", "--level", "0")
    check(p1.returncode == 0 and p2.returncode == 0,
          f"ims {mode}: rendered in memory and out of core ({p1.stderr.strip()} "
          f"{p2.stderr.strip()})")
    if p1.returncode or p2.returncode:
        continue
    print(f"     {p2.stdout.strip()}")
    peak, most, _ = stats(p2)
    check(peak is not None and peak <= 4.0, f"ims {mode} at 4M: peak cache {peak} MiB <= 4 MiB")
    q = psnr(mem, ooc)
    if mode == "mip":
        # region renders cast every pixel: the unrefined in-memory MIP bit for bit, and within
        # 55 dB of the refined default (docs/rendering.md, "Quality and adaptive refinement")
        plain = os.path.join(OUT, f"ims_{mode}_mem_unrefined.png")
        p3 = render(ims_path, plain, "--mode", mode, *TF, "--set", "refinement=off")
        qp = psnr(plain, ooc) if p3.returncode == 0 else 0
        check(qp == 99.0, f"ims mip out of core (4 MiB) is the unrefined in-memory image bit "
              f"for bit ({qp})")
        check(q >= 55, f"ims mip out of core (4 MiB): {q:.1f} dB >= 55 (measured 60.9) against the refined "
              f"in-memory default")
    else:
        check(q >= 50, f"ims composite out of core (4 MiB): {q:.1f} dB >= 50 against in memory")
    local = os.path.join(OUT, f"ims_{mode}_local.png")
    p3 = render(ims_path, local, "--mode", mode, *TF, "--memory-limit", "4M", "--level", "0",
                env={"VOLVIS_SANDBOX": "0"})
    check(p3.returncode == 0 and psnr(ooc, local) == 99.0,
          f"ims {mode}: the sandboxed reader's chunks and libhdf5 in-process give one image "
          f"{p3.stderr.strip()}")
p = render(ims_path, os.path.join(OUT, "ims_16m.png"), *TF, "--memory-limit", "16M", "--level",
           "0")
peak, most, _ = stats(p)
check(p.returncode == 0 and most == 1,
      f"ims at 16M: each chunk read once a frame ({p.stdout.strip()} {p.stderr.strip()})")

mem = os.path.join(OUT, "ph_l1_mem.png")
ooc = os.path.join(OUT, "ph_l1_ooc.png")
view = ["--mode", "mip", "--tf", "10000:45000", "--channel", "1", "--level", "1"]
p1 = render(bdv_path, mem, *view)
p2 = render(bdv_path, ooc, *view, "--memory-limit", "4M")
check(p1.returncode == 0 and p2.returncode == 0 and psnr(mem, ooc) == 99.0,
      f"bdv phantom level 1: out-of-core MIP is the in-memory one bit for bit "
      f"({p1.stderr.strip()} {p2.stderr.strip()})")

# ---- BigDataViewer's companion XML: the voxel size and its unit ------------------------------


def bdv_xml(name, h5name, size, unit="\u00b5m"):
    """NAME.xml as BigDataViewer/Fiji write it: setup 0's voxelSize (x y z)."""
    with open(os.path.join(OUT, name), "w", encoding="utf-8") as f:
        f.write(f"""<?xml version="1.0" encoding="UTF-8"?>
<SpimData version="0.2">
  <BasePath type="relative">.</BasePath>
  <SequenceDescription>
    <ImageLoader format="bdv.hdf5"><hdf5 type="relative">{h5name}</hdf5></ImageLoader>
    <ViewSetups>
      <ViewSetup><id>1</id><name>other</name>
        <voxelSize><unit>mm</unit><size>9 9 9</size></voxelSize></ViewSetup>
      <ViewSetup><id>0</id><name>0</name><size>64 64 64</size>
        <voxelSize><unit>{unit}</unit><size>{size}</size></voxelSize></ViewSetup>
    </ViewSetups>
  </SequenceDescription>
</SpimData>
""")


aniso_lv = levels_of(phantom[:64, :64, :64])
vs = [0.5, 0.75, 2.0]  # x, y, z
aniso = os.path.join(OUT, "aniso.h5")
bdv(aniso, [aniso_lv])
bdv_xml("aniso.xml", "aniso.h5", " ".join(map(str, vs)))
p = volvis("info", aniso)
check(p.returncode == 0 and re.search(r"spacing:\s+0\.5 x 0\.75 x 2 um", p.stdout)
      and re.search(r"unit:\s+um", p.stdout),
      "bdv + XML: volvis info gives the XML's voxel size and unit "
      f"{re.findall(r'(?:spacing|unit):.*', p.stdout)} {p.stderr.strip()}")
for k in range(2):
    got, aff, err = read_level(aniso, k)
    f = 2.0 ** k
    ok = got is not None and np.array_equal(got, aniso_lv[k])
    ok = ok and np.allclose(np.abs(np.diag(aff)[:3]), [f * v for v in vs], rtol=1e-4)
    ok = ok and np.allclose(np.abs(aff[:3, 3]), [(f - 1) / 2 * v for v in vs], atol=1e-4)
    check(ok, f"bdv + XML level {k}: spacing {f} x {vs}, voxel 0 at {(f - 1) / 2} voxels "
          f"({None if aff is None else aff[:3].tolist()} {err})")
view = ["--mode", "mip", "--azimuth", "30", "--elevation", "25", "--tf", "10000:45000"]
mem = os.path.join(OUT, "aniso_mem.png")
ooc = os.path.join(OUT, "aniso_ooc.png")
iso = os.path.join(OUT, "aniso_iso.png")
p1 = render(aniso, mem, *view)
p2 = render(aniso, ooc, *view, "--memory-limit", "4M", "--level", "0")
check(p1.returncode == 0 and p2.returncode == 0 and psnr(mem, ooc) == 99.0,
      f"bdv + XML: the out-of-core MIP (the readers' level table) is the in-memory one "
      f"({p1.stderr.strip()} {p2.stderr.strip()})")
bdv_xml("aniso.xml", "another.h5", " ".join(map(str, vs)))
p3 = render(aniso, iso, *view)
check(p3.returncode == 0 and psnr(mem, iso) < 30,
      f"an XML of another HDF5 file is not read (isotropic image {psnr(mem, iso):.1f} dB "
      f"from the anisotropic one) {p3.stderr.strip()}")
got, aff, err = read_level(aniso, 0)
check(aff is not None and np.allclose(np.abs(np.diag(aff)[:3]), 1),
      f"... and its voxels stay 1 a side {err}")

view = ["--azimuth", "35", "--elevation", "20", "--tf", "10000:45000", "--alpha", "--channel",
        "1", "--memory-limit", "4M"]
mixed = os.path.join(OUT, "lod_mixed_a.png")
coarse = os.path.join(OUT, "lod_coarse_a.png")
p1 = render(bdv_path, mixed, *view, "--lod", "2.5")
p2 = render(bdv_path, coarse, *view, "--level", "1")
_, _, nodes = stats(p1)
print(f"     {p1.stdout.strip()}")
check(p1.returncode == 0 and len(nodes) >= 2 and nodes[0] > 0 and nodes[1] > 0,
      f"bdv --lod 2.5 mixes levels 0 and 1 (nodes per level {nodes}) {p1.stderr.strip()}")
if p1.returncode == 0 and p2.returncode == 0:
    n = cracks(mixed, coarse)
    check(n == 0, f"no crack between levels: {n} pixels opaque in one, empty in the other")
    check(psnr(mixed, coarse) >= 25, f"mixed levels against level 1: {psnr(mixed, coarse):.1f} dB")

# ---- bad files -------------------------------------------------------------------------------


def refused(path, needle, what, env=None):
    png = os.path.join(OUT, "bad.png")
    if os.path.exists(png):
        os.remove(png)
    p = render(path, png, "--memory-limit", "4M", "--level", "0", env=env)
    err = p.stderr.strip()
    check(p.returncode != 0 and len(err.splitlines()) == 1 and os.path.basename(path) in err
          and needle in err and not os.path.exists(png), f"{what}: {err}")


small = levels_of(phantom[:64, :64, :64])
path = os.path.join(OUT, "neither.h5")
with h5py.File(path, "w") as f:
    f["volume"] = phantom
refused(path, "neither", "an HDF5 file of neither layout")



def bad_bdv(name, dataset, data):
    """A small BigDataViewer file whose dataset @p dataset is replaced by @p data."""
    path = os.path.join(OUT, name)
    bdv(path, [small])
    with h5py.File(path, "a") as f:
        del f[dataset]
        f[dataset] = data
    return path


bdv_xml("aniso.xml", "aniso.h5", "0 0.5 2")
refused(aniso, "aniso.xml: ViewSetup 0's voxelSize", "a companion XML with a voxel size of 0")
with open(os.path.join(OUT, "aniso.xml"), "w") as f:
    f.write("<SpimData><SequenceDescription><ViewSetups")
refused(aniso, "aniso.xml: the companion XML cannot be parsed", "a truncated companion XML")
os.remove(os.path.join(OUT, "aniso.xml"))
refused(bad_bdv("rank2.h5", "t00000/s00/0/cells", np.zeros((64, 64), np.uint16)), "not 3",
        "a cells dataset of rank 2")
refused(bad_bdv("bigger.h5", "t00000/s00/2/cells", np.zeros((128, 16, 16), np.uint16)),
        "inconsistent", "a level larger than level 0")
refused(bad_bdv("dtype.h5", "t00000/s00/1/cells", np.zeros((32, 32, 32), np.float32)),
        "inconsistent", "a level of another type")

path = os.path.join(OUT, "corrupt.h5")
bdv(path, [small])
with h5py.File(path, "r") as f:
    d = f["t00000/s00/0/cells"]
    off = d.id.get_chunk_info(0).byte_offset
with open(path, "r+b") as f:
    f.seek(off + 4)
    f.write(b"\xff" * 64)
refused(path, "does not read", "a chunk whose compressed bytes are corrupted")

path = os.path.join(OUT, "truncated.h5")
bdv(path, [small])
size = os.path.getsize(path)
with open(path, "r+b") as f:
    f.truncate(size // 3)
refused(path, "truncated.h5", "a truncated file")

refused(bdv_path, "crashed (SIGABRT)", "a reader that aborts",
        env={"VOLVIS_SANDBOX_INJECT": "abort"})

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
