"""Jupyter: PNG encoding for inline display, and ``volvis.show`` (the
anywidget view of volvis.widgets, else an interactive view with
ipywidgets, degrading to a static image)."""
import os
import tempfile
import threading

import numpy as np

from ._lib import check, cstr, ffi, lib
from .errors import InvalidError

__all__ = ["png_bytes", "read_png", "save_png", "show", "Viewer"]


def _to_image(arr):
    """A (h, w, 3|4) uint8 or float array as a new vv_image (float RGBA)."""
    a = np.asarray(arr)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise InvalidError("expected an (h, w, 3) or (h, w, 4) image, got shape %s" % (a.shape,))
    h, w = a.shape[:2]
    f = a.astype(np.float32) / 255.0 if a.dtype == np.uint8 else a.astype(np.float32)
    if f.shape[2] == 3:
        f = np.concatenate([f, np.ones((h, w, 1), np.float32)], axis=2)
    img = ffi.new("vv_image **")
    check(lib.vv_image_new(img, w, h))
    img = ffi.gc(img[0], lib.vv_image_free)
    f = np.ascontiguousarray(f)
    ffi.memmove(img.rgba, ffi.from_buffer(f), f.nbytes)
    return img


def png_bytes(arr, alpha=None):
    """PNG file bytes of an (h, w, 3|4) image array, encoded by the library
    (vv_image_write_png, libpng) through a temporary file. uint8 values are
    written unchanged; float values as round(255 * clamp(v, 0, 1))."""
    a = np.asarray(arr)
    img = _to_image(a)
    if alpha is None:
        alpha = a.shape[2] == 4
    with tempfile.TemporaryDirectory(prefix="volvis-png-") as d:
        path = os.path.join(d, "image.png")
        check(lib.vv_image_write_png(img, cstr(path), 1.0, 1 if alpha else 0))
        with open(path, "rb") as f:
            return f.read()


def _in_kernel():
    try:
        from IPython import get_ipython
    except ImportError:
        return False
    ip = get_ipython()
    return ip is not None and getattr(ip, "kernel", None) is not None


class Viewer:
    """The interactive view of :func:`show`: an image, azimuth/elevation/zoom
    sliders and a mode menu (ipywidgets). While a slider moves, frames are
    drawn by the Navigator's preview renderer (vv_preview: a reduced ray
    cast chosen to hold ``budget`` seconds a frame by the measured times);
    when input stops for ``refine_after`` seconds the full renderer draws
    the final image. ``viewer.widget`` is the ipywidgets box; ``viewer.world``
    the World shown (its view is changed by the controls)."""

    def __init__(self, world, renderer=None, size=None, budget=1 / 15, refine_after=0.3,
                 **options):
        import ipywidgets as widgets
        from .render import render
        from .world import World
        if not isinstance(world, World):
            world = World.for_volume(world)
        self.world = world
        if size is not None:
            world.view.size = size
        self._render = render
        self._renderer = renderer
        self._options = options
        self._base = world.view.copy()
        self._budget = budget
        self._refine_after = refine_after
        self._timer = None
        self._lock = threading.Lock()
        name = renderer if isinstance(renderer, str) else (world.renderer or "raycast")
        out = ffi.new("vv_preview **")
        check(lib.vv_preview_new(out, cstr(name)))
        self._preview = ffi.gc(out[0], lib.vv_preview_free)
        self._policy = ffi.new("vv_preview_policy *")
        lib.vv_preview_policy_init(self._policy)
        w, h = world.view.size
        self.image = widgets.Image(format="png", width=w, height=h)
        self.azimuth = widgets.FloatSlider(value=0, min=-180, max=180, step=1,
                                           description="azimuth")
        self.elevation = widgets.FloatSlider(value=0, min=-89, max=89, step=1,
                                             description="elevation")
        self.zoom = widgets.FloatSlider(value=1, min=0.25, max=8, step=0.05,
                                        description="zoom")
        self.status = widgets.Label(value="")
        for s in (self.azimuth, self.elevation, self.zoom):
            s.observe(self._moved, names="value")
        self.widget = widgets.VBox([self.image, widgets.HBox([self.azimuth, self.elevation]),
                                    widgets.HBox([self.zoom, self.status])])
        self.refine()

    def _apply_view(self):
        v = self._base.copy()
        v.turn(self.azimuth.value, self.elevation.value, self.zoom.value)
        self.world.view = v

    def _moved(self, change):
        with self._lock:
            self._apply_view()
            self._draw_preview()
            if self._timer is not None:
                self._timer.cancel()
            self._timer = threading.Timer(self._refine_after, self.refine)
            self._timer.daemon = True
            self._timer.start()

    def _draw_preview(self):
        import time
        kind = lib.vv_preview_policy_choose(self._policy, self._budget)
        vw, vh = self.world.view.size
        pw, ph = ffi.new("int *"), ffi.new("int *")
        lib.vv_preview_size(kind, vw, vh, pw, ph)
        img = ffi.new("vv_image **")
        check(lib.vv_image_new(img, pw[0], ph[0]))
        img = ffi.gc(img[0], lib.vv_image_free)
        t0 = time.perf_counter()
        wc = self.world._c
        check(lib.vv_preview_render(self._preview, wc, ffi.addressof(wc, "view"), kind, ffi.NULL,
                                    img))
        dt = time.perf_counter() - t0
        if not lib.vv_preview_last_warmup(self._preview):
            lib.vv_preview_policy_record(self._policy, kind, dt)
        a = np.empty((ph[0], pw[0], 4), np.uint8)
        lib.vv_image_to_8bit(img, 4, 1.0, ffi.from_buffer("uint8_t[]", a))
        self.image.value = png_bytes(a)
        self.status.value = "%s %.0f ms" % (ffi.string(lib.vv_preview_kind_name(kind)).decode(),
                                            1000 * dt)

    def refine(self):
        """Draws the full-quality image of the current view."""
        import time
        t0 = time.perf_counter()
        img = self._render(self.world, renderer=self._renderer, **self._options)
        self.image.value = png_bytes(img)
        self.status.value = "full %.0f ms" % (1000 * (time.perf_counter() - t0))

    def _ipython_display_(self):
        from IPython.display import display
        display(self.widget)


