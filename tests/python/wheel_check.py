#!/usr/bin/env python3
"""The installed pip wheel, used from a folder outside the source tree
(tests/python/wheel.sh runs this with the fresh environment's python, the
working directory a temporary folder).

Usage: wheel_check.py DATA_DIR

Checks: `import volvis` comes from the environment's site-packages (no build
tree on sys.path) and loads the wheel's libvolvis; a NIfTI renders; a TIFF written here renders after being
read back through the sandboxed reader (volvis-reader of the wheel: with
VOLVIS_READER naming a missing program the same read fails, so the read did
go through the reader); the `volvis` command of the environment prints its
help, renders both files to PNGs and serves the browser client's page from
the wheel (`volvis serve`); the napari plug-in's entry point (group
napari.manifest) names its npe2 manifest, which the wheel holds.
"""
import os
import pathlib
import re
import subprocess
import sys
import time
import urllib.request

import numpy as np

import volvis


def fail(msg):
    print("wheel_check: FAIL: " + msg)
    sys.exit(1)


def main():
    data = pathlib.Path(sys.argv[1])
    here = pathlib.Path.cwd()
    prefix = pathlib.Path(sys.prefix).resolve()
    pkg = pathlib.Path(volvis.__file__).resolve().parent
    if prefix not in pkg.parents:
        fail("volvis imported from %s, not from the environment %s" % (pkg, prefix))
    for var in ("PYTHONPATH", "VOLVIS_READER", "VOLVIS_SANDBOX", "VOLVIS_WEB_DIR"):
        if os.environ.get(var):
            fail("%s is set (%s): the check must use the wheel alone" % (var, os.environ[var]))
    # the library loaded is the wheel's (its RUNPATH $ORIGIN/lib comes before
    # ld.so's cache, where an installed /usr/local/lib/libvolvis.so would be)
    with open("/proc/self/maps") as f:
        libs = {line.split()[-1] for line in f if "libvolvis" in line}
    if not libs or any(pathlib.Path(p).resolve().parent != pkg / "lib" for p in libs):
        fail("libvolvis loaded from %s, not from %s" % (sorted(libs), pkg / "lib"))
    print("volvis %s from %s" % (volvis.__version__, pkg))

    nii = data / "volumes" / "avg152T1_RL_nifti.nii.gz"
    vol = volvis.open(nii)
    img = np.asarray(volvis.render(vol, size=(96, 96)))
    if img.shape != (96, 96, 4) or int(img[..., :3].max()) == 0:
        fail("the NIfTI rendered to %s, max %d" % (img.shape, int(img.max())))
    print("NIfTI %s rendered" % vol)

    k, j, i = np.indices((24, 28, 32))
    ball = ((i - 16) ** 2 + (j - 14) ** 2 + (k - 12) ** 2 < 100).astype(np.uint8) * 200
    tif = here / "ball.tif"
    volvis.Volume(ball).save(tif)
    back = volvis.open(tif)
    if not np.array_equal(back.array, ball):
        fail("the TIFF read back differs from what was written")
    img = np.asarray(volvis.render(back, size=(64, 64)))
    if int(img[..., :3].max()) == 0:
        fail("the TIFF rendered black")
    print("TIFF %s read through volvis-reader and rendered" % back)
    # the same read with the reader hidden fails: the TIFF went through it
    code = "import volvis; volvis.open(%r)" % str(tif)
    env = dict(os.environ, VOLVIS_READER=str(here / "no-such-reader"))
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    if r.returncode == 0 or "volvis-reader" not in r.stderr:
        fail("with VOLVIS_READER missing the TIFF still read (rc %d): %s" % (r.returncode,
                                                                            r.stderr[-300:]))

    exe = pathlib.Path(sys.prefix) / "bin" / "volvis"
    r = subprocess.run([str(exe), "--help"], capture_output=True, text=True)
    if r.returncode != 0 or "usage: volvis" not in r.stdout:
        fail("volvis --help: rc %d\n%s%s" % (r.returncode, r.stdout, r.stderr))
    for src, png in ((nii, "head.png"), (tif, "ball.png")):
        r = subprocess.run([str(exe), "render", str(src), "-o", png, "--size", "128x128"],
                           capture_output=True, text=True)
        if r.returncode != 0 or not (here / png).exists():
            fail("volvis render %s: rc %d\n%s%s" % (src.name, r.returncode, r.stdout, r.stderr))
        shot = volvis.read_png(here / png)
        if int(np.asarray(shot)[..., :3].max()) == 0:
            fail("volvis render %s wrote a black image" % src.name)
    print("volvis --help, volvis render (NIfTI, TIFF) from %s" % exe)

    srv = subprocess.Popen([str(exe), "serve", "--port", "0", str(tif)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = srv.stdout.readline()
        m = re.match(r"(http://127\.0\.0\.1:\d+/)\?token=(\w+)", line.strip())
        if not m:
            fail("volvis serve printed %r" % line)
        page = None
        for _ in range(50):
            try:
                page = urllib.request.urlopen(m.group(1) + "?token=" + m.group(2),
                                              timeout=5).read().decode()
                break
            except OSError:
                time.sleep(0.1)
        if not page or "<html" not in page:
            fail("volvis serve: no page from %s" % m.group(1))
    finally:
        srv.terminate()
        srv.wait(timeout=10)
    print("volvis serve: the browser client's page served from the wheel")
    # the napari plug-in: napari finds it by the entry point of group
    # napari.manifest naming the npe2 manifest inside the package
    import importlib.metadata
    import importlib.resources
    eps = [e for e in importlib.metadata.entry_points(group="napari.manifest")
           if e.name == "volvis"]
    if len(eps) != 1 or eps[0].value != "volvis.napari:napari.yaml":
        fail("napari.manifest entry point: %r" % (eps,))
    mf = importlib.resources.files("volvis.napari").joinpath("napari.yaml")
    if not mf.is_file() or "volvis.napari._widget:VolVisWidget" not in mf.read_text():
        fail("the napari manifest %s is missing or not the plug-in's" % mf)
    for mod in ("_reader", "_writer", "_widget"):
        if not importlib.resources.files("volvis.napari").joinpath(mod + ".py").is_file():
            fail("volvis/napari/%s.py is not in the wheel" % mod)
    print("napari: the entry point names %s" % mf)
    print("wheel_check: ok")


if __name__ == "__main__":
    main()
