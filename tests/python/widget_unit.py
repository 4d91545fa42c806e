"""volvis.widgets.View without a browser (test_python_widget): the page's
messages (the ones python/volvis/_widget.js sends) are handed to the
widget's comm as the kernel hands a comm_msg over, and the frames it sends
are caught.

Checked on the CT head of ../shared/data: the first full frame; a drag gives
reduced frames (the Navigator's preview sizes), moves the camera traits as
vv_nav_view_rotate moves a copy of the camera, and ends with a full frame;
50 motions at once are drawn as fewer frames, the last one the newest
camera (newest wins); setting mode, preset and camera from Python
re-renders; snapshot() is (h, w, 4) uint8 and equals `volvis render` of the
World saved as a scene, bit for bit; the JPEG of the final frame is within
JPEG's loss of it; bad traits are refused; the slice views; a .vvb
pyramid out of core (previews, then the full frame equal to volvis.render);
a three-channel OME-Zarr store written by zarr-python out of core (one
object of every channel, each ball in its colour, equal to volvis.render).

Usage: widget_unit.py [BUILD_PYTHON_DIR VOLVIS_CLI OUT_DIR]. Exit 77 when
anywidget or Pillow is missing (.venv from scripts/install-deps.sh test)."""
import io
import json
import math
import os
import subprocess
import sys
import time

import widget_setup
from widget_setup import HEAD, ROOT

PYDIR, OUT, args = widget_setup.start("widget_unit", ["anywidget", "numpy", "PIL"], n_args=3)
CLI = args[1] if len(args) > 1 else str(ROOT / "build" / "release" / "volvis")
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

import volvis  # noqa: E402
from volvis import widgets  # noqa: E402
from volvis._lib import ffi, lib  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)


def psnr(a, b):
    d = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2)
    return math.inf if d == 0 else 10 * math.log10(255.0 ** 2 / d)


class Catcher:
    """Stands for the comm: keeps what the widget sends."""

    def __init__(self):
        self.frames = []

    def __call__(self, content, buffers=None):
        self.frames.append((content, list(buffers or [])))

    def of(self, kind):
        return [f for f in self.frames if f[0].get("type") == kind]

    def wait_sharp(self, gen_at_least, timeout=30):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for h, b in reversed(self.frames):
                if h.get("type") == "frame" and h["sharp"] and h["gen"] >= gen_at_least:
                    return h, b
            time.sleep(0.02)
        return None, None


def msg(v, **content):
    """A custom message of the page, as the kernel's comm hands it over."""
    v.comm.handle_msg({"content": {"comm_id": v.comm.comm_id,
                                   "data": {"method": "custom", "content": content}},
                       "buffers": []})


OUT.mkdir(parents=True, exist_ok=True)
t_start = time.monotonic()
W, H = 256, 192
v = widgets.View(HEAD, size=(W, H), preset="ct-bone")
cat = Catcher()
v.send = cat
check(v.wait(30), "the first full frame is drawn")
check(v.width == W and v.height == H and v.preset == "ct-bone", "size and preset traits")
check(v.tf["opacity"] and v.tf["color"], "the tf trait holds the preset's points")
own = volvis.World.open(HEAD).objects[0].tf.opacity
check(len(v._own_tfs) == 1 and np.allclose(
    volvis.TransferFunction._at(v._own_tfs[0], None).opacity, own),
    "the World's own transfer function is kept for preset ''")
check(v.mode == "composite" and "mip" in v.modes and "ct-bone" in v.presets, "mode, modes, presets")

# the page asks for the newest frame when it shows the widget
check([h["sharp"] for h, _ in cat.of("frame")] == [True], "one frame: the full one")
cat.frames.clear()
msg(v, type="ready")
check(len(cat.of("frame")) == 1 and cat.of("frame")[0][0]["sharp"], "ready: the newest frame again")
h0, b0 = cat.of("frame")[0]
img0 = np.asarray(Image.open(io.BytesIO(b0[0])))
check(h0["mime"] == "image/jpeg" and img0.shape == (H, W, 3), "a JPEG frame of the view's size")

# ---- a drag: previews, then the full frame; the camera traits follow --------
eye0, at0, up0 = list(v.eye), list(v.at), list(v.up)
ref = volvis.View(eye=eye0, at=at0, up=up0, fov=v.fov, size=(W, H))
cat.frames.clear()
for i in range(12):
    msg(v, type="motion", motion="rotate", dx=6, dy=2, factor=1)
    lib.vv_nav_view_rotate(ref._c, 6, 2)
    time.sleep(0.06)
check(all(np.allclose(getattr(v, k), getattr(ref, k), atol=1e-9) for k in ("eye", "at", "up")),
      "the camera traits after the drag are vv_nav_view_rotate's of a copy")
