#!/usr/bin/python3
"""Writes the DICOM test and benchmark series of VolVis into a folder.

Nothing it writes is committed: the tests and bench/bench_dicom call it at run
time with a temporary folder.

  dicom_testdata.py ct NRRD OUT [--first K] [--count N] [--oblique DEG]
                    [--series-number N] [--description TEXT] [--crop N]
      The short CT volume NRRD (../shared/data/volumes/ct_head.nrrd, values in
      Hounsfield units) as a CT series of one file per slice with pydicom:
      stored as unsigned 12-bit values HU + 1024 with Rescale Intercept -1024
      and Slope 1, Pixel Spacing and slice positions from the NRRD spacing,
      explicit VR little endian. Image Orientation (Patient) -1\0\0\0\-1\0 and
      positions from (120, 130, -80) up +z, which read as RAS are the identity
      direction at (-120, -130, -80). --first/--count pick slices, --crop
      keeps the first N rows and columns, --oblique rotates the orientation and
      the positions by DEG degrees about the patient's A-P axis (the pixels
      stay as they are: the same voxels, a rotated frame).
      The files carry a made-up patient name and ID (VOLVIS^TEST, VV-PHI-0001)
      so that tests can check that they are never printed by default.

  dicom_testdata.py oblique NRRD OUT [--angle DEG] [--size N] [--slices N]
      An oblique slab through the middle of the same head, its frame turned
      by DEG degrees about the A-P axis, the pixels resampled (nearest
      neighbour) from the upright volume: read correctly, the anatomy stays
      upright in the patient frame.

  dicom_testdata.py multiframe NRRD OUT.dcm [--first K] [--count N] [--crop N]
      Slices K..K+N-1 of the head as one Enhanced CT file (multi-frame): pixel
      spacing, orientation and rescale in the Shared Functional Groups, one
      Plane Position per frame in the Per-frame Functional Groups, the frames
      stored in a scrambled order (the reader sorts them by position).

  dicom_testdata.py compress IN OUT SYNTAX...
      Copies every file of IN into OUT/SYNTAX/ through gdcmconv for each
      SYNTAX: jpeg (lossless), jpegls, j2k, rle, deflated, implicit.

  dicom_testdata.py bench NRRD OUT [--size 512] [--slices 300]
      The same CT scaled (nearest neighbour, numpy) to SIZE x SIZE x SLICES,
      uncompressed, for bench/bench_dicom.
"""
import argparse
import array
import gzip
import math
import os
import subprocess
import sys

try:
    import pydicom
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
except ImportError:
    sys.stderr.write("dicom_testdata.py: python3-pydicom is not installed\n")
    sys.exit(77)

CT_STORAGE = "1.2.840.10008.5.1.4.1.1.2"


def read_nrrd(path):
    """A short NRRD with an attached raw or gzip payload: (sizes, spacings, values)."""
    data = open(path, "rb").read()
    end = data.index(b"\n\n")
    fields = {}
    for line in data[:end].decode("latin-1").splitlines()[1:]:
        if line.startswith("#") or ": " not in line:
            continue
        k, v = line.split(": ", 1)
        fields[k.strip()] = v.strip()
    if fields.get("type") not in ("short", "int16", "signed short"):
        raise SystemExit("dicom_testdata.py: %s: expected a short NRRD" % path)
    payload = data[end + 2:]
    if fields.get("encoding") == "gzip":
        payload = gzip.decompress(payload)
    values = array.array("h", payload)
    if fields.get("endian", "little") == "big":
        values.byteswap()
    sizes = [int(x) for x in fields["sizes"].split()]
    spacings = [float(x) for x in fields.get("spacings", "1 1 1").split()]
    return sizes, spacings, values


