#!/usr/bin/python3
"""The volume and mesh writers read back by independent readers (issue 34).

  writers_independent.py VOLVIS OUTDIR SOURCE_DIR

Writes, with numpy only, a raw NRRD of every voxel type with an oblique
direction, an origin and anisotropic spacing in LPS, converts it with
`volvis convert` to NIfTI (.nii, .nii.gz, NIfTI-2), MetaImage (.mha, .mhd),
VTK legacy (.vtk), VTK XML image data (.vti), TIFF (.tif with ImageJ's
keys, .ome.tif; every codec, BigTIFF) and OME-Zarr (a pyramid), and reads
each back with nibabel, VTK's readers, tifffile or zarr-python: voxels equal, affine / spacing / origin /
direction equal to what was written (NIfTI's RAS is LPS with x and y
negated). An oblique DICOM series (written by scripts/dicom_testdata.py with
pydicom) converted to NIfTI lands where its Image Position (Patient) says in
nibabel. An isosurface written as .vtp has the area `volvis isosurface`
reports by vtkMassProperties, normals and the same counts; as .glb (parsed
here: a JSON chunk and a binary chunk) the same triangle count and bounds.
Exit 0 passed, 1 failed, 77 skipped (a module missing).
"""
import json
import os
import re
import struct
import subprocess
import sys

try:
    import numpy as np
    import nibabel as nib
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    import pydicom
    import tifffile
    import zarr
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-numpy, python3-nibabel, python3-vtk9, python3-pydicom, "
          "python3-tifffile, python3-zarr)")
    sys.exit(77)

VOLVIS, OUT, SRC = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(OUT, exist_ok=True)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def run(*args):
    p = subprocess.run([VOLVIS, *args], capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"FAIL volvis {' '.join(args)}: {p.stderr.strip()}")
    return p.stdout + p.stderr


TYPES = {"u8": ("uint8", "unsigned char"), "i8": ("int8", "signed char"),
         "u16": ("uint16", "unsigned short"), "i16": ("int16", "short"),
         "u32": ("uint32", "unsigned int"), "i32": ("int32", "int"),
         "f32": ("float32", "float"), "f64": ("float64", "double")}
DIMS = (13, 7, 5)  # i, j, k
SPACING = np.array([0.7, 1.1, 2.3])
ORIGIN = np.array([-5.0, 7.0, 11.0])  # LPS
a, b = 0.3, -0.2
RZ = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
RX = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
DIRECTION = RX @ RZ  # columns: the world directions of i, j, k
LPS2RAS = np.diag([-1.0, -1.0, 1.0])


def write_nrrd(path, arr, ntype, direction=DIRECTION, units=False):
    """arr indexed [k, j, i] (C order: i fastest), as NRRD's raw data."""
    cols = [direction[:, c] * SPACING[c] for c in range(3)]
    vec = " ".join("(%s)" % ",".join(repr(float(x)) for x in c) for c in cols)
    hdr = ("NRRD0004\ntype: %s\ndimension: 3\nspace: left-posterior-superior\n"
           "sizes: %d %d %d\nspace directions: %s\nspace origin: (%s)\n%s"
           "endian: little\nencoding: raw\n\n" %
           (ntype, *DIMS, vec, ",".join(repr(float(x)) for x in ORIGIN),
            'space units: "mm" "mm" "mm"\n' if units else ""))
    with open(path, "wb") as f:
        f.write(hdr.encode())
        f.write(arr.astype(arr.dtype.newbyteorder("<")).tobytes())


def vtk_image(reader_cls, path):
    r = reader_cls()
    r.SetFileName(path)
    r.Update()
    o = r.GetOutput()
    nx, ny, nz = o.GetDimensions()
    a = vtk_to_numpy(o.GetPointData().GetScalars()).reshape(nz, ny, nx)
    return o, a


rng = np.random.default_rng(34)


def random_array(dt):
    """DIMS voxels of type dt, [k, j, i]: integers over the type's whole
    range, floats of a wide spread."""
    if dt[0] in "ui":
        info = np.iinfo(dt)
        return rng.integers(info.min, info.max, size=DIMS[::-1], dtype=dt, endpoint=True)
    return (rng.standard_normal(DIMS[::-1]) * 1e5).astype(dt)


