"""Runs the anchors' VTK benchmark (../shared/anchors/bench_vtk.py) under
this Python's VTK, headless, with vtkSmartVolumeMapper held to its CPU path.

usage: PYTHON bench/vtk_peer.py ANCHORS_DIR [bench_vtk.py's arguments]

PYTHON is the interpreter whose VTK is measured: the virtual environment's
(.venv/bin/python, VTK 9.7 from PyPI, pinned in
scripts/requirements-pypi.txt) or Debian's /usr/bin/python3 (VTK 9.1).
bench_vtk.py builds every mapper itself; this wrapper changes two things
before it runs, and nothing in how it measures:

- the window: without $DISPLAY, VTK 9.4 and later (the PyPI wheels) render
  offscreen through EGL (Mesa's surfaceless llvmpipe here; the
  fixed-point mapper casts its rays on the CPU and only draws its image
  with OpenGL), so the window class is set to vtkEGLRenderWindow and
  bench_vtk.py's re-run under xvfb-run is turned off; Debian's 9.1 is built
  for X only, so there this script re-runs itself under `xvfb-run -a`;
- the smart mapper: bench_vtk.py asks vtkSmartVolumeMapper for its default
  render mode, which picks the GPU ray caster wherever OpenGL 3.2 runs
  (llvmpipe included); here that request is turned into
  SetRequestedRenderModeToRayCast, its CPU path (vtkFixedPointVolumeRayCast
  inside), so that `--mappers smart` measures the CPU mapper. bench_vtk.py
  prints the mode the mapper used ("# smart mapper used render mode: ...").
"""
import os
import runpy
import subprocess
import sys


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: %s ANCHORS_DIR VOLUME [bench_vtk.py arguments]" % sys.argv[0])
    anchors = sys.argv[1]
    script = os.path.join(anchors, "bench_vtk.py")
    if not os.path.isfile(script):
        sys.exit("vtk_peer: %s: no such file (the anchors' VTK benchmark)" % script)
    import vtk

    major, minor = (int(x) for x in vtk.vtkVersion.GetVTKVersion().split(".")[:2])
    if not os.environ.get("DISPLAY"):
        if (major, minor) >= (9, 4):
            os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
            os.environ["ANCHORS_NO_XVFB"] = "1"
        elif not os.environ.get("VTK_PEER_XVFB"):
            xvfb = "/usr/bin/xvfb-run"
            if not os.path.exists(xvfb):
                sys.exit("vtk_peer: VTK %d.%d renders through X only and there is no $DISPLAY "
                         "and no %s" % (major, minor, xvfb))
            env = dict(os.environ, VTK_PEER_XVFB="1", ANCHORS_NO_XVFB="1")
            sys.stdout.flush()
            sys.exit(subprocess.call([xvfb, "-a", "-s", "-screen 0 1280x1024x24", sys.executable,
                                      os.path.abspath(__file__)] + sys.argv[1:], env=env))

    class SmartCPU(vtk.vtkSmartVolumeMapper):
        """vtkSmartVolumeMapper whose default request is its CPU ray caster."""

        def SetRequestedRenderModeToDefault(self):
            self.SetRequestedRenderModeToRayCast()

    vtk.vtkSmartVolumeMapper = SmartCPU
    sys.argv = [script] + sys.argv[2:]
    runpy.run_path(script, run_name="__main__")


if __name__ == "__main__":
    main()
