#!/usr/bin/python3
"""Times VTK's vtkDICOMImageReader on a DICOM folder (the peer of bench_dicom).

  dicom_vtk.py FOLDER [--repeat N] [--dataset NAME]

Reads the folder once to warm the page cache, then N times, and prints the
median wall-clock time as `anchor=vtk op=dicom_load dataset=NAME value=S unit=s`
(with the voxel count and value range on stderr, to check it read the same
voxels). Needs Debian's python3-vtk9 (run with /usr/bin/python3).
"""
import argparse
import statistics
import sys
import time

try:
    import vtk
except ImportError:
    sys.stderr.write("dicom_vtk.py: python3-vtk9 is not installed\n")
    sys.exit(77)


def load(folder):
    r = vtk.vtkDICOMImageReader()
    r.SetDirectoryName(folder)
    r.Update()
    return r.GetOutput()


def main():
    p = argparse.ArgumentParser()
    p.add_argument("folder")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--dataset", default="ct512x512x300")
    a = p.parse_args()
    img = load(a.folder)
    dims = img.GetDimensions()
    lo, hi = img.GetScalarRange()
    sys.stderr.write("vtk: %d x %d x %d, %s, range %g .. %g\n" %
                     (dims[0], dims[1], dims[2], img.GetScalarTypeAsString(), lo, hi))
    times = []
    for _ in range(a.repeat):
        t = time.perf_counter()
        load(a.folder)
        times.append(time.perf_counter() - t)
    print("anchor=vtk op=dicom_load dataset=%s value=%.6g unit=s" %
          (a.dataset, statistics.median(times)), flush=True)


if __name__ == "__main__":
    main()
