#!/usr/bin/env python3
"""Tiled and pyramidal TIFF out of core (issue 91, item 3), files written by tifffile.

  tiff_store_cli.py VOLVIS OUTDIR [--big]

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test): tifffile writes,
VolVis reads; tifffile's own reading of each level and numpy are the judges.

- a tiled BigTIFF OME-TIFF (u16, zlib, 64 x 64 tiles cut at the edges) with three
  SubIFD levels: `volvis info` names four levels and their spacing; each level read
  whole (`convert --level L`) is tifffile's level L in x and y and the mean of 2^L
  slices in z (level 0: the stack voxel for voxel);
- rendered out of core (--memory-limit 8M) at level 0 as in memory (>= 50 dB), and by
  level of detail from the SubIFD levels;
- channels and time of an OME-TIFF (TCZYX, tiled, SubIFDs): a channel at a time step
  at level 1 voxel for voxel; two channels together out of core as in memory;
- strips: an ImageJ stack of several rows a strip, and a folder of one-page files,
  out of core as in memory (>= 50 dB);
- hostile files: tiles cut off the end of the file, a SubIFD offset past the file, a
  page of another size: one line naming the file, a non-zero exit, no image written;
- with --big: 300 MB of voxels (1024 x 1024 x 150 u16, 256 x 256 tiles, three SubIFD
  levels) under --memory-limit 64M renders like in memory (>= 50 dB) with volvis's
  peak RSS, and the peak PSS of volvis and its reader processes together, <= 200 MB.
"""
import os
import shutil
import struct
import subprocess
import sys
import time

try:
    import numpy as np
    import tifffile
except ImportError as e:
    print(f"skipped: {e} (the .venv of scripts/install-deps.sh test)")
    sys.exit(77)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cli_common import Checks, read_nrrd, render_png, run  # noqa: E402
from pyramid_common import psnr  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
BIG = "--big" in sys.argv[3:]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
check = Checks()
SIZE = ["--size", "200x160"]


def volvis(*args):
    return run(VOLVIS, *args)


def render(name, src, *args):
    return render_png(VOLVIS, OUT, check, name, src, *SIZE, *args)


def db(a, b):
    return psnr(a, b) if a and b else -1.0


def read_level(src, level, *args):
    out = os.path.join(OUT, "back.nrrd")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("convert", src, out, "--quiet", "--level", str(level), *args)
    if p.returncode != 0:
        check(False, f"convert {os.path.basename(src)} --level {level}: {p.stderr.strip()}")
        return None
    return read_nrrd(out)[0]


def z_mean(a, f):
    """The mean of F slices (z first) of A, rounded to nearest as VolVis's pyramids do."""
    a = a.astype(np.float64)
    n = (a.shape[0] + f - 1) // f
    return np.stack([np.floor(a[k * f:(k + 1) * f].mean(0) + 0.5) for k in range(n)])


def field(nz, ny, nx, seed):
    """A smooth u16 volume with a ball in it (z, y, x)."""
    z, y, x = np.mgrid[0:nz, 0:ny, 0:nx].astype(np.float32)
    v = (1000 + 900 * np.sin(x / 17.0 + seed) * np.cos(y / 13.0) + 9 * z
         + 900 * (((x - nx / 2) ** 2 + (y - ny / 2) ** 2 + (3 * (z - nz / 2)) ** 2)
                  < (0.35 * nx) ** 2))
    return v.astype(np.uint16)


def pyramid_tiff(path, v, levels, tile, meta, axes="ZYX"):
    """V written as a tiled OME-TIFF with LEVELS SubIFD levels (every 2^l-th pixel in
    x and y, as tifffile's examples do)."""
    with tifffile.TiffWriter(path, bigtiff=True) as w:
        opts = dict(tile=tile, compression="zlib", compressionargs={"level": 1},
                    photometric="minisblack")
        w.write(v, subifds=levels, metadata={"axes": axes, **meta}, **opts)
        for lv in range(1, levels + 1):
            f = 2 ** lv
            w.write(v[..., ::f, ::f], subfiletype=1, **opts)


