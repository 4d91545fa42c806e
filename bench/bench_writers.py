#!/usr/bin/python3
"""Writing speed of the volume writers (issue 34's targets), same run.

The CT head (../shared/data/volumes/ct_head.nrrd, 256 x 256 x 108 i16) is
opened once with the Python package; then, alternated A B A B for --rounds
rounds (median reported):

1. .nii.gz: volvis (Volume.save, gzip level 1) against nibabel's
   Nifti1Image save of the same array and affine (its default level 1).
   Target: VolVis no slower.
2. .mha compressed: volvis against VTK's vtkMetaImageWriter with
   compression on (python3-vtk9). Target: VolVis no slower.
3. .nii uncompressed against `dd` of the same number of bytes into the same
   folder (conv=fsync, as the atomic writer syncs before its rename).
   Target: VolVis >= 80 % of dd's speed.
4. OME-TIFF with deflate against tifffile's imwrite (ome=True,
   compression zlib) of the same array: no target in the issue, reported for
   reference. Not the same work: VolVis adds horizontal differencing
   (predictor 2) for integers, which tifffile cannot do without imagecodecs.

usage: PYTHONPATH=build/release/python /usr/bin/python3 bench/bench_writers.py
           [--volume PATH] [--rounds N] [--dir DIR]

Prints `anchor=... op=... dataset=... value=... unit=s` lines and '#' notes
with the load average, as the other benchmarks do. Files are written under
--dir (default build/bench-out/writers) and removed.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_VOLUME = os.path.join(ROOT, "..", "shared", "data", "volumes", "ct_head.nrrd")


def emit(anchor, op, dataset, value):
    print("anchor=%s op=%s dataset=%s value=%.6g unit=s" % (anchor, op, dataset, value),
          flush=True)


def timed(fn):
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--volume", default=DEFAULT_VOLUME)
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--dir", default=os.path.join(ROOT, "build", "bench-out", "writers"))
    args = ap.parse_args()
    try:
        import numpy as np
        import nibabel as nib
        import vtk
        from vtk.util.numpy_support import numpy_to_vtk
        import tifffile
        import volvis
    except ImportError as e:
        print("# bench_writers: skipped: %s (PYTHONPATH=build/release/python, python3-nibabel, "
              "python3-vtk9, python3-tifffile)" % e)
        return 77
    os.makedirs(args.dir, exist_ok=True)
    name = os.path.basename(args.volume)
    v = volvis.open(args.volume)
    arr = np.ascontiguousarray(v.array)  # [k, j, i]
    sp = [float(x) for x in v.spacing]
    org = [float(x) for x in v.origin]
    affine = np.eye(4)
    affine[:3, :3] = np.diag(sp)
    affine[:3, 3] = org
    nib_img = nib.Nifti1Image(arr.transpose(2, 1, 0), affine)

    img = vtk.vtkImageData()
    img.SetDimensions(arr.shape[2], arr.shape[1], arr.shape[0])
    img.SetSpacing(*sp)
    img.SetOrigin(*org)
    img.GetPointData().SetScalars(numpy_to_vtk(arr.ravel(), deep=1))

    def vtk_mha(path):
        w = vtk.vtkMetaImageWriter()
        w.SetFileName(path)
        w.SetCompression(True)
        w.SetInputData(img)
        w.Write()

    p = lambda n: os.path.join(args.dir, n)  # noqa: E731
    nbytes = arr.nbytes + 352
    pairs = {
        "write_nii_gz": (lambda: v.save(p("v.nii.gz")), "nibabel",
                         lambda: nib.save(nib_img, p("n.nii.gz"))),
        "write_mha_zlib": (lambda: v.save(p("v.mha")), "vtk", lambda: vtk_mha(p("k.mha"))),
        "write_ome_tif_deflate": (lambda: v.save(p("v.ome.tif")), "tifffile",
                                  lambda: tifffile.imwrite(
                                      p("t.ome.tif"), arr, ome=True, compression="zlib",
                                      metadata={"axes": "ZYX", "PhysicalSizeX": sp[0],
                                                "PhysicalSizeY": sp[1],
                                                "PhysicalSizeZ": sp[2]})),
        "write_nii_raw": (lambda: v.save(p("v.nii")), "dd",
                          lambda: subprocess.run(
                              ["dd", "if=/dev/zero", "of=" + p("d.bin"), "bs=%d" % nbytes,
                               "count=1", "conv=fsync", "status=none"], check=True)),
    }
    load = os.getloadavg()
    print("# bench_writers: %s, %d rounds, load %.2f %.2f %.2f" % (name, args.rounds, *load))
    for op, (ours, peer, theirs) in pairs.items():
        a, b = [], []
        ours()
        theirs()  # warm-up pair
        for _ in range(args.rounds):
            a.append(timed(ours))
            b.append(timed(theirs))
        ma, mb = statistics.median(a), statistics.median(b)
        emit("volvis", op, name, ma)
        emit(peer, op, name, mb)
        if op == "write_nii_raw":
            print("# %s: volvis %.1f ms, dd %.1f ms: %.0f %% of dd's speed (target >= 80 %%)" %
                  (op, ma * 1e3, mb * 1e3, 100 * mb / ma))
        elif op == "write_ome_tif_deflate":
            sa = os.path.getsize(p("v.ome.tif"))
            sb = os.path.getsize(p("t.ome.tif"))
            print("# %s: volvis %.1f ms (%.1f MB), %s %.1f ms (%.1f MB): %.2fx (no target)" %
                  (op, ma * 1e3, sa / 1e6, peer, mb * 1e3, sb / 1e6, ma / mb))
        else:
            print("# %s: volvis %.1f ms, %s %.1f ms: %.2fx (target <= 1)" %
                  (op, ma * 1e3, peer, mb * 1e3, ma / mb))
    for f in os.listdir(args.dir):
        os.unlink(os.path.join(args.dir, f))
    print("# load after: %.2f %.2f %.2f" % os.getloadavg())
    return 0


if __name__ == "__main__":
    sys.exit(main())