lps_affine = np.eye(4)
lps_affine[:3, :3] = DIRECTION * SPACING
lps_affine[:3, 3] = ORIGIN
for name, (dt, ntype) in TYPES.items():
    arr = random_array(dt)
    src = os.path.join(OUT, f"src_{name}.nrrd")
    write_nrrd(src, arr, ntype)
    # NIfTI through nibabel: voxels, affine (RAS), codes
    for ext, extra in ((".nii", []), (".nii.gz", []), ("_2.nii", ["--nifti2"])):
        dst = os.path.join(OUT, f"w_{name}{ext}")
        run("convert", src, dst, "--quiet", *extra)
        img = nib.load(dst)
        data = np.asanyarray(img.dataobj)
        check(data.dtype == np.dtype(dt) and np.array_equal(data, arr.transpose(2, 1, 0)),
              f"nibabel {name}{ext}: voxels and type equal")
        want = np.diag([-1.0, -1.0, 1.0, 1.0]) @ lps_affine
        tol = 1e-12 if extra else 1e-5  # NIfTI-1 stores float32
        check(np.allclose(img.affine, want, atol=tol), f"nibabel {name}{ext}: affine (RAS)")
        hdr = img.header
        check(int(hdr["sform_code"]) == 1 and int(hdr["qform_code"]) == 1,
              f"nibabel {name}{ext}: sform and qform codes 1 (scanner)")
        check(np.allclose(img.get_qform(), want, atol=1e-4), f"nibabel {name}{ext}: qform")
        check(isinstance(img, nib.Nifti2Image) == bool(extra), f"nibabel {name}{ext}: version")
    # MetaImage, VTK legacy, .vti through VTK's readers
    for ext, cls in ((".mha", vtk.vtkMetaImageReader), (".mhd", vtk.vtkMetaImageReader),
                     (".vtk", vtk.vtkStructuredPointsReader),
                     (".vti", vtk.vtkXMLImageDataReader)):
        dst = os.path.join(OUT, f"w_{name}{ext}")
        run("convert", src, dst, "--quiet")
        o, data = vtk_image(cls, dst)
        check(data.dtype == np.dtype(dt) and np.array_equal(data, arr),
              f"VTK {name}{ext}: voxels and type equal")
        check(np.allclose(o.GetSpacing(), SPACING, atol=1e-12), f"VTK {name}{ext}: spacing")
        check(np.allclose(o.GetOrigin(), ORIGIN, atol=1e-12), f"VTK {name}{ext}: origin")
        if ext == ".vti":
            m = o.GetDirectionMatrix()
            d = np.array([[m.GetElement(r, c) for c in range(3)] for r in range(3)])
            check(np.allclose(d, DIRECTION, atol=1e-12), f"VTK {name}{ext}: direction")

# TIFF through tifffile: an axis-aligned source in millimetres (TIFF holds
# no direction). OME-TIFF: axes, pixel type, physical sizes and units, the
# planes' positions; ImageJ: slices, spacing, unit, origin, X/YResolution.
# LZW and zstd need imagecodecs, which Debian 12 lacks: for them the
# compression tag is read here and the voxels by VolVis (test_io_writers).
import xml.etree.ElementTree as ET
OME_NS = {"o": "http://www.openmicroscopy.org/Schemas/OME/2016-06"}
for name, (dt, ntype) in TYPES.items():
    arr = random_array(dt)
    src = os.path.join(OUT, f"tsrc_{name}.nrrd")
    write_nrrd(src, arr, ntype, direction=np.eye(3), units=True)
    ome = os.path.join(OUT, f"w_{name}.ome.tif")
    run("convert", src, ome, "--quiet")
    with tifffile.TiffFile(ome) as t:
        ser = t.series[0]
        check(t.is_ome and ser.axes == "ZYX" and ser.dtype == np.dtype(dt) and
              np.array_equal(ser.asarray(), arr), f"tifffile {name}.ome.tif: axes ZYX, voxels")
        px = ET.fromstring(t.ome_metadata).find(".//o:Pixels", OME_NS)
        planes = px.findall("o:Plane", OME_NS)
        sizes = [float(px.get(f"PhysicalSize{a}")) for a in "XYZ"]
        check(np.allclose(sizes, SPACING, rtol=1e-15) and
              all(px.get(f"PhysicalSize{a}Unit") == "mm" for a in "XYZ"),
              f"tifffile {name}.ome.tif: physical sizes in mm")
        pos = [[float(p.get(f"Position{a}")) for a in "XYZ"] for p in planes]
        want = [ORIGIN + [0, 0, k * SPACING[2]] for k in range(DIMS[2])]
        check(len(planes) == DIMS[2] and np.allclose(pos, want, atol=1e-12) and
              px.find("o:Channel", OME_NS) is not None,
              f"tifffile {name}.ome.tif: a channel and a plane per slice at its position")
    ij = os.path.join(OUT, f"w_{name}.tif")
    run("convert", src, ij, "--quiet")
    with tifffile.TiffFile(ij) as t:
        md = t.imagej_metadata or {}
        check(t.is_imagej and np.array_equal(t.asarray(), arr) and md.get("slices") == DIMS[2],
              f"tifffile {name}.tif: ImageJ stack, voxels")
        xr = t.pages[0].tags["XResolution"].value
        yr = t.pages[0].tags["YResolution"].value
        check(abs(xr[1] / xr[0] - SPACING[0]) < 1e-6 and abs(yr[1] / yr[0] - SPACING[1]) < 1e-6
              and abs(md.get("spacing", 0) - SPACING[2]) < 1e-12 and md.get("unit") == "mm",
              f"tifffile {name}.tif: X/YResolution, spacing and unit")
        org = [-md.get(f"{a}origin", 0) * SPACING[i] for i, a in enumerate("xyz")]
        check(np.allclose(org, ORIGIN, atol=1e-9), f"tifffile {name}.tif: origin (in voxels)")
