#!/usr/bin/python3
"""Peer of bench_raster: VTK renders the same isosurface in the same view.

VTK's flying edges extracts the isosurface (with normals) of VOLUME at ISO,
then a vtkPolyDataMapper draws it offscreen at SIZE^2 through OpenGL (on a
machine without a GPU that is Mesa's llvmpipe software rasterizer, given
LP_NUM_THREADS threads), Phong ka 0.1 kd 0.6 ks 0.3 n 30, white, with VTK's
headlight, camera of ../shared/BENCHMARKS.md (eye at scale * 11 *
normalize(1, -1.6, 1), fov 20, up +z). Prints

  anchor=vtk-<version>-<gl renderer> op=raster_frame dataset=<file> value=<s> unit=s

(median of --runs frames, each forced to re-render with a camera nudge so
that no frame is a cached one) and writes OUTDIR/<stem>_vtk_raster.png.

usage: peer_raster_vtk.py VOLUME --iso V [--size N] [--runs N] [--threads N] [--outdir DIR]
Runs itself under xvfb-run when there is no DISPLAY.
"""
import argparse
import os
import statistics
import subprocess
import sys
import time

ap = argparse.ArgumentParser()
ap.add_argument("volume")
ap.add_argument("--iso", type=float, required=True)
ap.add_argument("--size", type=int, default=512)
ap.add_argument("--runs", type=int, default=5)
ap.add_argument("--threads", type=int, default=2)
ap.add_argument("--outdir", default="build/bench-out")
args = ap.parse_args()

os.environ["LP_NUM_THREADS"] = str(args.threads)
if not os.environ.get("DISPLAY") and not os.environ.get("PEER_NO_XVFB"):
    env = dict(os.environ, PEER_NO_XVFB="1")
    sys.exit(subprocess.call(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", sys.executable,
                              os.path.abspath(__file__)] + sys.argv[1:], env=env))

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "..", "shared", "anchors"))
import numpy as np  # noqa: E402
import vtk  # noqa: E402
from vtk.util.numpy_support import numpy_to_vtk  # noqa: E402

import anchors_common as ac  # noqa: E402

vtk.vtkObject.GlobalWarningDisplayOff()
dataset = os.path.basename(args.volume)
arr, spacing, _, _ = ac.read_nrrd(args.volume)
nz, ny, nx = arr.shape
img = vtk.vtkImageData()
img.SetDimensions(nx, ny, nz)
img.SetSpacing(*spacing)
img.SetOrigin(*[-(n - 1) * s / 2.0 for n, s in zip((nx, ny, nz), spacing)])
va = numpy_to_vtk(np.ascontiguousarray(arr).ravel(), deep=True)
img.GetPointData().SetScalars(va)

vtk.vtkSMPTools.Initialize(args.threads)
fe = vtk.vtkFlyingEdges3D()
fe.SetInputData(img)
fe.SetValue(0, args.iso)
fe.SetComputeNormals(1)
fe.SetComputeScalars(0)
fe.Update()
mesh = fe.GetOutput()

mapper = vtk.vtkPolyDataMapper()
mapper.SetInputData(mesh)
mapper.ScalarVisibilityOff()
actor = vtk.vtkActor()
actor.SetMapper(mapper)
p = actor.GetProperty()
p.SetColor(1, 1, 1)
p.SetAmbient(0.1)
p.SetDiffuse(0.6)
p.SetSpecular(0.3)
p.SetSpecularPower(30)
p.SetInterpolationToPhong()
ren = vtk.vtkRenderer()
ren.SetBackground(0, 0, 0)
ren.AddActor(actor)
rw = vtk.vtkRenderWindow()
rw.SetOffScreenRendering(1)
rw.SetSize(args.size, args.size)
rw.SetMultiSamples(0)
rw.AddRenderer(ren)
ext = max((n - 1) * s for n, s in zip((nx, ny, nz), spacing))
d = np.array([1.0, -1.6, 1.0])
d /= np.linalg.norm(d)
cam = ren.GetActiveCamera()
cam.SetFocalPoint(0, 0, 0)
cam.SetPosition(*(d * ext / 2 * 11))
cam.SetViewUp(0, 0, 1)
cam.SetViewAngle(20)
ren.ResetCameraClippingRange()
rw.Render()  # first frame: uploads the mesh

times = []
for i in range(args.runs):
    cam.Azimuth(1e-3 if i % 2 == 0 else -1e-3)
    t0 = time.perf_counter()
    rw.Render()
    # glFinish: read the pixels back, as the software renderer's frame includes its image
    wi = vtk.vtkWindowToImageFilter()
    wi.SetInput(rw)
    wi.ShouldRerenderOff()
    wi.ReadFrontBufferOff()
    wi.Update()
    times.append(time.perf_counter() - t0)
gl = rw.ReportCapabilities() or ""
glr = "unknown"
for line in gl.splitlines():
    if "OpenGL renderer string" in line:
        glr = line.split(":", 1)[1].strip().split()[0]
anchor = "vtk-%s-%s" % (vtk.vtkVersion.GetVTKVersion(), glr)
print("# %s: %d triangles, LP_NUM_THREADS=%s, %dx%d" % (dataset, mesh.GetNumberOfPolys(),
                                                      os.environ["LP_NUM_THREADS"], args.size,
                                                      args.size))
print("anchor=%s op=raster_triangles dataset=%s value=%d unit=triangles"
      % (anchor, dataset, mesh.GetNumberOfPolys()))
print("anchor=%s op=raster_frame dataset=%s value=%.6g unit=s"
      % (anchor, dataset, statistics.median(times)))
os.makedirs(args.outdir, exist_ok=True)
stem = dataset.split(".")[0]
w = vtk.vtkPNGWriter()
w.SetFileName(os.path.join(args.outdir, "%s_vtk_raster.png" % stem))
wi = vtk.vtkWindowToImageFilter()
wi.SetInput(rw)
wi.Update()
w.SetInputConnection(wi.GetOutputPort())
w.Write()
print("# image %s" % os.path.join(args.outdir, "%s_vtk_raster.png" % stem))
