#!/usr/bin/env python3
"""The napari plug-in's "VolVis 3-D" widget on a large OME-Zarr pyramid
(docs/python.md, "napari"): which level napari's own 3-D view draws, the
widget's first and final frame times and nodes per level at two zooms,
`volvis render --lod 1` of the same World and view timed beside it, and the
PSNR between the two.

Usage (under Xvfb, .venv's python, the build tree's package):
  PYTHONPATH=build/release/python xvfb-run -a .venv/bin/python \\
      bench/bench_napari_lod.py N OUT_DIR [CLI] [--store PATH --contrast LO:HI]
makes OUT_DIR/bN.raw (N^3 u8: shells and a lattice of bright points every
8 voxels, written slab by slab) and OUT_DIR/bN.ome.zarr (volvis convert:
its pyramid), unless they exist, then measures. --store measures an
existing pyramid instead (e.g. bench/remote_2048.py's u16 phantom), drawn
with the layer's contrast limits LO:HI (default 90:255, the u8 store's).
"""
import os
import subprocess
import sys
import time

import numpy as np


def make(n, out_dir, cli):
    raw = os.path.join(out_dir, "b%d.raw" % n)
    store = os.path.join(out_dir, "b%d.ome.zarr" % n)
    if not os.path.exists(store):
        y, x = np.ogrid[:n, :n]
        with open(raw, "wb") as f:
            for z0 in range(0, n, 32):
                z = np.arange(z0, min(n, z0 + 32))[:, None, None]
                r = np.sqrt((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
                slab = ((60 + 40 * np.cos(r / (n / 40))) * (r < 0.47 * n)).astype(np.uint8)
                slab[(z % 8 == 0) & (y % 8 == 0) & (x % 8 == 0) & (r < 0.47 * n)] = 255
                f.write(slab.tobytes())
        subprocess.run([cli, "convert", "-q", "--raw", "%dx%dx%d:u8" % (n, n, n), raw, store],
                       check=True)
        os.remove(raw)
    return store


def main():
    args, opts = [], {}
    it = iter(sys.argv[1:])
    for x in it:
        if x in ("--store", "--contrast"):
            opts[x] = next(it)
        else:
            args.append(x)
    n, out_dir = int(args[0]), args[1]
    cli = args[2] if len(args) > 2 else "build/release/volvis"
    contrast = tuple(float(c) for c in opts.get("--contrast", "90:255").split(":"))
    os.makedirs(out_dir, exist_ok=True)
    t0 = time.perf_counter()
    store = opts["--store"] if "--store" in opts else make(n, out_dir, cli)
    print("store %s (%.1f s to make or find)" % (store, time.perf_counter() - t0))

    import napari
    import npe2
    from qtpy.QtWidgets import QApplication

    import volvis
    from volvis.napari import MANIFEST
    from volvis.napari._widget import VolVisWidget, viewer_camera
    pm = npe2.PluginManager.instance()
    if "volvis" not in pm._manifests:
        pm.register(npe2.PluginManifest.from_file(MANIFEST))
    v = napari.Viewer(show=True)
    layer = v.open(store, plugin="volvis")[0]
    layer.rendering = "translucent"
    layer.colormap = "viridis"
    layer.contrast_limits = contrast
    v.dims.ndisplay = 3
    app = QApplication.instance()
    for _ in range(30):
        app.processEvents()
        time.sleep(0.02)
    print("levels %s; napari's 3-D view draws level %d" % (
        [d.shape for d in layer.data], layer.data_level))
    cam = viewer_camera(v)
    cam.angles = (0, 25, 80)
    w = VolVisWidget(v, max_side=512, debounce_ms=10)
    scene = os.path.join(out_dir, "scene.json")
    png = os.path.join(out_dir, "cli.png")
    for zoom in (1.0, 4.0):
        cam.zoom = cam.zoom * zoom
        before = w.finals
        t0 = time.perf_counter()
        w.request()
        first = None
        while w.finals == before and time.perf_counter() - t0 < 600:
            app.processEvents()
            time.sleep(0.005)
            if first is None and w.frame is not None and w.frame["pass"] == "coarse" \
                    and w.frame["generation"] == w._generation:
                first = time.perf_counter() - t0
        f = w.frame
        print("zoom x%g: first frame %.2f s, final %.2f s at %dx%d, nodes per level %s"
              % (zoom, first or -1, f["seconds"], *f["view"].size, f["lod"]["nodes"]))
        world = f["world"].clone()
        world.view = f["view"]
        world.save(scene, volume_files=[store])
        t0 = time.perf_counter()
        subprocess.run([cli, "render", scene, "--lod", "1", "--size", "%dx%d" % f["view"].size,
                        "-o", png], check=True, capture_output=True)
        print("  volvis render --lod 1 of the same World and view: %.2f s"
              % (time.perf_counter() - t0))
        ref = volvis.read_png(png)
        img = w.image[:, ::-1] if f["mirror"] else w.image
        mse = np.mean((img[..., :3].astype(float) - ref[..., :3]) ** 2)
        print("  PSNR widget vs volvis render: %s dB" % (
            "inf" if mse == 0 else "%.2f" % (10 * np.log10(255 ** 2 / mse))))
        volvis.save_png(w.image, os.path.join(out_dir, "widget_zoom%g.png" % zoom))


if __name__ == "__main__":
    main()