src = os.path.join(OUT, "tsrc_i16.nrrd")
for codec, tag in (("deflate", 8), ("packbits", 32773), ("none", 1), ("lzw", 5),
                   ("zstd", 50000)):
    dst = os.path.join(OUT, f"codec_{codec}.tif")
    run("convert", src, dst, "--quiet", "--codec", codec)
    with tifffile.TiffFile(dst) as t:
        ok = all(p.compression == tag for p in t.pages)
        if tag in (8, 32773, 1):
            ok &= np.array_equal(t.asarray(), tifffile.imread(os.path.join(OUT, "w_i16.tif")))
        check(ok, f"tifffile --codec {codec}: compression {tag} on every page" +
              (", voxels" if tag in (8, 32773, 1) else ""))
dst = os.path.join(OUT, "big.ome.tif")
run("convert", src, dst, "--quiet", "--bigtiff")
with tifffile.TiffFile(dst) as t:
    check(t.is_bigtiff and t.is_ome and np.array_equal(t.asarray(), tifffile.imread(
        os.path.join(OUT, "w_i16.ome.tif"))), "tifffile --bigtiff: BigTIFF, OME, voxels")
p = subprocess.run([VOLVIS, "convert", os.path.join(OUT, "src_u8.nrrd"),
                    os.path.join(OUT, "warn.ome.tif")], capture_output=True, text=True)
check(p.returncode == 0 and "warning" in p.stderr and "direction" in p.stderr,
      "OME-TIFF of an oblique volume: a warning names the direction matrix")