# ---- a tiled pyramid: its levels voxel for voxel -------------------------------------------
v = field(40, 150, 170, 0.0)
pyr = os.path.join(OUT, "pyr.ome.tif")
META = {"PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 2.0}
pyramid_tiff(pyr, v, 3, (64, 64), META)
p = volvis("info", pyr)
check(p.returncode == 0 and "levels:       4" in p.stdout
      and "level 1: 85 x 75 x 20, spacing 1 x 1 x 4" in p.stdout
      and "level 3: 22 x 19 x 5, spacing 4 x 4 x 16" in p.stdout
      and "spacing:      0.5 x 0.5 x 2 um" in p.stdout,
      f"info: four levels, their sizes and spacing ({p.stdout[:400]} {p.stderr.strip()})")
with tifffile.TiffFile(pyr) as tf:
    judge = [lv.asarray() for lv in tf.series[0].levels]
check(len(judge) == 4, f"tifffile reads 4 levels ({len(judge)})")
for lv in range(4):
    got = read_level(pyr, lv)
    want = z_mean(judge[lv], 2 ** lv)
    check(got is not None and got.shape == want.shape
          and np.array_equal(got.astype(np.float64), want),
          f"level {lv}: tifffile's level, slices averaged by {2 ** lv} "
          f"({None if got is None else got.shape} vs {want.shape})")

mem = render("pyr_mem", pyr, "--tf", "1500:2900")
ooc = render("pyr_ooc", pyr, "--level", "0", "--memory-limit", "8M", "--tf", "1500:2900")
d = db(mem, ooc)
check(d >= 50, f"out of core (--memory-limit 8M) {d:.1f} dB from in memory (>= 50)")
lod1 = render("pyr_level1", pyr, "--level", "1", "--memory-limit", "8M", "--tf", "1500:2900")
w1 = os.path.join(OUT, "level1.nrrd")
p = volvis("convert", pyr, w1, "--quiet", "--level", "1")
whole1 = render("pyr_level1_whole", w1, "--tf", "1500:2900") if p.returncode == 0 else None
d = db(lod1, whole1)
check(d >= 50, f"level 1 out of core {d:.1f} dB from level 1 read whole (>= 50)")
p = volvis("render", pyr, "-o", os.path.join(OUT, "pyr_lod.png"), *SIZE, "--lod", "2",
           "--memory-limit", "8M", "--tf", "1500:2900")
check(p.returncode == 0 and "from 4 levels: 0: 0 nodes 0 chunks" in p.stdout,
      f"--lod 2 draws from the SubIFD levels alone ({p.stdout.strip()} {p.stderr.strip()})")

# ---- channels and time ----------------------------------------------------------------------
tc = np.stack([np.stack([field(24, 90, 100, 0.7 * c + 0.3 * t) for c in range(2)])
               for t in range(2)])  # t, c, z, y, x
hyper = os.path.join(OUT, "tc.ome.tif")
pyramid_tiff(hyper, tc, 1, (32, 32), META, axes="TCZYX")
got = read_level(hyper, 1, "--channel", "1", "--time", "1")
want = z_mean(tc[1, 1, :, ::2, ::2], 2)
check(got is not None and got.shape == want.shape and np.array_equal(got.astype(np.float64), want),
      "channel 1 at time step 1, level 1: voxel for voxel")
got = read_level(hyper, 0, "--channel", "1", "--time", "1")
check(got is not None and np.array_equal(got, tc[1, 1]), "channel 1 at time step 1, level 0")
cm = render("tc_mem", hyper, "--channels", "0,1", "--time", "1")
co = render("tc_ooc", hyper, "--channels", "0,1", "--time", "1", "--level", "0",
            "--memory-limit", "4M")
d = db(cm, co)
check(d >= 50, f"two channels at time step 1 out of core {d:.1f} dB from in memory (>= 50)")

# ---- strips: an ImageJ stack, a folder of pages ------------------------------------------------
s8 = (field(60, 140, 180, 1.1) // 16).astype(np.uint8)
ij = os.path.join(OUT, "strips.tif")
tifffile.imwrite(ij, s8, imagej=True, rowsperstrip=9, compression="zlib", resolution=(2.0, 2.0),
                 metadata={"spacing": 1.5, "unit": "micron"})
sm = render("strips_mem", ij, "--tf", "90:180")
so = render("strips_ooc", ij, "--level", "0", "--memory-limit", "2M", "--tf", "90:180")
d = db(sm, so)
check(d >= 50, f"an ImageJ stack of strips out of core {d:.1f} dB from in memory (>= 50)")
folder = os.path.join(OUT, "pages")
os.makedirs(folder)
for k in range(s8.shape[0]):
    tifffile.imwrite(os.path.join(folder, f"z{k}.tif"), s8[k], rowsperstrip=16)
fm = render("folder_mem", folder, "--tf", "90:180")
fo = render("folder_ooc", folder, "--level", "0", "--memory-limit", "2M", "--tf", "90:180")
d = db(fm, fo)
check(d >= 50, f"a folder of pages out of core {d:.1f} dB from in memory (>= 50)")


# ---- hostile files ---------------------------------------------------------------------------
def refused(name, path, want, *args):
    out = os.path.join(OUT, name + ".png")
    p = volvis("render", path, "-o", out, *SIZE, "--level", "0", "--memory-limit", "8M", *args)
    err = p.stderr.strip()
    check(p.returncode != 0 and len(err.splitlines()) == 1 and os.path.basename(path) in err
          and want in err and not os.path.exists(out),
          f"{name}: one line naming the file and '{want}', exit {p.returncode}, no image ({err})")


with open(pyr, "rb") as f:
    whole = f.read()
spoilt = bytearray(whole)  # slice 20's first tile: bytes zlib cannot inflate
with tifffile.TiffFile(pyr) as tf:
    at, n = tf.pages[20].dataoffsets[0], tf.pages[20].databytecounts[0]
spoilt[at:at + n] = b"\xff" * n
bad_tile = os.path.join(OUT, "bad_tile.ome.tif")
with open(bad_tile, "wb") as f:
    f.write(spoilt)
refused("bad_tile", bad_tile, "page 20: tile 0")
cut = os.path.join(OUT, "cut.ome.tif")
with open(cut, "wb") as f:  # cut in the middle: IFDs past the end
    f.write(whole[:len(whole) // 2])
refused("cut", cut, "page")

with tifffile.TiffFile(pyr) as tf:
    tag = tf.pages[0].tags["SubIFDs"]
    at, count = tag.valueoffset, tag.count
bad_sub = bytearray(whole)
check(count == 3, f"page 0 has 3 SubIFDs ({count})")
struct.pack_into("<Q", bad_sub, at, len(whole) + 4096)  # BigTIFF: level 1's offset, first
badp = os.path.join(OUT, "subifd_past.ome.tif")
with open(badp, "wb") as f:
    f.write(bad_sub)
p = volvis("render", badp, "-o", os.path.join(OUT, "subifd_past.png"), *SIZE, "--lod", "2",
           "--memory-limit", "2M")
err = p.stderr.strip()
check(p.returncode != 0 and len(err.splitlines()) == 1 and "subifd_past.ome.tif" in err
      and not os.path.exists(os.path.join(OUT, "subifd_past.png")),
      f"a SubIFD offset past the file: one line naming it, no image ({err})")

mixed = os.path.join(OUT, "mixed")
os.makedirs(mixed)
for k in range(12):
    tifffile.imwrite(os.path.join(mixed, f"z{k:02d}.tif"),
                     s8[k] if k != 9 else s8[k, :100, :100], rowsperstrip=16)
refused("mixed", mixed, "z09.tif")

# ---- 300 MB under 64M ------------------------------------------------------------------------


def descendants(pid):
    """PID and every process below it (from /proc/PID/task/*/children)."""
    found, to_visit = [], [pid]
    while to_visit:
        q = to_visit.pop()
        found.append(q)
        try:
            for t in os.listdir(f"/proc/{q}/task"):
                with open(f"/proc/{q}/task/{t}/children") as f:
                    to_visit.extend(int(c) for c in f.read().split())
        except (OSError, ValueError):
            pass  # a process that ended meanwhile
    return found


def status_kb(path, key):
    """The kB of line KEY in /proc's file PATH (0 when the process is gone)."""
    try:
        with open(path) as f:
            for ln in f:
                if ln.startswith(key):
                    return int(ln.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def tree_pss(pid):
    """The proportional set size (kB) of PID and its descendants together (shared
    libraries counted once), and PID's own peak resident set (VmHWM, kB)."""
    pss = sum(status_kb(f"/proc/{q}/smaps_rollup", "Pss:") for q in descendants(pid))
    return pss, status_kb(f"/proc/{pid}/status", "VmHWM:")


def peak_run(*args):
    """volvis ARGS; the peak over samples every 10 ms of its process tree's summed
    PSS (volvis and its sandboxed readers), and volvis's own peak RSS (kB)."""
    proc = subprocess.Popen([VOLVIS, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    peak, own = 0, 0
    while proc.poll() is None:
        pss, hwm = tree_pss(proc.pid)
        peak, own = max(peak, pss), max(own, hwm)
        time.sleep(0.01)
    out, err = proc.communicate()
    return proc.returncode, out, err, peak, own


if BIG:
    nz, n = 150, 1024
    big = np.empty((nz, n, n), np.uint16)
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float32)
    for k in range(nz):
        big[k] = (1000 + 900 * np.sin(xx / 57.0) * np.cos(yy / 43.0) + 6 * k
                  + 800 * (((xx - 512) ** 2 + (yy - 512) ** 2 + (6 * k - 450) ** 2) < 380 ** 2))
    bigp = os.path.join(OUT, "big.ome.tif")
    pyramid_tiff(bigp, big, 3, (256, 256), META)
    check(big.nbytes >= 300e6, f"{big.nbytes / 1e6:.0f} MB of voxels")
    del big
    bo = os.path.join(OUT, "big_ooc.png")
    rc, out, err, peak, own = peak_run("render", bigp, "-o", bo, *SIZE, "--level", "0",
                                  "--memory-limit", "64M", "--tf", "1500:2900")
    check(rc == 0, f"300 MB under --memory-limit 64M: {out.strip()} {err.strip()}")
    check(own <= 200 * 1024 and peak <= 200 * 1024,
          f"peak RSS of volvis {own / 1024:.0f} MB, of volvis and its readers together (PSS) "
          f"{peak / 1024:.0f} MB (each <= 200)")
    print(f"300 MB OME-TIFF under --memory-limit 64M: peak RSS {own / 1024:.0f} MB, with its "
          f"readers {peak / 1024:.0f} MB; {out.strip()}")
    bm = render("big_mem", bigp, "--tf", "1500:2900")
    d = db(bm, bo if rc == 0 else None)
    check(d >= 50, f"300 MB out of core {d:.1f} dB from in memory (>= 50)")
    os.remove(bigp)

check.finish("tiff_store_cli")
