#!/usr/bin/python3
"""BigDataViewer's dataset XML, the entry a Fiji user has, read as Fiji writes it.

  bdv_xml_cli.py VOLVIS OUTDIR

h5py writes a BigDataViewer HDF5 file (t<TTTTT>/s<SS>/<level>/cells, two
levels of 2x2x2 subsampling, gzip 16^3 chunks) of two setups ("DAPI",
"GFP") at three time points, every volume unsigned 16-bit stored as int16
(the format's convention, values above 32767 included); the XML beside it
is a SpimData 0.2 document as Fiji's "Export Current Image as XML/HDF5"
writes it: ImageLoader bdv.hdf5 with a relative path, ViewSetups with
voxel sizes in microns and channel attributes, Timepoints as a range, and
per view a registration of two affines (a translation, then the
calibration), which SpimData composes first to last. Then:

- `volvis info ds.xml`: the format, 2 levels, 2 channels by their setup
  names, 3 time steps, the calibration's spacing in um, the translation as
  the origin;
- `volvis convert ds.xml OUT.nii --channel C --time T --level L` equals
  h5py's data viewed as uint16 for every channel, time point and level,
  with the level's spacing (2^L times the calibration) and the placement
  of its first voxel ((2^L - 1) / 2 voxels in);
- a registration with a rotation: the NIfTI affine is the composed affine
  times the level's factors;
- `volvis render ds.xml --channel 0 --time 1` (values up to 45560): in
  memory and out of core (--memory-limit 4M --level 0, the long-lived
  sandboxed reader) MIP >= 60 dB (not bit for bit: on this 32 x 24 x 20
  volume of 16^3 chunks a few pixels along the nodes' seams differ by up to
  2/255, as they did before the XML was readable: `volvis render ds.h5`
  of the HDF5 file alone gives the same image pair); the images written and
  looked at (bdv_xml_*.png);
- bad XML: an HDF5 path outside the XML's folder, an XML cut short, a
  time point the HDF5 file lacks: one line naming the file, a non-zero exit
  and no output.
"""
import math
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
from pyramid_common import psnr  # noqa: E402

VOLVIS, OUT = sys.argv[1], sys.argv[2]
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


NAMES = ["DAPI", "GFP"]
TIMES = 3
SHAPE = (20, 24, 32)  # z, y, x
CAL = [0.5, 0.5, 2.0]  # x, y, z microns
SHIFT = [10.0, 20.0, 30.0]


def volume(s, t):
    """Setup s at time point t: a ramp whose values pass 32767 at (s, t) = (1, 2)."""
    z, y, x = np.mgrid[0:SHAPE[0], 0:SHAPE[1], 0:SHAPE[2]].astype(np.int64)
    return ((x + 2 * y + 3 * z) * (t + 1) * (s + 1) * 170 % 65536).astype(np.uint16)


levels = {}
h5 = os.path.join(OUT, "ds.h5")
with h5py.File(h5, "w") as f:
    for s in range(len(NAMES)):
        f[f"s{s:02d}/resolutions"] = np.array([[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]])
        f[f"s{s:02d}/subdivisions"] = np.array([[16, 16, 16], [16, 16, 16]], dtype=np.int32)
        for t in range(TIMES):
            a = volume(s, t)
            # level 1: BigDataViewer's 2x2x2 mean, as its exporter makes it
            b = a.astype(np.float64).reshape(10, 2, 12, 2, 16, 2).mean(axis=(1, 3, 5))
            b = np.floor(b + 0.5).astype(np.uint16)
            levels[s, t] = [a, b]
            for k, lv in enumerate((a, b)):
                f.create_dataset(f"t{t:05d}/s{s:02d}/{k}/cells", data=lv.view(np.int16),
                                 chunks=tuple(min(16, n) for n in lv.shape), compression="gzip")
check(levels[1, 2][0].max() > 32767, "the GFP setup at time point 2 holds values above 32767")


def affine_text(m):
    return " ".join(f"{v:.17g}" for v in np.asarray(m)[:3].ravel())


