#!/usr/bin/python3
"""A file's channels and time steps on the command line (issue 30).

  channels_time_cli.py VOLVIS OUTDIR

Writes, with independent writers, files of several channels and time steps:

- an OME-TIFF (TCZYX, u16) by tifffile, with channel names, colours and a
  time increment;
- an ImageJ hyperstack (TZCYX, u16) by tifffile;
- a 5-D NIfTI-1 (x, y, z, t, channel; f32, gzip) and a 4-D one by nibabel;
- a NRRD with an axis of kind RGB-color and one of kind time by Teem's
  `unu make` (when teem-apps is there: else the test is skipped);
- VTK XML image data (.vti) by vtkXMLImageDataWriter in every data mode,
  zlib or not, either byte order: each component a channel, its name, the
  direction and the extent's origin; bad .vti files are one-line errors;
- a cardiac cine DICOM series by pydicom: 4 phases at each of 6 slice
  positions, one file an image, the files' names and instance numbers
  shuffled, Trigger Time and Temporal Position Identifier set;

then checks:

- `volvis convert IN OUT.nii --channel C --time T` gives, read with nibabel,
  the voxels numpy wrote at (T, C), for every channel and step (a sample of
  pairs, first and last among them);
- `volvis info` names the counts, the OME names and colours, each channel's
  value range and the time increment; an RGB TIFF's samples and a NRRD
  RGB-color axis are red, green and blue;
- `volvis render --channels C` takes the file's colour when no --colors;
- `volvis render --time-range A:B:S` writes each step's image, equal to
  `--time T` alone, one channel and several; `volvis animate` with an
  `objects[0].time` track draws step k in frame k, equal to `--time k`;
- a scene's volume object with "time" draws that step (channels too);
- a big-endian 4-D NIfTI's steps read by offset (swapped) draw as the
  steps read by nifti_clib;
- `volvis measure --coloc C1,C2 --mask M --thresholds TA,TB` equals numpy's
  Pearson's r and Manders' M1, M2; `--channel C --time T --histogram`
  equals numpy's histogram;
- bad input: a step or channel past the file's, --time on a file without a
  time axis, a NRRD with two time axes: one line naming the file and the
  count, a non-zero exit, no output written.

Exit 0 passed, 1 failed, 77 skipped (a module or unu missing).
"""
import os
import shutil
import subprocess
import sys

try:
    import numpy as np
    import nibabel as nib
    import tifffile
    from PIL import Image
    import pydicom
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-numpy, python3-nibabel, python3-tifffile, python3-pil, "
          "python3-pydicom)")
    sys.exit(77)
UNU = shutil.which("teem-unu") or shutil.which("unu")
if not UNU:  # pragma: no cover
    print("skipped: Teem's unu (teem-unu) is missing (teem-apps)")
    sys.exit(77)

VOLVIS, OUT = sys.argv[1], sys.argv[2]
os.makedirs(OUT, exist_ok=True)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def volvis(*args):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True)


def read_back(path, c, t, extra=()):
    """volvis convert --channel c --time t to NIfTI, read with nibabel as (z, y, x)."""
    nii = os.path.join(OUT, f"back_{os.path.basename(path)}_{c}_{t}.nii")
    if os.path.exists(nii):
        os.remove(nii)
    p = volvis("convert", path, nii, "--channel", str(c), "--time", str(t), "--quiet", *extra)
    if p.returncode != 0:
        check(False, f"convert {os.path.basename(path)} --channel {c} --time {t}: "
              f"{p.stderr.strip()}")
        return None
    return np.asarray(nib.load(nii).dataobj).transpose(2, 1, 0)


def refused(args, needle, out_file, what):
    if os.path.exists(out_file):
        os.remove(out_file)
    p = volvis(*args)
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode != 0 and len(lines) == 1 and needle in lines[0] and
          not os.path.exists(out_file), f"{what}: {lines[:2]} (exit {p.returncode})")


rng = np.random.default_rng(30)
T, C, Z, Y, X = 4, 3, 6, 14, 11
tczyx = rng.integers(0, 4000, size=(T, C, Z, Y, X), dtype=np.uint16)

