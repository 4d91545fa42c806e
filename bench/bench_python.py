#!/usr/bin/python3
"""Benchmarks of the Python package (issue 31's targets), same run.

1. overhead: the per-frame cost of volvis.render over the C library's
   render of the same World (the CT head, 512^2, composite, the shared view
   of ../shared/BENCHMARKS.md as bench_raycast sets it up): the library's
   vv_renderer_render called directly (one cffi call, image left in C)
   against volvis.render with a persistent Renderer (write check, options,
   worker thread and progress polling, 8-bit conversion into numpy),
   alternated A B A B; and bench_raycast (a C program) on the same World for
   reference. Target: overhead <= 2 %.
2. vtk: against VTK-Python (python3-vtk9's vtkFixedPointVolumeRayCastMapper
   in an offscreen window under Xvfb), the same view, TF and step: time to
   first image from a numpy array (array -> volume -> first rendered image
   in numpy) and frame time (median over orbiting frames). Target: VolVis
   >= 3x faster on both. Each side runs in its own process, alternated.

usage: PYTHONPATH=build/release/python /usr/bin/python3 bench/bench_python.py
           [--volume PATH] [--size N] [--runs N] [--rounds N] [--parts overhead,vtk]

Prints `anchor=... op=... dataset=... value=... unit=...` lines and '#'
notes, with the load average, as the other benchmarks do.
"""
import argparse
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEFAULT_VOLUME = os.path.join(ROOT, "..", "shared", "data", "volumes", "ct_head.nrrd")
EYE_DIR, EYE_DIST, FOV = (1.0, -1.6, 1.0), 11.0, 20.0  # the shared view (anchors_common)


def emit(anchor, op, dataset, value, unit):
    print("anchor=%s op=%s dataset=%s value=%.6g unit=%s" % (anchor, op, dataset, value, unit),
          flush=True)


def load():
    return "%.2f" % os.getloadavg()[0]


def setup_world(volvis, vol, size, opacity=0.5, step_vox=0.5):
    """bench_raycast's World: centred volume, the shared view, a ramp TF over
    the range, Phong material, a headlight."""
    import numpy as np
    dims, sp = vol.dims, vol.spacing
    vol.origin = [-(n - 1) * s / 2 for n, s in zip(dims, sp)]
    vol.direction = np.eye(3)
    ext = max((n - 1) * s for n, s in zip(dims, sp))
    scale = ext / 2
    d = np.array(EYE_DIR) / np.linalg.norm(EYE_DIR)
    w = volvis.World()
    o = w.add(volvis.VolumeObject(vol, name="bench", step=step_vox))
    lo, hi = vol.range
    o.tf = volvis.TransferFunction(opacity=[(lo, 0), (hi, opacity)],
                                   color=[(lo, (1, 1, 1)), (hi, (1, 1, 1))],
                                   unit_distance=min(sp))
    o.material = volvis.Material(ambient=0.1, diffuse=0.6, specular=0.3, shininess=30)
    w.add_light(headlight=True)
    w.view = volvis.View(eye=d * scale * EYE_DIST, at=(0, 0, 0), up=(0, 0, 1), fov=FOV,
                         size=(size, size))
    return w


def part_overhead(args, volvis):
    from volvis._volvis import ffi, lib
    ds = os.path.basename(args.volume)
    vol = volvis.open(args.volume)
    w = setup_world(volvis, vol, args.size)
    r = volvis.Renderer("raycast")
    img = ffi.gc(_new_image(ffi, lib, args.size), lib.vv_image_free)
    ro = ffi.new("vv_render_options *")
    lib.vv_render_options_init(ro)

    def c_call():
        t = time.perf_counter()
        assert lib.vv_renderer_render(r._c, w._c, ffi.addressof(w._c, "view"), ro, img) == 0
        return time.perf_counter() - t

    def py_call():
        t = time.perf_counter()
        volvis.render(w, renderer=r)
        return time.perf_counter() - t

    c_call()  # first frame builds the caches
    py_call()
    cs, ps = [], []
    for _ in range(args.rounds * args.runs):
        cs.append(c_call())
        ps.append(py_call())
    c, p = statistics.median(cs), statistics.median(ps)
    ratios = sorted(b / a for a, b in zip(cs, ps))
    emit("volvis", "render_frame_c_call", ds, c, "s")
    emit("volvis-python", "render_frame", ds, p, "s")
    emit("volvis-python", "render_overhead", ds, 100 * (statistics.median(ratios) - 1), "%")
    print("# %d alternated pairs at %dx%d; pairwise Python/C ratio min %.4f median %.4f max %.4f;"
          " load %s" % (len(cs), args.size, args.size, ratios[0], statistics.median(ratios),
                        ratios[-1], load()), flush=True)
    bench = os.path.join(ROOT, "build", "release", "bench", "bench_raycast")
    if os.path.exists(bench):
        out = subprocess.run([bench, args.volume, "--size", str(args.size), "--runs",
                              str(args.runs), "--modes", "composite", "--opacity", "0.5",
                              "--step-vox", "0.5", "--outdir", tempfile.gettempdir()],
                             capture_output=True, text=True).stdout
        for line in out.splitlines():
            if "op=dvr_composite_frame " in line:
                print(line.replace("anchor=volvis", "anchor=volvis-c-program"), flush=True)