check(np.allclose(v.eye, v.world.view.eye) and not np.allclose(v.eye, eye0, atol=1e-3),
      "the eye moved, and the World's view is the traits'")
r0 = np.linalg.norm(np.subtract(eye0, at0))
check(abs(np.linalg.norm(np.subtract(v.eye, v.at)) - r0) < 1e-6 * r0,
      "rotation keeps the eye's distance from the look-at point")
moving = [h for h, _ in cat.of("frame") if not h["sharp"]]
check(len(moving) >= 1, "frames while dragging: %d" % len(moving))
check(all(h["kind"].startswith("raycast_1/") and h["width"] < W and h["mime"] == "image/jpeg"
          for h in moving), "they are reduced ray casts: %s" % sorted({h["kind"] for h in moving}))
for h, b in cat.of("frame"):
    if not h["sharp"]:
        pw, ph = ffi.new("int *"), ffi.new("int *")
        k = ffi.new("vv_preview_kind *")
        lib.vv_preview_kind_parse(h["kind"].encode(), k)
        lib.vv_preview_size(k[0], W, H, pw, ph)
        check(Image.open(io.BytesIO(b[0])).size == (pw[0], ph[0]) == (h["width"], h["height"]),
              "a %s frame is %dx%d" % (h["kind"], pw[0], ph[0]))
        break
gen = v._gen
msg(v, type="end")
hs, bs = cat.wait_sharp(gen)
check(hs is not None, "the end of the drag gives a full frame")
snap = v.snapshot()
check(snap.shape == (H, W, 4) and snap.dtype == np.uint8, "snapshot(): (%d, %d, 4) uint8" % (H, W))
jpeg = np.asarray(Image.open(io.BytesIO(bs[0])))
p = psnr(jpeg, snap[:, :, :3])
check(p > 30, "the final JPEG is the snapshot within JPEG's loss: %.1f dB" % p)

# snapshot() against `volvis render` of the same World (saved as a scene)
scene = OUT / "widget_scene.json"
v.world.save(str(scene), volume_files=[str(HEAD)])
png = OUT / "widget_cli.png"
r = subprocess.run([CLI, "render", str(scene), "-o", str(png)], capture_output=True, text=True)
check(r.returncode == 0, "volvis render of the saved scene: %s" % r.stderr.strip()[:200])
if r.returncode == 0:
    cli_img = volvis.read_png(str(png))
    p = psnr(cli_img[:, :, :3], snap[:, :, :3])
    check(np.array_equal(cli_img[:, :, :3], snap[:, :, :3]),
          "snapshot() equals volvis render bit for bit (%s dB)" % p)
    volvis.save_png(snap, str(OUT / "widget_snapshot.png"))
Image.fromarray(jpeg).save(OUT / "widget_frame.png")

# ---- newest wins: 50 motions at once are drawn as fewer frames ---------------
cat.frames.clear()
s0 = v.stats
for i in range(50):
    msg(v, type="motion", motion="zoom", dx=0, dy=0, factor=1.01)
    msg(v, type="motion", motion="rotate", dx=-3, dy=0, factor=1)
gen = v._gen
msg(v, type="end")
hs, bs = cat.wait_sharp(gen)
s1 = v.stats
drawn = s1["frames"] - s0["frames"]
check(s1["inputs"] - s0["inputs"] == 100, "100 motions taken")
check(hs is not None and drawn < 100, "100 motions drawn as %d frames (newest wins)" % drawn)
check(hs is not None and hs["gen"] == v._gen, "the last frame shows the newest camera")
check([h["seq"] for h, _ in cat.of("frame")] == sorted(h["seq"] for h, _ in cat.of("frame")),
      "frames go out in order")
snap = v.snapshot()
p = psnr(np.asarray(Image.open(io.BytesIO(bs[0]))), snap[:, :, :3])
check(p > 30, "its JPEG is the newest camera's snapshot: %.1f dB" % p)

# ---- a full frame in progress is cancelled when the camera moves again ---------
v.width, v.height = 1024, 768
v.wait()
cancelled = False
for attempt in range(5):
    c0 = v.stats["cancelled"]
    old = v._cancel  # None, or the finished frame's until its thread lets it go
    v.orbit(3)
    end = time.monotonic() + 10
    while (v._cancel is None or v._cancel is old) and time.monotonic() < end:
        time.sleep(0.001)
    msg(v, type="motion", motion="rotate", dx=2, dy=0, factor=1)
    msg(v, type="end")
    v.wait()
    if v.stats["cancelled"] > c0:
        cancelled = True
        break
check(cancelled, "a full frame is cancelled by a newer camera (attempt %d)" % (attempt + 1))
v.width, v.height = W, H
v.wait()