def xml(name, h5name, transforms, timepoints=(0, TIMES - 1), cut=False):
    """NAME as Fiji's BigDataViewer export writes it; @p transforms: the
    4x4 affines of every view's registration, first to last."""
    setups = "".join(f"""      <ViewSetup>
        <id>{s}</id>
        <name>{n}</name>
        <size>{SHAPE[2]} {SHAPE[1]} {SHAPE[0]}</size>
        <voxelSize>
          <unit>µm</unit>
          <size>{CAL[0]} {CAL[1]} {CAL[2]}</size>
        </voxelSize>
        <attributes>
          <illumination>0</illumination>
          <channel>{s + 1}</channel>
          <tile>0</tile>
          <angle>0</angle>
        </attributes>
      </ViewSetup>
""" for s, n in enumerate(NAMES))
    regs = "".join(f"""    <ViewRegistration timepoint="{t}" setup="{s}">
""" + "".join(f"""      <ViewTransform type="affine">
        <Name>{label}</Name>
        <affine>{affine_text(m)}</affine>
      </ViewTransform>
""" for label, m in transforms) + """    </ViewRegistration>
""" for t in range(TIMES) for s in range(len(NAMES)))
    text = f"""<?xml version="1.0" encoding="UTF-8"?>
<SpimData version="0.2">
  <BasePath type="relative">.</BasePath>
  <SequenceDescription>
    <ImageLoader format="bdv.hdf5">
      <hdf5 type="relative">{h5name}</hdf5>
    </ImageLoader>
    <ViewSetups>
{setups}      <Attributes name="illumination">
        <Illumination><id>0</id><name>0</name></Illumination>
      </Attributes>
      <Attributes name="channel">
        <Channel><id>1</id><name>1</name></Channel>
        <Channel><id>2</id><name>2</name></Channel>
      </Attributes>
    </ViewSetups>
    <Timepoints type="range">
      <first>{timepoints[0]}</first>
      <last>{timepoints[1]}</last>
    </Timepoints>
    <MissingViews />
  </SequenceDescription>
  <ViewRegistrations>
{regs}  </ViewRegistrations>
</SpimData>
"""
    path = os.path.join(OUT, name)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text[: len(text) // 2] if cut else text)
    return path


translation = np.eye(4)
translation[:3, 3] = SHIFT
calibration = np.diag(CAL + [1.0])
ds = xml("ds.xml", "ds.h5", [("Translation", translation), ("calibration", calibration)])

# ---- volvis info ------------------------------------------------------------------------------
p = volvis("info", ds)
info = p.stdout
check(p.returncode == 0 and re.search(r"format:\s+bdv", info) and re.search(r"levels:\s+2", info)
      and re.search(r"channels:\s+2", info) and '"DAPI"' in info and '"GFP"' in info
      and re.search(r"time steps:\s+3", info)
      and re.search(r"spacing:\s+0\.5 x 0\.5 x 2 um", info)
      and re.search(r"origin:\s+10 20 30\b", info),
      "volvis info ds.xml: bdv, 2 levels, channels DAPI and GFP, 3 time steps, the "
      f"calibration's spacing and the translation's origin\n{info}{p.stderr.strip()}")
p = volvis("info", ds, "--channel", "1", "--time", "2")
m = re.search(r"range:\s+(\d+) \.\. (\d+)", p.stdout)
check(p.returncode == 0 and m and int(m.group(2)) == int(levels[1, 2][0].max()),
      f"GFP at time 2: range up to {levels[1, 2][0].max()} read as unsigned 16-bit "
      f"({m.group(0) if m else p.stderr.strip()})")

# ---- every channel, time point and level against h5py -----------------------------------------


def read(path, c, t, level):
    nii = os.path.join(OUT, "level.nii")
    p = volvis("convert", path, nii, "--channel", str(c), "--time", str(t), "--level",
               str(level), "--quiet")
    if p.returncode != 0:
        return None, None, p.stderr.strip()
    img = nib.load(nii)
    return np.asarray(img.dataobj).transpose(2, 1, 0), img.affine, ""


def expected_affine(a, f):
    """The NIfTI (RAS) affine of a level of factor @p f under the composed
    affine @p a: columns A diag(f), voxel 0 at A ((f - 1) / 2)."""
    m = a.copy()
    m[:3, :3] = a[:3, :3] @ np.diag([f, f, f])
    m[:3, 3] = (a @ np.array([(f - 1) / 2] * 3 + [1.0]))[:3]
    ras = np.diag([-1.0, -1.0, 1.0, 1.0])  # VolVis's world is LPS where the file says nothing
    return m, ras @ m


composed = translation @ calibration
bad = []
for c in range(len(NAMES)):
    for t in range(TIMES):
        for k in range(2):
            got, aff, err = read(ds, c, t, k)
            want = levels[c, t][k]
            lps, ras = expected_affine(composed, 2.0 ** k)
            ok = got is not None and got.dtype == np.uint16 and np.array_equal(got, want)
            ok = ok and (np.allclose(aff, ras, atol=1e-4) or np.allclose(aff, lps, atol=1e-4))
            if not ok:
                bad.append((c, t, k, err, None if aff is None else aff[:3].round(3).tolist()))
check(not bad, "convert --channel C --time T --level L: h5py's voxels as uint16 with the "
      f"level's spacing and placement, 2 channels x 3 time points x 2 levels {bad}")

# ---- a rotated registration ----------------------------------------------------------------------
th = math.radians(30)
rotation = np.eye(4)
rotation[:2, :2] = [[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]]
rot = xml("rot.xml", "ds.h5", [("Translation", translation), ("Rotation", rotation),
                               ("calibration", calibration)])
got, aff, err = read(rot, 0, 1, 1)
lps, ras = expected_affine(translation @ rotation @ calibration, 2.0)
check(got is not None and np.array_equal(got, levels[0, 1][1])
      and (np.allclose(aff, ras, atol=1e-4) or np.allclose(aff, lps, atol=1e-4)),
      f"a rotation in the registration: the affine is the composed one times the level's "
      f"factors ({None if aff is None else aff[:3].round(4).tolist()} against "
      f"{ras[:3].round(4).tolist()}) {err}")

# ---- rendering ---------------------------------------------------------------------------------
view = ["--channel", "0", "--time", "1", "--mode", "mip", "--size", "160x120", "--azimuth", "30",
        "--elevation", "20", "--tf", "0:65535"]  # the same ramp (a proxy's histogram differs)
mem = os.path.join(OUT, "bdv_xml_mem.png")
ooc = os.path.join(OUT, "bdv_xml_ooc.png")
p1 = volvis("render", ds, "-o", mem, *view)
p2 = volvis("render", ds, "-o", ooc, *view, "--memory-limit", "4M", "--level", "0")
q = psnr(mem, ooc)
check(p1.returncode == 0 and p2.returncode == 0 and "out of core" in p2.stdout and q >= 60,
      f"render ds.xml DAPI at time 1 (up to 45560): out of core (level 0) against the in-memory "
      f"MIP {q:.1f} dB "
      f"({p1.stderr.strip()} {p2.stdout.strip()} {p2.stderr.strip()})")

# ---- bad XML -----------------------------------------------------------------------------------


def refused(path, needle, what, *args):
    out = os.path.join(OUT, "bad.nii")
    if os.path.exists(out):
        os.remove(out)
    p = volvis("convert", path, out, "--quiet", *args)
    err = p.stderr.strip()
    check(p.returncode != 0 and len(err.splitlines()) == 1 and os.path.basename(path) in err
          and needle in err and not os.path.exists(out), f"{what}: {err}")


refused(xml("outside.xml", "../ds.h5", [("calibration", calibration)]), "outside.xml",
        "an HDF5 path outside the XML's folder")
refused(xml("cut.xml", "ds.h5", [("calibration", calibration)], cut=True), "cut.xml",
        "an XML cut short")
refused(xml("late.xml", "ds.h5", [("calibration", calibration)], timepoints=(0, 5)), "t00004",
        "a time point the HDF5 file lacks", "--time", "4")

print(f"{len(failures)} failure(s)")
sys.exit(1 if failures else 0)