# OME-Zarr through zarr-python: a pyramid of a 150 x 70 x 40 volume (levels
# 150 x 70 x 40, 75 x 35 x 20, 38 x 18 x 10), every voxel type; level 0
# equals the voxels, level 1 numpy's 2x2x2 mean (the partial blocks of odd
# axes averaged over what is inside; integers rounded half up), labels the
# first voxel of each block; scale and translation of each level, axes and
# unit, the zlib compressor and 64^3 chunks.
def mean_down(x):
    """2x2x2 means of x [k, j, i] over the voxels inside."""
    shape = [(n + 1) // 2 * 2 if n > 1 else 1 for n in x.shape]
    pad = np.zeros(shape)
    cnt = np.zeros(shape)
    pad[:x.shape[0], :x.shape[1], :x.shape[2]] = x
    cnt[:x.shape[0], :x.shape[1], :x.shape[2]] = 1
    f = [2 if n > 1 else 1 for n in x.shape]
    r = lambda a: a.reshape(shape[0] // f[0], f[0], shape[1] // f[1], f[1],  # noqa: E731
                            shape[2] // f[2], f[2]).sum(axis=(1, 3, 5))
    return r(pad) / r(cnt)


ZDIMS = (150, 70, 40)  # i, j, k
for name, (dt, ntype) in TYPES.items():
    if dt[0] in "ui":
        info = np.iinfo(dt)
        lo, hi = max(info.min, -100000), min(info.max, 100000)
        arr = rng.integers(lo, hi, size=ZDIMS[::-1], dtype=dt, endpoint=True)
    else:
        arr = (rng.standard_normal(ZDIMS[::-1]) * 1e3).astype(dt)
    src = os.path.join(OUT, f"zsrc_{name}.nrrd")
    cols = " ".join("(%s)" % ",".join(repr(float(x)) for x in np.eye(3)[:, c] * SPACING[c])
                    for c in range(3))
    with open(src, "wb") as f:
        f.write(("NRRD0004\ntype: %s\ndimension: 3\nspace: left-posterior-superior\n"
                 "sizes: %d %d %d\nspace directions: %s\nspace origin: (%s)\n"
                 'space units: "mm" "mm" "mm"\nendian: little\nencoding: raw\n\n' %
                 (ntype, *ZDIMS, cols, ",".join(repr(float(x)) for x in ORIGIN))).encode())
        f.write(arr.astype(arr.dtype.newbyteorder("<")).tobytes())
    for label in ([False, True] if dt[0] in "ui" else [False]):
        dst = os.path.join(OUT, f"w_{name}{'_label' if label else ''}.ome.zarr")
        # OME-NGFF 0.4 (Zarr v2) for Debian's zarr 2; 0.5: tests/io/zarr3_write_cli.py
        run("convert", src, dst, "--quiet", "--ngff", "0.4", *(["--label"] if label else []))
        g = zarr.open_group(dst, mode="r")
        ms = g.attrs["multiscales"][0]
        sets = ms["datasets"]
        tag = f"zarr {name}{' label' if label else ''}"
        check(ms["version"] == "0.4" and [a["name"] for a in ms["axes"]] == ["z", "y", "x"] and
              all(a.get("unit") == "millimeter" for a in ms["axes"]) and len(sets) == 3,
              f"{tag}: multiscales 0.4, axes z y x in millimeter, 3 levels")
        a0, a1 = g[sets[0]["path"]], g[sets[1]["path"]]
        check(a0.dtype == np.dtype(dt) and np.array_equal(a0[:], arr) and
              a0.chunks == (40, 64, 64) and a0.compressor.codec_id == "zlib",
              f"{tag}: level 0 voxels, chunks, zlib")
        if label:
            want = arr[::2, ::2, ::2]
        elif dt[0] == "f":
            want = mean_down(arr.astype(np.float64)).astype(dt)
        else:
            want = np.floor(mean_down(arr.astype(np.float64)) + 0.5).astype(dt)
        ok = a1.shape == want.shape and (np.allclose(a1[:], want, rtol=1e-6) if dt[0] == "f"
                                         else np.array_equal(a1[:], want))
        check(ok, f"{tag}: level 1 is the {'first voxel' if label else 'mean'} of each block")
        ok = True
        for l, d in enumerate(sets):
            tf = {t["type"]: t for t in d["coordinateTransformations"]}
            fac = np.array([2 ** l if n > 1 else 1 for n in ZDIMS[::-1]], dtype=float)
            sc = SPACING[::-1] * fac
            tr = ORIGIN[::-1] + (0 if label else 0.5 * (fac - 1) * SPACING[::-1])
            ok &= np.allclose(tf["scale"]["scale"], sc, rtol=1e-15)
            ok &= np.allclose(tf["translation"]["translation"], tr, atol=1e-12)
        check(ok, f"{tag}: scale and translation of every level")

# What a format cannot hold is a warning: the direction into legacy VTK
p = subprocess.run([VOLVIS, "convert", os.path.join(OUT, "src_u8.nrrd"),
                    os.path.join(OUT, "warn.vtk")], capture_output=True, text=True)
check(p.returncode == 0 and "warning" in p.stderr and "direction" in p.stderr,
      "legacy VTK of an oblique volume: a warning names the direction matrix")
p = subprocess.run([VOLVIS, "convert", "--strict", os.path.join(OUT, "src_u8.nrrd"),
                    os.path.join(OUT, "strict.vtk")], capture_output=True, text=True)
check(p.returncode != 0 and not os.path.exists(os.path.join(OUT, "strict.vtk")) and
      len(p.stderr.strip().splitlines()) == 1, "--strict: one-line error, no file")

# An oblique DICOM series as NIfTI lands where its positions say
ct = os.path.join(SRC, "..", "shared", "data", "volumes", "ct_head.nrrd")
series = os.path.join(OUT, "oblique_series")
subprocess.run([sys.executable, os.path.join(SRC, "scripts", "dicom_testdata.py"), "ct", ct,
                series, "--first", "40", "--count", "6", "--crop", "48", "--oblique", "25"],
               check=True)
nii = os.path.join(OUT, "oblique.nii.gz")
run("convert", series, nii, "--quiet")
img = nib.load(nii)
A = img.affine
data = np.asanyarray(img.dataobj)
files = sorted(os.listdir(series))
ok_pos = ok_vox = True
for fn in files:
    ds = pydicom.dcmread(os.path.join(series, fn))
    ipp = LPS2RAS @ np.array([float(x) for x in ds.ImagePositionPatient])
    iop = [float(x) for x in ds.ImageOrientationPatient]
    ks = [k for k in range(data.shape[2]) if np.allclose(A @ [0, 0, k, 1], [*ipp, 1], atol=1e-3)]
    if len(ks) != 1:
        ok_pos = False
        continue
    px = ds.pixel_array.astype(np.float64) * float(ds.RescaleSlope) + float(ds.RescaleIntercept)
    ok_vox &= np.array_equal(data[:, :, ks[0]].T.astype(np.float64), px)
    row, col = LPS2RAS @ np.array(iop[:3]), LPS2RAS @ np.array(iop[3:])
    sp = [float(x) for x in ds.PixelSpacing]
    ok_pos &= np.allclose(A[:3, 0], row * sp[1], atol=1e-4)
    ok_pos &= np.allclose(A[:3, 1], col * sp[0], atol=1e-4)
check(ok_pos, "oblique DICOM as NIfTI: every slice at its Image Position (Patient) in nibabel")
check(ok_vox, "oblique DICOM as NIfTI: every slice's pixels (rescaled) in place")

# Meshes: .vtp (VTK) and .glb (parsed here) against volvis's own figures
txt = run("isosurface", ct, "--iso", "300", "-o", os.path.join(OUT, "bone.vtp"))
m = re.search(r"(\d+) vertices, (\d+) triangles, area ([0-9.e+]+)", txt)
nv, nt, area = int(m.group(1)), int(m.group(2)), float(m.group(3))
r = vtk.vtkXMLPolyDataReader()
r.SetFileName(os.path.join(OUT, "bone.vtp"))
r.Update()
pd = r.GetOutput()
check(pd.GetNumberOfPoints() == nv and pd.GetNumberOfPolys() == nt, "vtp: vertex and triangle counts")
check(pd.GetPointData().GetNormals() is not None, "vtp: normals")
mp = vtk.vtkMassProperties()
mp.SetInputData(pd)
mp.Update()
check(abs(mp.GetSurfaceArea() - area) <= 1e-5 * area + 1,
      f"vtp: vtkMassProperties area {mp.GetSurfaceArea():.2f} = volvis's {area:.2f}")
run("isosurface", ct, "--iso", "300", "-o", os.path.join(OUT, "bone.glb"))
b = open(os.path.join(OUT, "bone.glb"), "rb").read()
magic, version, length = struct.unpack("<4sII", b[:12])
clen, ctype = struct.unpack("<I4s", b[12:20])
gl = json.loads(b[20:20 + clen])
check(magic == b"glTF" and version == 2 and length == len(b) and ctype == b"JSON",
      "glb: header and JSON chunk")
prim = gl["meshes"][0]["primitives"][0]
pos = gl["accessors"][prim["attributes"]["POSITION"]]
idx = gl["accessors"][prim["indices"]]
check(idx["count"] == 3 * nt, "glb: triangle count")
bounds = pd.GetBounds()
check(np.allclose(pos["min"], bounds[0::2], atol=1e-3) and
      np.allclose(pos["max"], bounds[1::2], atol=1e-3), "glb: bounds equal the .vtp's")
check("NORMAL" in prim["attributes"], "glb: normals")

if failures:
    print(f"{len(failures)} checks failed")
    sys.exit(1)
print("all checks passed")