def show(world, renderer=None, size=None, interactive=None, **options):
    """Shows a World (or a Volume or an array, in the default scene) in a
    notebook. In a Jupyter kernel with anywidget installed: the
    :class:`volvis.widgets.View` widget (drag, wheel and touch on the image;
    the frame policy of ``volvis serve``), unless renderer options are
    given. Else with ipywidgets: the older :class:`Viewer` (sliders orbit and
    zoom the view; previews while moving, refinement when input stops; kept
    for environments without anywidget, such as Debian's ipywidgets 6).
    Elsewhere, or with ``interactive=False``:
    the rendered image, displayed inline when IPython is present. The
    environment variable VOLVIS_WIDGETS=0 asks for the static image (for
    headless runs such as ``jupyter nbconvert --execute``, whose client
    cannot open the widgets of Debian's ipywidgets 6). Returns the View,
    the Viewer or the image."""
    from .render import render
    from .volume import Volume
    from .world import World
    if not isinstance(world, World):
        world = World.for_volume(world if isinstance(world, Volume) else Volume(world))
    if interactive is None:
        interactive = _in_kernel() and os.environ.get("VOLVIS_WIDGETS", "1") != "0"
    if interactive:
        try:
            from .widgets import View
        except ImportError:
            View = None
        if View is not None and not options:
            v = View(world, renderer=renderer, size=size or tuple(world.view.size))
            try:
                from IPython.display import display
                display(v)
            except ImportError:
                pass
            return v
        try:
            import ipywidgets  # noqa: F401
        except ImportError:
            interactive = False
    if interactive:
        v = Viewer(world, renderer=renderer, size=size, **options)
        try:
            from IPython.display import display
            display(v.widget)
        except ImportError:
            pass
        return v
    img = render(world, renderer=renderer, size=size, **options)
    try:
        from IPython.display import Image as IPImage, display
        if _in_kernel():
            display(IPImage(data=png_bytes(img)))
    except ImportError:
        pass
    return img


def read_png(path):
    """Reads an 8- or 16-bit PNG (vv_image_read_png) as an (h, w, 4) uint8
    array (RGBA; A = 255 when the file has none). Errors: FileError,
    FormatError, LimitError."""
    img = ffi.new("vv_image **")
    check(lib.vv_image_read_png(img, cstr(path)))
    img = ffi.gc(img[0], lib.vv_image_free)
    a = np.empty((img.height, img.width, 4), np.uint8)
    lib.vv_image_to_8bit(img, 4, 1.0, ffi.from_buffer("uint8_t[]", a))
    return a


def save_png(image, path, alpha=None):
    """Writes an (h, w, 3|4) image array as a PNG, atomically
    (vv_image_write_png); alpha None keeps the array's channels."""
    a = np.asarray(image)
    img = _to_image(a)
    if alpha is None:
        alpha = a.shape[2] == 4
    check(lib.vv_image_write_png(img, cstr(path), 1.0, 1 if alpha else 0))