# ---- properties set from Python re-render -------------------------------------
for name, value in (("mode", "mip"), ("preset", "ct-soft-tissue"),
                    ("eye", list(np.add(v.at, [0.0, -400.0, 0.0]))), ("up", [0.0, 0.0, 1.0]),
                    ("fov", 40.0)):
    gen = v._gen
    n = v.stats["full"]
    setattr(v, name, value)
    hs, _ = cat.wait_sharp(gen + 1)
    check(hs is not None and v.stats["full"] > n, "setting %s from Python re-renders" % name)
check(np.allclose(v.world.view.eye, v.eye) and abs(v.world.view.fov - 40) < 1e-9,
      "the camera traits set the World's view")
v.wait()
snap = v.snapshot()
want = volvis.render(v.world.clone(), renderer="raycast")
check(np.array_equal(snap, want), "snapshot() after the changes equals volvis.render (mip)")
check(v.preset == "ct-soft-tissue" and v.tf["opacity"] == [[float(x) for x in p]
      for p in volvis.TransferFunction.preset("ct-soft-tissue", v.world.objects[0].volume).opacity],
      "the tf trait follows the preset")
tf = {"opacity": [[0, 0], [300, 0], [1500, 0.8]], "color": [[0, 1, 0.5, 0.2], [1500, 1, 1, 1]]}
v.mode = "composite"
gen = v._gen
v.tf = tf
hs, _ = cat.wait_sharp(gen + 1)
check(hs is not None and v.preset == "" and
      np.allclose(v.world.objects[0].tf.opacity, tf["opacity"]),
      "setting tf re-renders with those points, and clears preset")
v.preset = "ct-bone"
check(v.tf["opacity"] != tf["opacity"], "a preset replaces the tf set")
gen = v._gen
v.preset = ""
hs, _ = cat.wait_sharp(gen + 1)
check(hs is not None and v.tf["opacity"] == [[float(a), float(b)] for a, b in tf["opacity"]] and
      np.allclose(v.world.objects[0].tf.opacity, tf["opacity"]),
      "preset '' puts back the last tf set, and re-renders")
v.orbit(30, 10, 1.2)
check(v.wait() and np.allclose(v.eye, v.world.view.eye), "orbit() moves the traits and re-renders")

# ---- refusals ----------------------------------------------------------------------
for name, value in (("mode", "bogus"), ("preset", "no-such"), ("fov", 200.0), ("width", 0),
                    ("up", [0.0, 0.0, 0.0]), ("slice_index", {"axial": "x"}),
                    ("slice_index", {"oblique": 3})):
    before = getattr(v, name)
    try:
        setattr(v, name, value)
        ok = False
    except Exception as e:
        ok = True
        why = str(e).splitlines()[0][:80]
    check(ok and (name == "up" or getattr(v, name) == before),
          "%s=%r is refused (%s)" % (name, value, why if ok else "accepted"))
check(np.allclose(v.world.view.up, v.up) and np.linalg.norm(v.up) > 0.5,
      "a refused camera leaves the World's view and the traits as they were")
eye = list(v.eye)
msg(v, type="motion", motion="rotate", dx=float("nan"), dy=1e300, factor=1)
msg(v, type="motion", motion="fly")
msg(v, type="bogus")
msg(v, type="end")
check(v.wait() and all(math.isfinite(x) for x in v.eye), "bad motions leave a finite camera")

# ---- slices ---------------------------------------------------------------------------
cat.frames.clear()
v.slices = True
end = time.monotonic() + 20
while len(cat.of("slice")) < 3 and time.monotonic() < end:
    time.sleep(0.05)
sl = {h["axis"]: (h, b) for h, b in cat.of("slice")}
check(set(sl) == {"axial", "coronal", "sagittal"}, "slices=True sends the three slice views")
check(v.slice_count == {"axial": 108, "coronal": 256, "sagittal": 256},
      "slice counts are the volume's: %s" % v.slice_count)
if "axial" in sl:
    h, b = sl["axial"]
    check(h["index"] == 54 and Image.open(io.BytesIO(b[0])).size == (h["width"], h["height"]),
          "the axial view starts in the middle slice")
cat.frames.clear()
msg(v, type="slice", axis="axial", index=10)
end = time.monotonic() + 20
while not cat.of("slice") and time.monotonic() < end:
    time.sleep(0.05)
check(v.slice_index["axial"] == 10 and any(h["axis"] == "axial" and h["index"] == 10
                                           for h, _ in cat.of("slice")),
      "a slice message moves the axial view")

