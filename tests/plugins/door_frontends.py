#!/usr/bin/python3
"""The door's contract: a toy front end (toy_frontend.c, under 60 lines)
opens what a user names through vv_world_open alone and draws it.

  door_frontends.py TOY_FRONTEND VOLVIS OUTDIR

Five inputs, the ones that are not ours written by independent writers:
a NIfTI file (../shared/data, written by SPM), a DICOM folder (pydicom,
16 CT slices), an OME-Zarr 0.4 store (python3-zarr with the multiscales
metadata written by hand, two levels), a scene file (examples/ct_head.json)
and a BigDataViewer dataset XML with its HDF5 file (h5py). For each:

- the toy front end writes a PNG that is not blank;
- it equals `volvis render INPUT --size 96x80 --threads 1` pixel for pixel:
  the CLI and the toy reach the same World through the same door;
- a missing input and a file that is no format at all are one-line errors
  naming the input, a non-zero exit and no PNG.
"""
import os
import shutil
import subprocess
import sys

try:
    import h5py
    import numpy as np
    import pydicom
    import zarr
    from PIL import Image
    from pydicom.dataset import FileDataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (python3-h5py, python3-numpy, python3-pydicom, python3-zarr, "
          "python3-pil)")
    sys.exit(77)

TOY, VOLVIS, OUT = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def blob(shape):
    """A bright ellipsoid in a dim box: something every mode shows."""
    z, y, x = np.mgrid[0:shape[0], 0:shape[1], 0:shape[2]].astype(np.float64)
    c = [(n - 1) / 2 for n in shape]
    r = ((z - c[0]) / (0.4 * shape[0])) ** 2 + ((y - c[1]) / (0.35 * shape[1])) ** 2 + \
        ((x - c[2]) / (0.3 * shape[2])) ** 2
    return np.where(r < 1, 1200 - 600 * r, 40).astype(np.int16)


def write_dicom(folder, vol, spacing):
    os.makedirs(folder)
    series, study = generate_uid(), generate_uid()
    for k in range(vol.shape[0]):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = pydicom.uid.CTImageStorage
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        path = os.path.join(folder, f"slice{k:03d}.dcm")
        ds = FileDataset(path, {}, file_meta=meta, preamble=b"\0" * 128)
        ds.SOPClassUID = meta.MediaStorageSOPClassUID
        ds.SOPInstanceUID = meta.MediaStorageSOPInstanceUID
        ds.StudyInstanceUID, ds.SeriesInstanceUID = study, series
        ds.Modality, ds.PatientName, ds.PatientID = "CT", "Toy^Door", "door"
        ds.InstanceNumber = k + 1
        ds.ImagePositionPatient = [0.0, 0.0, float(k * spacing[2])]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.PixelSpacing = [spacing[1], spacing[0]]
        ds.SliceThickness = spacing[2]
        ds.Rows, ds.Columns = vol.shape[1], vol.shape[2]
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleIntercept, ds.RescaleSlope = 0, 1
        ds.PixelData = vol[k].astype("<i2").tobytes()
        ds.is_little_endian, ds.is_implicit_VR = True, False
        ds.save_as(path, write_like_original=False)