def _new_image(ffi, lib, size):
    p = ffi.new("vv_image **")
    assert lib.vv_image_new(p, size, size) == 0
    return p[0]


VTK_WORKER = r'''
import math, sys, time, statistics
import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
vtk.vtkObject.GlobalWarningDisplayOff()
arr = np.load(sys.argv[1]); sp = [float(x) for x in sys.argv[2].split(",")]
size, runs, opacity, step_vox = int(sys.argv[3]), int(sys.argv[4]), 0.5, 0.5
EYE_DIR, EYE_DIST, FOV = (1.0, -1.6, 1.0), 11.0, 20.0
t0 = time.perf_counter()
nz, ny, nx = arr.shape
img = vtk.vtkImageData(); img.SetDimensions(nx, ny, nz); img.SetSpacing(*sp)
img.SetOrigin(*[-(n - 1) * s / 2.0 for n, s in zip((nx, ny, nz), sp)])
va = numpy_to_vtk(arr.ravel(), deep=False); img.GetPointData().SetScalars(va)
lo, hi = float(arr.min()), float(arr.max()); minsp = min(sp)
ren = vtk.vtkRenderer(); ren.SetBackground(0, 0, 0)
rw = vtk.vtkRenderWindow(); rw.SetOffScreenRendering(1); rw.SetSize(size, size)
rw.SetMultiSamples(0); rw.AddRenderer(ren)
m = vtk.vtkFixedPointVolumeRayCastMapper(); m.SetAutoAdjustSampleDistances(0)
m.SetLockSampleDistanceToInputSpacing(0); m.SetSampleDistance(step_vox * minsp)
m.SetInteractiveSampleDistance(step_vox * minsp); m.SetImageSampleDistance(1.0)
m.SetMinimumImageSampleDistance(1.0); m.SetMaximumImageSampleDistance(1.0)
m.SetInputData(img); m.SetBlendModeToComposite()
col = vtk.vtkColorTransferFunction(); col.AddRGBPoint(lo, 1, 1, 1); col.AddRGBPoint(hi, 1, 1, 1)
op = vtk.vtkPiecewiseFunction(); op.AddPoint(lo, 0.0); op.AddPoint(hi, opacity)
prop = vtk.vtkVolumeProperty(); prop.SetColor(col); prop.SetScalarOpacity(op)
prop.SetScalarOpacityUnitDistance(minsp); prop.SetInterpolationTypeToLinear(); prop.ShadeOn()
prop.SetAmbient(0.1); prop.SetDiffuse(0.6); prop.SetSpecular(0.3); prop.SetSpecularPower(30.0)
vol = vtk.vtkVolume(); vol.SetMapper(m); vol.SetProperty(prop); ren.AddVolume(vol)
ext = max((n - 1) * s for n, s in zip((nx, ny, nz), sp)); scale = ext / 2
d = np.array(EYE_DIR) / np.linalg.norm(EYE_DIR)
cam = ren.GetActiveCamera(); cam.SetPosition(*(d * scale * EYE_DIST)); cam.SetFocalPoint(0, 0, 0)
cam.SetViewUp(0, 0, 1); cam.SetViewAngle(FOV); ren.ResetCameraClippingRange()
grab = vtk.vtkWindowToImageFilter(); grab.SetInput(rw); grab.ReadFrontBufferOff()
def frame():
    rw.Render(); grab.Modified(); grab.Update()
    o = grab.GetOutput(); return vtk_to_numpy(o.GetPointData().GetScalars()).reshape(size, size, -1)
first = frame(); t_first = time.perf_counter() - t0
ts = []
for k in range(runs):
    cam.Azimuth(3); ren.ResetCameraClippingRange()
    t = time.perf_counter(); frame(); ts.append(time.perf_counter() - t)
print("first=%.6f frame=%.6f mean=%.3f" % (t_first, statistics.median(ts), float(first.mean())))
'''