# OME-TIFF: red, green and blue channels by name (OME colours are RGBA)
ome = os.path.join(OUT, "cells.ome.tif")
tifffile.imwrite(ome, tczyx, metadata={
    "axes": "TCZYX",
    "Channel": {"Name": ["DAPI", "GFP", "mCherry"],
                "Color": [-16776961, 16711935, 65535]},
    "TimeIncrement": 0.5, "TimeIncrementUnit": "s"})
for t, c in ((0, 0), (3, 2), (1, 1)):
    got = read_back(ome, c, t)
    if got is not None:
        check(np.array_equal(got, tczyx[t, c]), f"OME-TIFF channel {c} time {t}: voxels")

# ImageJ hyperstack: TZCYX
ij = os.path.join(OUT, "stack_ij.tif")
# with ImageJ lookup tables (IJMetadata "luts"): yellow, cyan and grey
luts = np.zeros((3, 3, 256), np.uint8)
ramp = np.arange(256, dtype=np.uint8)
luts[0, 0] = luts[0, 1] = ramp
luts[1, 1] = luts[1, 2] = ramp
luts[2, 0] = luts[2, 1] = luts[2, 2] = ramp
tifffile.imwrite(ij, np.ascontiguousarray(tczyx.transpose(0, 2, 1, 3, 4)), imagej=True,
                 metadata={"axes": "TZCYX", "LUTs": list(luts)})
for t, c in ((3, 2), (2, 1)):
    got = read_back(ij, c, t)
    if got is not None:
        check(np.array_equal(got, tczyx[t, c]), f"ImageJ hyperstack channel {c} time {t}: voxels")

# NIfTI: x, y, z, t, channel
xyztc = rng.normal(size=(X, Y, Z, T, C)).astype(np.float32)
img = nib.Nifti1Image(xyztc, np.diag([0.5, 0.6, 0.7, 1.0]))
img.header.set_xyzt_units("mm", "msec")
img.header["pixdim"][4] = 250
five = os.path.join(OUT, "five.nii.gz")
nib.save(img, five)
for t, c in ((1, 2), (3, 1)):
    got = read_back(five, c, t)
    if got is not None:
        check(np.array_equal(got, xyztc[:, :, :, t, c].transpose(2, 1, 0)),
              f"5-D NIfTI channel {c} time {t}: voxels")
four = os.path.join(OUT, "four.nii")
nib.save(nib.Nifti1Image(xyztc[..., 1], np.eye(4)), four)
got = read_back(four, 0, 2)
if got is not None:
    check(np.array_equal(got, xyztc[:, :, :, 2, 1].transpose(2, 1, 0)), "4-D NIfTI time 2: voxels")

# NRRD by unu make: axes (RGB-color, x, y, z, time), the colour fastest
cxyzt = rng.integers(-3000, 3000, size=(T, Z, Y, X, 3), dtype=np.int16)  # numpy: t, z, y, x, c
raw = os.path.join(OUT, "rgbt.raw")
cxyzt.tofile(raw)
nrrd = os.path.join(OUT, "rgbt.nrrd")
p = subprocess.run([UNU, "make", "-i", raw, "-t", "short", "-s", "3", str(X), str(Y), str(Z),
                    str(T), "-k", "RGB-color", "space", "space", "space", "time", "-e", "raw",
                    "-en", "little", "-o", nrrd], capture_output=True, text=True)
check(p.returncode == 0, f"unu make: {p.stderr.strip()}")
for t, c in ((3, 1), (1, 2)):
    got = read_back(nrrd, c, t)
    if got is not None:
        check(np.array_equal(got, cxyzt[t, :, :, :, c]), f"NRRD RGB-color channel {c} time {t}: voxels")
# two time axes: refused in one line
bad_nrrd = os.path.join(OUT, "twotime.nrrd")
subprocess.run([UNU, "make", "-i", raw, "-t", "short", "-s", "3", str(X), str(Y), str(Z),
                str(T), "-k", "time", "space", "space", "space", "time", "-e", "raw", "-en",
                "little", "-o", bad_nrrd], check=True, capture_output=True)
refused(["convert", bad_nrrd, os.path.join(OUT, "bad.nii"), "-q"], "both time axes",
        os.path.join(OUT, "bad.nii"), "NRRD with two time axes")

# VTK legacy with a 3-component SCALARS array, written by VTK's own writer
# (binary, big-endian) and as ASCII: each component is a channel
try:
    import vtk
    from vtk.util import numpy_support
except ImportError:  # pragma: no cover
    vtk = None
    check(False, "python3-vtk9 is missing: VTK multi-component channels not checked")