v.close()
check(not v._thread.is_alive(), "close() stops the render thread")
for bad, err, text in (("/nonexistent/x.nrrd", volvis.FileError, "/nonexistent/x.nrrd"),
                       (42, volvis.InvalidError, "got int")):
    try:
        widgets.View(bad)
        got = None
    except Exception as e:
        got = e
    check(isinstance(got, err) and text in str(got) and "\n" not in str(got),
          "View(%r): %s" % (bad, got))
w = volvis.World.open(HEAD)
w.view.size = (64, 48)
shown = volvis.show(w, interactive=True)
check(isinstance(shown, widgets.View) and shown.width == 64 and shown.wait(30),
      "volvis.show gives the View when anywidget is installed")
shown.close()
# ---- a file out of core (a .vvb pyramid): previews read progressively, the full
# frame by level of detail equals volvis.render of the same World
vvb = OUT / "head.vvb"
r = subprocess.run([CLI, "convert", str(HEAD), str(vvb)], capture_output=True, text=True)
check(r.returncode == 0, "volvis convert to .vvb: %s" % r.stderr.strip()[:200])
if r.returncode == 0:
    v = widgets.View(volvis.World.open(vvb, memory="out_of_core"), size=(128, 96))
    cat = Catcher()
    v.send = cat
    check(v.wait(60), "out of core: the first full frame")
    for i in range(6):
        msg(v, type="motion", motion="rotate", dx=8, dy=0, factor=1)
        time.sleep(0.05)
    gen = v._gen
    msg(v, type="end")
    hs, _ = cat.wait_sharp(gen, 60)
    check(hs is not None and any(not h["sharp"] for h, _ in cat.of("frame")),
          "out of core: reduced frames while dragging, then the full one (%s)"
          % [h["kind"] for h, _ in cat.of("frame")])
    check(np.array_equal(v.snapshot(), volvis.render(v.world.clone())),
          "out of core: snapshot() equals volvis.render")
    v.close()

# ---- a store of three channels out of core (issue 89), written by zarr-python 3:
# one object of every channel, each in its omero colour, equal to volvis.render
try:
    import zarr
except ImportError:
    zarr = None
    print("skipped: the three-channel store out of core (zarr-python 3 is not installed)")
if zarr is not None:
    store = str(OUT / "three.ome.zarr")
    g = zarr.open_group(store, mode="w")
    z, y, x = np.mgrid[0:32, 0:48, 0:96]
    vox = np.zeros((3, 32, 48, 96), np.uint16)
    for c in range(3):  # a ball a channel, left to right
        ball = (z - 16) ** 2 + (y - 24) ** 2 + (x - (16 + 32 * c)) ** 2 < 12 ** 2
        vox[c][ball] = 3000
    vox += np.uint16(100)
    lv, ds = vox, []
    for k in range(2):
        a = g.create_array(str(k), shape=lv.shape, dtype=lv.dtype, chunks=(1, 16, 16, 16))
        a[:] = lv
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [1.0] + [2.0 ** k] * 3}]})
        lv = lv[:, ::2, ::2, ::2]
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": "c", "type": "channel"}] + [{"name": n, "type": "space"} for n in "zyx"],
        "datasets": ds}], "omero": {"channels": [
            {"label": n, "color": col, "active": True,
             "window": {"min": 0, "max": 4000, "start": 200, "end": 3000}}
            for n, col in (("r", "FF0000"), ("g", "00FF00"), ("b", "0000FF"))]}}
    w3 = volvis.World.open(store, memory="out_of_core", memory_limit="8M")
    check(w3.opened["out_of_core"] and w3.opened["n_channels"] == 3 and
          w3.objects[0]._c.n_channels == 3,
          "a store of three channels out of core opens as one object of them all")
    v = widgets.View(w3, size=(192, 96))
    check(v.wait(60), "three channels out of core: the first full frame")
    snap = v.snapshot()
    Image.fromarray(snap).save(OUT / "three_channels.png")
    check(np.array_equal(snap, volvis.render(v.world.clone())),
          "three channels out of core: snapshot() equals volvis.render")
    # the default view looks at the front (+x to the left, as an anatomical
    # front view): the balls red, green, blue from right to left
    rgb = snap[:, :, :3].astype(float)
    where = []
    for c in range(3):
        own = (rgb[:, :, c] > 40) & (rgb[:, :, c] > 1.5 * np.delete(rgb, c, axis=2).max(axis=2))
        where.append((int(own.sum()), float(np.nonzero(own)[1].mean()) if own.any() else -1.0))
    check(all(n > 50 for n, _ in where) and where[0][1] > where[1][1] > where[2][1],
          "each channel's ball in its own colour, in its place (pixels, mean column: %s)"
          % [(n, round(x, 1)) for n, x in where])
    v.close()

print("widget_unit: %.1f s, %d failures" % (time.monotonic() - t_start, len(failures)))
sys.exit(1 if failures else 0)