VOLVIS_WORKER = r'''
import sys, time, statistics
import numpy as np
sys.path.insert(0, sys.argv[5])
import volvis
sys.path.insert(0, sys.argv[6]); from bench_python import setup_world
arr = np.load(sys.argv[1]); sp = [float(x) for x in sys.argv[2].split(",")]
size, runs = int(sys.argv[3]), int(sys.argv[4])
t0 = time.perf_counter()
vol = volvis.Volume(arr, spacing=sp)
w = setup_world(volvis, vol, size)
r = volvis.Renderer("raycast")
first = volvis.render(w, renderer=r); t_first = time.perf_counter() - t0
ts = []
for k in range(runs):
    w.view.orbit(azimuth=3)
    t = time.perf_counter(); volvis.render(w, renderer=r); ts.append(time.perf_counter() - t)
print("first=%.6f frame=%.6f mean=%.3f" % (t_first, statistics.median(ts), float(first.mean())))
'''


def _parse(out):
    vals = dict(kv.split("=") for kv in out.strip().splitlines()[-1].split())
    return float(vals["first"]), float(vals["frame"])


def part_vtk(args, volvis):
    import numpy as np
    ds = os.path.basename(args.volume)
    vol = volvis.open(args.volume)
    sp = ",".join("%r" % s for s in vol.spacing)
    with tempfile.TemporaryDirectory() as d:
        npy = os.path.join(d, "vol.npy")
        np.save(npy, vol.array)
        vw, pw = os.path.join(d, "vtk_worker.py"), os.path.join(d, "volvis_worker.py")
        open(vw, "w").write(VTK_WORKER)
        open(pw, "w").write(VOLVIS_WORKER)
        pkg = os.path.dirname(os.path.dirname(volvis.__file__))
        vtk_cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", "/usr/bin/python3", vw, npy,
                   sp, str(args.size), str(args.runs)]
        vv_cmd = ["/usr/bin/python3", pw, npy, sp, str(args.size), str(args.runs), pkg, HERE]
        env = dict(os.environ, LP_NUM_THREADS=str(os.cpu_count() or 1))
        pairs = []
        for k in range(args.rounds):
            ld = load()
            a = _parse(subprocess.run(vtk_cmd, capture_output=True, text=True, env=env,
                                      check=True).stdout)
            b = _parse(subprocess.run(vv_cmd, capture_output=True, text=True, env=env,
                                      check=True).stdout)
            pairs.append((a, b))
            print("# round %d (load %s): VTK first %.3f s frame %.3f s; VolVis first %.3f s "
                  "frame %.3f s; VTK/VolVis %.2fx first, %.2fx frame"
                  % (k, ld, a[0], a[1], b[0], b[1], a[0] / b[0], a[1] / b[1]), flush=True)
    med = [statistics.median(x) for x in zip(*[(a[0], a[1], b[0], b[1]) for a, b in pairs])]
    emit("vtk-" + "fixedpoint", "first_image_from_numpy", ds, med[0], "s")
    emit("vtk-" + "fixedpoint", "frame", ds, med[1], "s")
    emit("volvis-python", "first_image_from_numpy", ds, med[2], "s")
    emit("volvis-python", "frame", ds, med[3], "s")
    emit("volvis-python", "speedup_first_image_vs_vtk", ds,
         statistics.median(a[0] / b[0] for a, b in pairs), "x")
    emit("volvis-python", "speedup_frame_vs_vtk", ds,
         statistics.median(a[1] / b[1] for a, b in pairs), "x")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--volume", default=DEFAULT_VOLUME)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--parts", default="overhead,vtk")
    args = ap.parse_args()
    import volvis
    print("# %s, %d threads, load %s" % (os.path.basename(args.volume), volvis.get_threads(),
                                          load()), flush=True)
    if "overhead" in args.parts:
        part_overhead(args, volvis)
    if "vtk" in args.parts:
        part_vtk(args, volvis)


if __name__ == "__main__":
    main()