if vtk is not None:
    zyxc = rng.integers(0, 60000, size=(Z, Y, X, 3), dtype=np.uint16)
    im = vtk.vtkImageData()
    im.SetDimensions(X, Y, Z)
    im.SetSpacing(0.5, 0.5, 2.0)
    arr = numpy_support.numpy_to_vtk(zyxc.reshape(-1, 3), deep=1,
                                     array_type=vtk.VTK_UNSIGNED_SHORT)
    arr.SetName("rgb")
    im.GetPointData().SetScalars(arr)
    for mode in ("binary", "ascii"):
        vtkf = os.path.join(OUT, f"three_{mode}.vtk")
        w = vtk.vtkStructuredPointsWriter()
        w.SetInputData(im)
        w.SetFileName(vtkf)
        if mode == "binary":
            w.SetFileTypeToBinary()
        else:
            w.SetFileTypeToASCII()
        w.Write()
        for c in (0, 2):
            got = read_back(vtkf, c, 0)
            if got is not None:
                check(np.array_equal(got, zyxc[..., c]), f"VTK {mode} component {c}: voxels")
    p = volvis("info", os.path.join(OUT, "three_binary.vtk"))
    check("channels:     3 (this is channel 0)" in p.stdout.splitlines(),
          f"info: VTK with 3 components lists 3 channels: {p.stdout.strip()[-200:]}")
    refused(["convert", os.path.join(OUT, "three_ascii.vtk"), os.path.join(OUT, "bad.nii"),
             "--channel", "3", "-q"], "channel 3", os.path.join(OUT, "bad.nii"),
            "VTK component past the file's")

    # VTK XML image data (.vti) by vtkXMLImageDataWriter: every data mode
    # (ascii, inline base64, appended raw or base64), zlib or none, either
    # byte order; i16 with 3 named components, a direction matrix and an
    # extent that does not start at 0
    i16 = rng.integers(-3000, 3000, size=(Z, Y, X, 3), dtype=np.int16)
    im = vtk.vtkImageData()
    im.SetExtent(2, X + 1, 0, Y - 1, -1, Z - 2)
    im.SetSpacing(0.5, 0.75, 2.0)
    im.SetOrigin(1, 2, 3)
    im.SetDirectionMatrix(0, -1, 0, 1, 0, 0, 0, 0, 1)
    arr = numpy_support.numpy_to_vtk(i16.reshape(-1, 3), deep=1, array_type=vtk.VTK_SHORT)
    arr.SetName("stains")
    for c, nm in enumerate(("nuclei", "membrane", "protein")):
        arr.SetComponentName(c, nm)
    im.GetPointData().SetScalars(arr)
    modes = {"ascii": ("ascii", True, False, False), "base64_zlib": ("binary", True, False, False),
             "base64_raw": ("binary", False, False, False),
             "appended_zlib": ("appended", True, False, False),
             "appended_raw": ("appended", False, True, False),
             "appended_be": ("appended", True, True, True)}
    for mode, (dm, zlib, raw, be) in modes.items():
        vti = os.path.join(OUT, f"stains_{mode}.vti")
        w = vtk.vtkXMLImageDataWriter()
        w.SetInputData(im)
        w.SetFileName(vti)
        {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
         "appended": w.SetDataModeToAppended}[dm]()
        if not zlib:
            w.SetCompressorTypeToNone()
        if raw:
            w.EncodeAppendedDataOff()
        if be:
            w.SetByteOrderToBigEndian()
        w.Write()
        # both ends of the components in two modes, one in the others (each
        # read back is a convert: the suite's time under the sanitizers)
        for c in (0, 2) if mode in ("ascii", "appended_be") else (len(mode) % 2 * 2,):
            got = read_back(vti, c, 0)
            if got is not None:
                check(np.array_equal(got, i16[..., c]), f"VTI {mode} component {c}: voxels")
    p = volvis("info", os.path.join(OUT, "stains_appended_zlib.vti"))
    lines = p.stdout.splitlines()
    check("channels:     3 (this is channel 0)" in lines and
          any('"membrane"' in ln for ln in lines) and
          "direction:    [0 -1 0; 1 0 0; 0 0 1] (columns: i, j, k axes)" in lines and
          "spacing:      0.5 x 0.75 x 2" in lines,
          f"info VTI: 3 named channels, direction, spacing ({p.stderr.strip()})")
    # the extent's first point (2, 0, -1) is the volume's origin
    check(any(ln.split() == ["origin:", "1", "3", "1"] for ln in lines),
          f"info VTI: origin at the extent's first point ({[ln for ln in lines if 'origin' in ln]})")
    # a round trip through VolVis' own writer
    back = os.path.join(OUT, "stains_back.vti")
    p = volvis("convert", os.path.join(OUT, "stains_ascii.vti"), back, "--channel", "1", "-q")
    got = read_back(back, 0, 0) if p.returncode == 0 else None
    check(got is not None and np.array_equal(got, i16[..., 1]),
          f"VTI written by volvis reads back ({p.stderr.strip()})")
    # bad files: one line naming the file and the problem, no output
    good = open(os.path.join(OUT, "stains_appended_raw.vti"), "rb").read()
    bads = {"truncated": good[: len(good) // 2],
            "bomb": good.replace(b"<VTKFile", b'<!DOCTYPE x [<!ENTITY a "aaaa">]>\n<VTKFile', 1),
            "extent": good.replace(b'WholeExtent="2', b'WholeExtent="9', 1),
            "type": good.replace(b'type="Int16"', b'type="Int64"', 1)}
    needles = {"truncated": "stains_bad_truncated.vti", "bomb": "entity",
               "extent": "Extent", "type": "Int64"}
    for k, data in bads.items():
        path = os.path.join(OUT, f"stains_bad_{k}.vti")
        open(path, "wb").write(data)
        refused(["convert", path, os.path.join(OUT, "bad.nii"), "-q"], needles[k],
                os.path.join(OUT, "bad.nii"), f"VTI {k}")
    refused(["convert", os.path.join(OUT, "stains_base64_raw.vti"), os.path.join(OUT, "bad.nii"),
             "--channel", "3", "-q"], "channel 3", os.path.join(OUT, "bad.nii"),
            "VTI component past the file's")

# A cardiac cine series (pydicom): T phases at each of Z positions along an
# oblique normal, one MR image a file, written in a shuffled order. Each
# step reads as numpy wrote it, sorted along the normal; info lists the
# series as Z slices x T time steps and says the steps are 40 ms apart; a step past them and a series whose positions hold unequal
# numbers of images are one-line errors.
MR_STORAGE = "1.2.840.10008.5.1.4.1.1.4"
cine = os.path.join(OUT, "cine")
shutil.rmtree(cine, ignore_errors=True)
os.makedirs(cine)
tzyx = rng.integers(0, 4000, size=(T, Z, Y, X), dtype=np.uint16)
series_uid, study_uid, frame_uid = generate_uid(), generate_uid(), generate_uid()
row, col = np.array([1.0, 0, 0]), np.array([0, 0.8, -0.6])
normal = np.cross(row, col)
order = rng.permutation(T * Z)
for n, idx in enumerate(order):
    t, z = int(idx % T), int(idx // T)
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = MR_STORAGE
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    path = os.path.join(cine, f"im{n:03d}.dcm")
    ds = FileDataset(path, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = MR_STORAGE, meta.MediaStorageSOPInstanceUID
    ds.StudyInstanceUID, ds.SeriesInstanceUID = study_uid, series_uid
    ds.FrameOfReferenceUID, ds.Modality, ds.SeriesNumber = frame_uid, "MR", 7
    ds.InstanceNumber = int(n + 1)  # shuffled: not the time order
    ds.TriggerTime = f"{40 * t:.1f}"
    ds.TemporalPositionIdentifier = t + 1
    ds.ImageOrientationPatient = [f"{v:.6f}" for v in (*row, *col)]
    ds.ImagePositionPatient = [f"{v:.6f}" for v in (np.array([-20.0, 5, 30]) + 2.5 * z * normal)]
    ds.PixelSpacing = ["1.25", "0.75"]
    ds.SliceThickness = "2.5"
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.Rows, ds.Columns = Y, X
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 0
    ds.PixelData = tzyx[t, z].tobytes()
    ds.save_as(path, write_like_original=False)
for t in (0, 2, 3):
    got = read_back(cine, 0, t)
    if got is not None:
        check(np.array_equal(got, tzyx[t]), f"DICOM cine phase {t}: voxels")
p = volvis("info", cine, "--time", "1")
check(p.returncode == 0 and "time steps:   4 (this is step 1), 0.04 s apart" in
      p.stdout.splitlines(), f"info DICOM cine: 4 steps 40 ms apart ({p.stderr.strip()})")
# the listing counts the slices of one step and names the steps
want = f'#7 MR "" {X} x {Y} x {Z} x {T} time steps ({T * Z} files)'
check(any(line.endswith(want) for line in p.stdout.splitlines()),
      f"info DICOM cine: the series listed as {want} ({p.stdout.splitlines()[:2]})")
refused(["convert", cine, os.path.join(OUT, "cine_bad.nii"), "--time", "4", "-q"],
        "time step 4 asked, the series has 4", os.path.join(OUT, "cine_bad.nii"),
        "DICOM cine: a step past the series")
os.remove(os.path.join(cine, "im000.dcm"))
refused(["convert", cine, os.path.join(OUT, "cine_bad.nii"), "-q"], "same position",
        os.path.join(OUT, "cine_bad.nii"), "DICOM cine with an image missing")

# volvis info: the counts, names, colours, ranges and the time increment
p = volvis("info", ome, "--time", "2")
lines = p.stdout.splitlines()
check(p.returncode == 0, f"volvis info OME-TIFF: {p.stderr.strip()}")
check("channels:     3 (this is channel 0)" in lines, "info: 3 channels")
for c, (name, colour) in enumerate((("DAPI", "#ff0000"), ("GFP", "#00ff00"),
                                    ("mCherry", "#0000ff"))):
    want = (f"  channel {c:<3d} \"{name}\" {colour} range {tczyx[2, c].min()} .. "
            f"{tczyx[2, c].max()}")
    check(want in lines, f"info: {want.strip()}")
check("time steps:   4 (this is step 2), 0.5 s apart" in lines, "info: 4 time steps, 0.5 s")
p = volvis("info", ij)
lines = p.stdout.splitlines()
for c, colour in enumerate(("#ffff00", "#00ffff")):
    check(any(ln.startswith(f"  channel {c:<3d} {colour} range") for ln in lines),
          f"info: ImageJ LUT of channel {c} is {colour}")
check(any(ln.startswith("  channel 2   range") for ln in lines),
      "info: ImageJ's grey LUT gives no colour (the default set)")
# an RGB TIFF (tifffile, photometric RGB) and a NRRD axis of kind
# RGB-color: their samples are red, green and blue
rgb_tif = os.path.join(OUT, "rgb.tif")
tifffile.imwrite(rgb_tif, rng.integers(0, 255, size=(Z, Y, X, 3), dtype=np.uint8),
                 photometric="rgb")
for path in (rgb_tif, nrrd):
    p = volvis("info", path)
    lines = p.stdout.splitlines()
    for c, colour in enumerate(("#ff0000", "#00ff00", "#0000ff")):
        check(any(ln.startswith(f"  channel {c:<3d} {colour} range") for ln in lines),
              f"info {os.path.basename(path)}: sample {c} is {colour} ({p.stderr.strip()})")
p = volvis("info", five)
check("time steps:   4 (this is step 0), 0.25 s apart" in p.stdout.splitlines() and
      "channels:     3 (this is channel 0)" in p.stdout.splitlines(),
      f"info 5-D NIfTI: channels and steps 0.25 s apart ({p.stderr.strip()})")

# render --channels C takes the file's colour: blue mCherry, a MIP
png = os.path.join(OUT, "blue.png")
p = volvis("render", ome, "--channels", "2", "--blend", "maximum", "--time", "1", "-o", png,
           "--size", "64x64", "--ortho", "-q")
check(p.returncode == 0, f"render --channels 2: {p.stderr.strip()}")
if p.returncode == 0:
    im = np.asarray(Image.open(png).convert("RGB")).astype(int)
    check(im[..., 2].max() > 100 and im[..., 0].max() == 0 and im[..., 1].max() == 0,
          f"render --channels 2 is blue (max R G B {im[..., 0].max()} {im[..., 1].max()} "
          f"{im[..., 2].max()})")

# render --time-range: each step's PNG equals the render of --time T alone
# (with the transfer function given: else the range's first step's is used
# for all); channels too
for extra in (("--tf", "500:3500"),
              ("--channels", "0,2", "--blend", "maximum", "--contrast", "500:3500,900:3900")):
    base = os.path.join(OUT, "range" + ("_ch" if extra else "") + ".png")
    p = volvis("render", ome, "--time-range", "1:3:2", *extra, "-o", base, "--size", "48x48",
               "--ortho", "-q")
    check(p.returncode == 0, f"render --time-range 1:3:2 {' '.join(extra)}: {p.stderr.strip()}")
    for t in (1, 3):
        step = base[:-4] + f"_t{t:04d}.png"
        one = os.path.join(OUT, "one.png")
        # --time-range computes gradients at the samples drawn (each step is
        # drawn once), as gradient_budget_mb=0 does
        q = volvis("render", ome, "--time", str(t), *extra, "-o", one, "--size", "48x48",
                   "--ortho", "-q", "--set", "gradient_budget_mb=0")
        if p.returncode or q.returncode or not os.path.exists(step):
            check(False, f"render --time {t} {' '.join(extra)}: {q.stderr.strip()}")
            continue
        same = np.array_equal(np.asarray(Image.open(step)), np.asarray(Image.open(one)))
        check(same and not os.path.exists(base[:-4] + "_t0002.png"),
              f"--time-range step {t} {' '.join(extra)} equals --time {t}; step 2 skipped")
refused(["render", ome, "--time-range", "2:7", "-o", os.path.join(OUT, "r.png")],
        "the file has 4 time steps", os.path.join(OUT, "r_t0002.png"), "render --time-range 2:7")

# volvis animate with an objects[0].time track: frame k shows step k, equal
# to the render of --time k (the transfer function given, gradients at the
# samples as --time-range); a key past the file's steps is an error
anim = os.path.join(OUT, "time.json")
with open(anim, "w") as f:
    f.write('{"fps": 1, "duration": 4, "tracks": [{"property": "objects[0].time", '
            '"interpolation": "linear", "keys": [{"time": 0, "value": 0}, '
            '{"time": 3, "value": 3}]}]}')
frames = os.path.join(OUT, "frames")
shutil.rmtree(frames, ignore_errors=True)
os.makedirs(frames)
same_args = ("--size", "40x40", "--ortho", "--tf", "500:3500", "--set", "gradient_budget_mb=0")
p = volvis("animate", ome, "--animation", anim, "-o", os.path.join(frames, "f_%02d.png"), "-q",
           *same_args)
check(p.returncode == 0, f"animate with a time track: {p.stderr.strip()}")
if p.returncode == 0:
    images = [np.asarray(Image.open(os.path.join(frames, f"f_{t:02d}.png"))) for t in range(4)]
    for t in (1, 3):
        one = os.path.join(OUT, f"anim_one_{t}.png")
        volvis("render", ome, "--time", str(t), "-o", one, "-q", *same_args)
        check(np.array_equal(images[t], np.asarray(Image.open(one))),
              f"animate time track: frame {t} equals --time {t}")
    check(not np.array_equal(images[0], images[3]), "animate time track: frames 0 and 3 differ")
with open(anim, "w") as f:
    f.write('{"fps": 1, "duration": 2, "tracks": [{"property": "objects[0].time", '
            '"keys": [{"time": 0, "value": 0}, {"time": 1, "value": 9}]}]}')
refused(["animate", ome, "--animation", anim, "-o", os.path.join(frames, "g_%02d.png"), "-q",
         "--size", "16x16"], "time step 9 asked, it has 4", os.path.join(frames, "g_01.png"),
        "animate: a time key past the file's steps")

# scene files: a volume object's "time" draws that step of the file (the
# same image as a scene of the step alone, written by volvis convert --time);
# with "channels" each channel's step; a step past the file's names the key
step2 = os.path.join(OUT, "step2.ome.tif")
p = volvis("convert", ome, step2, "--time", "2", "-q")
check(p.returncode == 0, f"convert --time 2 to OME-TIFF: {p.stderr.strip()}")


def scene_png(name, body):
    scene = os.path.join(OUT, name + ".json")
    with open(scene, "w") as f:
        f.write('{"objects": [%s]}' % body)
    png = os.path.join(OUT, name + ".png")
    q = volvis("render", scene, "-o", png, "-q", "--size", "40x40", "--ortho")
    if q.returncode:
        check(False, f"scene {name}: {q.stderr.strip()}")
        return None
    return np.asarray(Image.open(png))


one_tf = '"transfer_function": {"opacity": [[500, 0], [3500, 0.5]]}'
a = scene_png("scene_t2", '{"type": "volume", "file": "cells.ome.tif", "time": 2, %s}' % one_tf)
b = scene_png("scene_step2", '{"type": "volume", "file": "step2.ome.tif", %s}' % one_tf)
c0 = scene_png("scene_t0", '{"type": "volume", "file": "cells.ome.tif", %s}' % one_tf)
if a is not None and b is not None and c0 is not None:
    check(np.array_equal(a, b) and not np.array_equal(a, c0),
          'scene "time": 2 equals a scene of step 2 alone, not of step 0')
chans = ', "blend": "maximum", "channels": [{"channel": 0}, {"channel": 2}]'
a = scene_png("scene_tc2", '{"type": "volume", "file": "cells.ome.tif", "time": 2%s}' % chans)
c0 = scene_png("scene_tc0", '{"type": "volume", "file": "cells.ome.tif"%s}' % chans)
if a is not None and c0 is not None:
    check(not np.array_equal(a, c0), 'scene "time": 2 with "channels" draws step 2, not 0')
# volvis animate of a scene (the GUI's saved session) with an objects[0].time
# track: frame 2 draws each channel's step 2 of the object's own file, as
# the scene with "time": 2 does
anim2 = os.path.join(OUT, "time2.json")
with open(anim2, "w") as f:
    f.write('{"fps": 1, "duration": 3, "tracks": [{"property": "objects[0].time", '
            '"interpolation": "linear", "keys": [{"time": 0, "value": 0}, '
            '{"time": 2, "value": 2}]}]}')
# (transfer functions given: a scene's default ones come from its step's
# quantiles, while a track keeps those of the step it starts from)
grad = ("--size", "40x40", "--ortho", "--set", "gradient_budget_mb=0")
tfc = '{"opacity": [[500, 0], [3500, 0.5]], "color": [[0, [1, 0, 1]]]}'
for name, t in (("scene_anim0", 0), ("scene_anim2", 2)):
    with open(os.path.join(OUT, name + ".json"), "w") as f:
        f.write('{"objects": [{"type": "volume", "file": "cells.ome.tif", "time": %d, '
                '"blend": "maximum", "channels": [{"channel": 0, "transfer_function": %s}, '
                '{"channel": 2, "transfer_function": %s}]}]}' % (t, tfc, tfc))
p = volvis("animate", os.path.join(OUT, "scene_anim0.json"), "--animation", anim2, "-o",
           os.path.join(frames, "s_%02d.png"), "-q", *grad)
check(p.returncode == 0, f"animate a scene with a time track: {p.stderr.strip()}")
q = volvis("render", os.path.join(OUT, "scene_anim2.json"), "-o", os.path.join(OUT, "tc2g.png"),
           "-q", *grad)
if p.returncode == 0 and q.returncode == 0:
    s2 = np.asarray(Image.open(os.path.join(frames, "s_02.png")))
    s0 = np.asarray(Image.open(os.path.join(frames, "s_00.png")))
    check(np.array_equal(s2, np.asarray(Image.open(os.path.join(OUT, "tc2g.png")))) and
          not np.array_equal(s2, s0),
          'animate a scene: frame 2 of the time track equals the scene with "time": 2')
bad = os.path.join(OUT, "scene_bad.json")
with open(bad, "w") as f:
    f.write('{"objects": [{"type": "volume", "file": "cells.ome.tif", "time": 9}]}')
refused(["render", bad, "-o", os.path.join(OUT, "scene_bad.png"), "-q"],
        "scene_bad.json:1:58: objects[0].time: tiff:", os.path.join(OUT, "scene_bad.png"),
        'scene "time": 9 on 4 steps')

# a big-endian 4-D NIfTI by nibabel: --time-range reads steps after the
# first by offset (vv_time_series' raw layout, bytes swapped here); each
# step's image equals the render of --time T read by nifti_clib
big = os.path.join(OUT, "big_endian.nii")
series = (rng.random((X, Y, Z, 5)) * 3000).astype(">u2")
nib.save(nib.Nifti1Image(series, np.eye(4), header=nib.Nifti1Header(endianness=">")), big)
check(nib.load(big).header.endianness == ">", "nibabel wrote a big-endian NIfTI")
base = os.path.join(OUT, "big.png")
for t in range(5):
    if os.path.exists(base[:-4] + f"_t{t:04d}.png"):
        os.remove(base[:-4] + f"_t{t:04d}.png")
p = volvis("render", big, "--time-range", "0:4:4", "-o", base, "-q", *same_args)
check(p.returncode == 0, f"render --time-range on a big-endian NIfTI: {p.stderr.strip()}")
for t in (4,):
    one = os.path.join(OUT, f"big_one_{t}.png")
    q = volvis("render", big, "--time", str(t), "-o", one, "-q", *same_args)
    step = base[:-4] + f"_t{t:04d}.png"
    check(q.returncode == 0 and os.path.exists(step) and
          np.array_equal(np.asarray(Image.open(step)), np.asarray(Image.open(one))),
          f"big-endian NIfTI: --time-range step {t} equals --time {t}")

# colocalisation against numpy: Pearson's r and Manders' M1, M2 within a
# mask written by nibabel, with thresholds; a channel's histogram at a step
mask_xyz = (rng.random((X, Y, Z)) < 0.6).astype(np.uint8)
mask = os.path.join(OUT, "mask.nii")
nib.save(nib.Nifti1Image(mask_xyz, np.eye(4)), mask)
inside = mask_xyz.transpose(2, 1, 0).astype(bool)
p = volvis("measure", ome, "--coloc", "0,2", "--time", "3", "--mask", mask, "--thresholds",
           "1200,800", "--json")
check(p.returncode == 0, f"measure --coloc: {p.stderr.strip()}")
if p.returncode == 0:
    import json
    got = json.loads(p.stdout)
    a, b = tczyx[3, 0][inside].astype(float), tczyx[3, 2][inside].astype(float)
    both = (a > 1200) & (b > 800)
    want = {"voxels": int(inside.sum()), "pearson": np.corrcoef(a, b)[0, 1],
            "manders_m1": a[both].sum() / a[a > 1200].sum(),
            "manders_m2": b[both].sum() / b[b > 800].sum()}
    for key, value in want.items():
        check(abs(got[key] - value) <= 1e-9 * max(1, abs(value)),
              f"measure --coloc {key}: {got[key]} against numpy {value}")
p = volvis("measure", ome, "--channel", "1", "--time", "2", "--histogram", "--bins", "4",
           "--range", "0:4000", "--json")
if p.returncode == 0:
    import json
    counts = json.loads(p.stdout)["histogram"]["counts"]
    want = np.histogram(tczyx[2, 1], bins=4, range=(0, 4000))[0].tolist()
    check(counts == want, f"measure --channel 1 --time 2 --histogram: {counts} against {want}")
else:
    check(False, f"measure --channel 1 --histogram: {p.stderr.strip()}")
refused(["measure", ome, "--coloc", "0,3"], "channel 3 asked, the stack has 3",
        os.path.join(OUT, "none"), "measure --coloc 0,3 on 3 channels")
small = os.path.join(OUT, "small_mask.nii")
nib.save(nib.Nifti1Image(mask_xyz[:, :, :-1], np.eye(4)), small)
refused(["measure", ome, "--coloc", "0,1", "--mask", small], "mask is 11 x 14 x 5",
        os.path.join(OUT, "none"), "measure --coloc with a mask of another size")

# bad input
out_nii = os.path.join(OUT, "refused.nii")
refused(["convert", ome, out_nii, "--time", "4", "-q"], "time step 4 asked, the stack has 4",
        out_nii, "OME-TIFF --time 4")
refused(["convert", five, out_nii, "--channel", "3", "-q"], "channel 3 asked, the file has 3",
        out_nii, "NIfTI --channel 3")
refused(["convert", nrrd, out_nii, "--time", "9", "-q"], "time step 9 asked, the file has 4",
        out_nii, "NRRD --time 9")
head = "../shared/data/volumes/ct_head.nrrd"
if os.path.exists(head):
    refused(["convert", head, out_nii, "--time", "1", "-q"], "time step 1 asked, the file has 1",
            out_nii, "3-D NRRD --time 1")
slc = "../shared/data/volumes/nut.slc"
if os.path.exists(slc):
    refused(["info", slc, "--time", "1"], "the file has 1 time step", out_nii,
            "SLC --time 1 (no time axis)")

print(f"{len(failures)} failed" if failures else "all passed")
sys.exit(1 if failures else 0)