def write_ome_zarr(path, vol):
    g = zarr.open_group(path, mode="w")
    levels = [vol, vol[::2, ::2, ::2]]
    for i, lv in enumerate(levels):
        g.create_dataset(str(i), data=lv, chunks=(8, 16, 16))
    g.attrs["multiscales"] = [{
        "version": "0.4", "name": "blob",
        "axes": [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"],
        "datasets": [{"path": str(i), "coordinateTransformations": [
            {"type": "scale", "scale": [2.0 * 2 ** i, 1.0 * 2 ** i, 1.0 * 2 ** i]}]}
            for i in range(len(levels))]}]


def write_bdv(xml_path, vol):
    h5 = os.path.splitext(xml_path)[0] + ".h5"
    with h5py.File(h5, "w") as f:
        f["s00/resolutions"] = np.array([[1.0, 1.0, 1.0]])
        f["s00/subdivisions"] = np.array([[16, 16, 16]], dtype=np.int32)
        f.create_dataset("t00000/s00/0/cells", data=vol.astype(np.int16), chunks=(16, 16, 16))
    z, y, x = vol.shape
    with open(xml_path, "w") as f:
        f.write(f"""<?xml version="1.0" encoding="UTF-8"?>
<SpimData version="0.2">
  <BasePath type="relative">.</BasePath>
  <SequenceDescription>
    <ImageLoader format="bdv.hdf5">
      <hdf5 type="relative">{os.path.basename(h5)}</hdf5>
    </ImageLoader>
    <ViewSetups>
      <ViewSetup>
        <id>0</id>
        <name>blob</name>
        <size>{x} {y} {z}</size>
        <voxelSize>
          <unit>um</unit>
          <size>1.0 1.0 2.0</size>
        </voxelSize>
      </ViewSetup>
    </ViewSetups>
    <Timepoints type="range">
      <first>0</first>
      <last>0</last>
    </Timepoints>
  </SequenceDescription>
  <ViewRegistrations>
    <ViewRegistration timepoint="0" setup="0">
      <ViewTransform type="affine">
        <affine>1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 2.0 0.0</affine>
      </ViewTransform>
    </ViewRegistration>
  </ViewRegistrations>
</SpimData>
""")


vol = blob((16, 40, 48))
inputs = {
    "nifti": "../shared/data/volumes/avg152T1_RL_nifti.nii.gz",
    "dicom": os.path.join(OUT, "dicom"),
    "ome_zarr": os.path.join(OUT, "blob.ome.zarr"),
    "scene": "examples/ct_head.json",
    "bdv_xml": os.path.join(OUT, "blob.xml"),
}
write_dicom(inputs["dicom"], vol, (1.0, 1.0, 2.0))
write_ome_zarr(inputs["ome_zarr"], vol.astype(np.uint16))
write_bdv(inputs["bdv_xml"], vol)

for name, path in inputs.items():
    toy_png = os.path.join(OUT, f"toy_{name}.png")
    cli_png = os.path.join(OUT, f"cli_{name}.png")
    toy = subprocess.run([TOY, path, "96", "80", toy_png], capture_output=True, text=True)
    check(toy.returncode == 0, f"{name}: the toy front end draws it ({toy.stderr.strip()})")
    cli = subprocess.run([VOLVIS, "render", path, "--size", "96x80", "--threads", "1", "-q",
                          "-o", cli_png], capture_output=True, text=True)
    check(cli.returncode == 0, f"{name}: volvis render draws it ({cli.stderr.strip()})")
    if toy.returncode or cli.returncode:
        continue
    a = np.asarray(Image.open(toy_png).convert("RGB"), dtype=np.int16)
    b = np.asarray(Image.open(cli_png).convert("RGB"), dtype=np.int16)
    check(a.shape == (80, 96, 3), f"{name}: 96x80 pixels")
    check(a.max() > 40, f"{name}: not blank (brightest {a.max()})")
    check(a.shape == b.shape and not np.any(a != b),
          f"{name}: the same image as volvis render (max difference "
          f"{int(np.abs(a - b).max()) if a.shape == b.shape else 'shape'})")

junk = os.path.join(OUT, "junk.bin")
with open(junk, "wb") as f:
    f.write(b"\x13\x37 this is no volume format at all \x00" * 8)
for path, what in ((os.path.join(OUT, "missing.nii"), "a missing input"), (junk, "junk")):
    png = os.path.join(OUT, "bad.png")
    r = subprocess.run([TOY, path, "96", "80", png], capture_output=True, text=True)
    lines = r.stderr.strip().splitlines()
    check(r.returncode != 0 and len(lines) == 1 and os.path.basename(path) in lines[0]
          and not os.path.exists(png), f"{what}: one line naming it, no PNG ({lines})")

print(f"{len(failures)} failed" if failures else "all passed")
sys.exit(1 if failures else 0)