def base_dataset(path, study_uid, series_uid, frame_uid, number, description, instance):
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CT_STORAGE
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = FileDataset(path, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian = True
    ds.is_implicit_VR = False
    ds.SOPClassUID = CT_STORAGE
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.PatientName = "VOLVIS^TEST"
    ds.PatientID = "VV-PHI-0001"
    ds.StudyInstanceUID = study_uid
    ds.SeriesInstanceUID = series_uid
    ds.FrameOfReferenceUID = frame_uid
    ds.StudyDate = "20260101"
    ds.StudyDescription = "VolVis test head"
    ds.SeriesDescription = description
    ds.SeriesNumber = number
    ds.InstanceNumber = instance
    ds.Modality = "CT"
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated = 16
    ds.BitsStored = 12
    ds.HighBit = 11
    ds.PixelRepresentation = 0
    ds.RescaleIntercept = "-1024"
    ds.RescaleSlope = "1"
    ds.RescaleType = "HU"
    return ds


def write_series(out, sizes, spacings, slice_bytes, nslices, args, scale=(1.0, 1.0, 1.0)):
    """slice_bytes(k) gives slice k's uint16 little-endian stored values."""
    os.makedirs(out, exist_ok=True)
    nx, ny = sizes[0], sizes[1]
    study = generate_uid()
    series = generate_uid()
    frame = generate_uid()
    # The NRRD's rows run from the back of the head to the face and its
    # slices from the neck up: in DICOM's LPS frame the row direction is -x,
    # the column direction -y (anterior) and the normal +z (superior), which
    # is RAS's identity. --oblique turns this frame about the A-P (y) axis.
    a = math.radians(args.oblique)

    def turn(v):
        return [math.cos(a) * v[0] + math.sin(a) * v[2], v[1],
                -math.sin(a) * v[0] + math.cos(a) * v[2]]

    row = turn([-1.0, 0.0, 0.0])
    col = [0.0, -1.0, 0.0]
    nrm = turn([0.0, 0.0, 1.0])
    origin = [120.0, 130.0, -80.0]
    dz = spacings[2]
    for k in range(nslices):
        z = (args.first + k) * dz
        pos = [origin[i] + z * nrm[i] for i in range(3)]
        name = os.path.join(out, "slice%04d.dcm" % (k + 1))
        instance = nslices - k if getattr(args, "reverse_instances", False) else args.first + k + 1
        ds = base_dataset(name, study, series, frame, args.series_number, args.description,
                          instance)
        ds.Rows = ny
        ds.Columns = nx
        ds.PixelSpacing = ["%.8g" % spacings[1], "%.8g" % spacings[0]]
        ds.SliceThickness = "%.8g" % dz
        ds.ImagePositionPatient = ["%.6f" % p for p in pos]
        ds.ImageOrientationPatient = ["%.8f" % x for x in row + col]
        ds.SliceLocation = "%.6f" % z
        ds.PixelData = slice_bytes(args.first + k)
        ds.save_as(name, write_like_original=False)


def cmd_ct(args):
    sizes, spacings, values = read_nrrd(args.nrrd)
    nx, ny, nz = sizes
    count = args.count if args.count > 0 else nz - args.first
    if args.first < 0 or args.first + count > nz:
        raise SystemExit("dicom_testdata.py: slices %d..%d outside 0..%d" %
                         (args.first, args.first + count - 1, nz - 1))
    crop = args.crop if args.crop > 0 else nx

    def slice_bytes(k):
        out = array.array("H")
        for j in range(min(crop, ny)):
            base = (k * ny + j) * nx
            out.extend(max(0, min(4095, v + 1024)) for v in values[base:base + min(crop, nx)])
        if sys.byteorder == "big":
            out.byteswap()
        return out.tobytes()

    write_series(args.out, [min(crop, nx), min(crop, ny), nz], spacings, slice_bytes, count, args)


def cmd_oblique(args):
    """An oblique slab resampled (nearest neighbour) from the upright head, so
    that the anatomy stays upright in the patient frame."""
    sizes, spacings, values = read_nrrd(args.nrrd)
    nx, ny, nz = sizes
    psx, psy, dz = spacings
    o0 = [120.0, 130.0, -80.0]
    r0, c0, n0 = [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]
    a = math.radians(args.angle)

    def turn(v):
        return [math.cos(a) * v[0] + math.sin(a) * v[2], v[1],
                -math.sin(a) * v[0] + math.cos(a) * v[2]]

    r, c, n = turn(r0), c0, turn(n0)
    pc = [o0[i] + (nx - 1) / 2 * psx * r0[i] + (ny - 1) / 2 * psy * c0[i] +
          (nz - 1) / 2 * dz * n0[i] for i in range(3)]
    m, q, s = args.size, args.slices, psx
    org = [pc[i] - (m - 1) / 2 * s * r[i] - (m - 1) / 2 * s * c[i] - (q - 1) / 2 * dz * n[i]
           for i in range(3)]
    os.makedirs(args.out, exist_ok=True)
    study, series, frame = generate_uid(), generate_uid(), generate_uid()
    for k in range(q):
        out = array.array("H")
        for j in range(m):
            for i in range(m):
                p = [org[t] + i * s * r[t] + j * s * c[t] + k * dz * n[t] for t in range(3)]
                d = [p[t] - o0[t] for t in range(3)]
                ii = math.floor(sum(d[t] * r0[t] for t in range(3)) / psx + 0.5)
                jj = math.floor(sum(d[t] * c0[t] for t in range(3)) / psy + 0.5)
                kk = math.floor(sum(d[t] * n0[t] for t in range(3)) / dz + 0.5)
                v = -1024
                if 0 <= ii < nx and 0 <= jj < ny and 0 <= kk < nz:
                    v = values[(kk * ny + jj) * nx + ii]
                out.append(max(0, min(4095, v + 1024)))
        if sys.byteorder == "big":
            out.byteswap()
        name = os.path.join(args.out, "obl%04d.dcm" % (k + 1))
        ds = base_dataset(name, study, series, frame, 1, "Oblique head", k + 1)
        ds.Rows = m
        ds.Columns = m
        ds.PixelSpacing = ["%.8g" % s, "%.8g" % s]
        ds.SliceThickness = "%.8g" % dz
        ds.ImagePositionPatient = ["%.6f" % (org[t] + k * dz * n[t]) for t in range(3)]
        ds.ImageOrientationPatient = ["%.8f" % x for x in r + c]
        ds.PixelData = out.tobytes()
        ds.save_as(name, write_like_original=False)


def cmd_multiframe(args):
    """Slices of the head as one Enhanced CT file: geometry and rescale in
    the functional groups, frames stored in a scrambled order."""
    from pydicom.dataset import Dataset
    from pydicom.sequence import Sequence
    sizes, spacings, values = read_nrrd(args.nrrd)
    nx, ny, nz = sizes
    m = min(args.crop, nx, ny)
    dz = spacings[2]
    order = [(k * 5 + 3) % args.count for k in range(args.count)]  # 5 is prime to count
    if len(set(order)) != args.count:
        order = list(range(args.count))[::-1]
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.2.1"
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = FileDataset(args.out, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian = True
    ds.is_implicit_VR = False
    ds.SOPClassUID = meta.MediaStorageSOPClassUID
    ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
    ds.PatientName = "VOLVIS^TEST"
    ds.PatientID = "VV-PHI-0001"
    ds.StudyInstanceUID = generate_uid()
    ds.SeriesInstanceUID = generate_uid()
    ds.FrameOfReferenceUID = generate_uid()
    ds.Modality = "CT"
    ds.SeriesNumber = 1
    ds.InstanceNumber = 1
    ds.SeriesDescription = "Enhanced head"
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated = 16
    ds.BitsStored = 12
    ds.HighBit = 11
    ds.PixelRepresentation = 0
    ds.Rows = m
    ds.Columns = m
    ds.NumberOfFrames = args.count
    shared = Dataset()
    pm = Dataset()
    pm.PixelSpacing = ["%.8g" % spacings[1], "%.8g" % spacings[0]]
    pm.SliceThickness = "%.8g" % dz
    shared.PixelMeasuresSequence = Sequence([pm])
    po = Dataset()
    po.ImageOrientationPatient = ["-1", "0", "0", "0", "-1", "0"]
    shared.PlaneOrientationSequence = Sequence([po])
    pv = Dataset()
    pv.RescaleIntercept = "-1024"
    pv.RescaleSlope = "1"
    pv.RescaleType = "HU"
    shared.PixelValueTransformationSequence = Sequence([pv])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    frames = []
    pixels = array.array("H")
    for k in order:
        z = args.first + k
        fg = Dataset()
        pp = Dataset()
        pp.ImagePositionPatient = ["120", "130", "%.6f" % (-80.0 + z * dz)]
        fg.PlanePositionSequence = Sequence([pp])
        frames.append(fg)
        for j in range(m):
            base = (z * ny + j) * nx
            pixels.extend(max(0, min(4095, v + 1024)) for v in values[base:base + m])
    ds.PerFrameFunctionalGroupsSequence = Sequence(frames)
    if sys.byteorder == "big":
        pixels.byteswap()
    ds.PixelData = pixels.tobytes()
    ds.save_as(args.out, write_like_original=False)


def cmd_compress(args):
    flags = {"jpeg": ["--jpeg"], "jpegls": ["--jpegls"], "j2k": ["--j2k"], "rle": ["--rle"],
             "deflated": ["--deflated"], "implicit": ["--implicit"]}
    names = sorted(n for n in os.listdir(args.src) if not n.startswith("."))
    for syn in args.syntax:
        if syn not in flags:
            raise SystemExit("dicom_testdata.py: unknown syntax %s" % syn)
        dst = os.path.join(args.out, syn)
        os.makedirs(dst, exist_ok=True)
        for n in names:
            subprocess.run(["gdcmconv"] + flags[syn] + [os.path.join(args.src, n),
                                                        os.path.join(dst, n)], check=True)


def cmd_bench(args):
    import numpy as np
    sizes, spacings, values = read_nrrd(args.nrrd)
    nx, ny, nz = sizes
    vol = np.frombuffer(values.tobytes(), dtype="<i2").reshape(nz, ny, nx)
    s = args.size
    iy = (np.arange(s) * ny) // s
    ix = (np.arange(s) * nx) // s
    iz = (np.arange(args.slices) * nz) // args.slices
    sp = [spacings[0] * nx / s, spacings[1] * ny / s, spacings[2] * nz / args.slices]
    args.first = 0
    args.oblique = 0.0

    def slice_bytes(k):
        sl = vol[iz[k]][np.ix_(iy, ix)].astype(np.int32) + 1024
        return np.clip(sl, 0, 4095).astype("<u2").tobytes()

    write_series(args.out, [s, s, args.slices], sp, slice_bytes, args.slices, args)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("ct")
    c.add_argument("nrrd")
    c.add_argument("out")
    c.add_argument("--first", type=int, default=0)
    c.add_argument("--count", type=int, default=0)
    c.add_argument("--crop", type=int, default=0)
    c.add_argument("--oblique", type=float, default=0.0)
    c.add_argument("--series-number", type=int, default=1)
    c.add_argument("--description", default="Head CT")
    c.add_argument("--reverse-instances", action="store_true",
                   help="Instance Number counts down while the positions go up")
    c.set_defaults(func=cmd_ct)
    o = sub.add_parser("oblique")
    o.add_argument("nrrd")
    o.add_argument("out")
    o.add_argument("--angle", type=float, default=30.0)
    o.add_argument("--size", type=int, default=96)
    o.add_argument("--slices", type=int, default=24)
    o.set_defaults(func=cmd_oblique)
    f = sub.add_parser("multiframe")
    f.add_argument("nrrd")
    f.add_argument("out")
    f.add_argument("--first", type=int, default=40)
    f.add_argument("--count", type=int, default=8)
    f.add_argument("--crop", type=int, default=64)
    f.set_defaults(func=cmd_multiframe)
    k = sub.add_parser("compress")
    k.add_argument("src")
    k.add_argument("out")
    k.add_argument("syntax", nargs="+")
    k.set_defaults(func=cmd_compress)
    b = sub.add_parser("bench")
    b.add_argument("nrrd")
    b.add_argument("out")
    b.add_argument("--size", type=int, default=512)
    b.add_argument("--slices", type=int, default=300)
    b.add_argument("--series-number", type=int, default=1)
    b.add_argument("--description", default="Bench CT")
    b.set_defaults(func=cmd_bench)
    args = p.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
