"""The Jupyter widget of VolVis: ``volvis.widgets.View(world_or_path, ...)``
(anywidget: JupyterLab 4, Notebook 7, VS Code; docs/python.md, "The
Jupyter widget").

    from volvis.widgets import View
    v = View("head.nrrd", mode="mip", size=(512, 384), slices=True)
    v                      # the last expression of a cell shows it
    v.eye, v.at, v.up      # the camera, read after a drag
    v.preset = "ct-bone"   # re-renders
    img = v.snapshot()     # (h, w, 4) uint8: the full-quality frame

Frames follow the policy of ``volvis serve`` (apps/volvis/serve/
serve_session.c): while the pointer drags, the reduced ray cast that the
Navigator's frame-rate policy (vv_preview_policy) picks for a 42 ms budget,
at most 30 frames a second, JPEG quality 60; when the drag ends (or no input
came for 0.5 s), the full frame of the World's renderer (what ``volvis
render`` draws), JPEG quality 90. Frames are drawn on one render thread from
snapshots of the World (vv_world_clone): input arriving during a frame only
moves the camera, so the next frame shows the newest camera and the ones in
between are never drawn (newest wins); a full frame is cancelled when the
camera moves again. The page draws a frame only when it is newer than the
one on screen.
"""
import io
import math
import pathlib
import threading
import time

import numpy as np

from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import Volume
from .world import TransferFunction, World, mode_code, tf_presets

try:
    import anywidget
    import traitlets as tr
except ImportError as e:  # pragma: no cover - reported on import
    raise ImportError("volvis.widgets needs anywidget (pip install 'volvis[widget]' or "
                      "pip install anywidget): %s" % e) from e

__all__ = ["View", "PREVIEW_BUDGET", "MIN_PERIOD", "STILL_AFTER", "JPEG_MOVING", "JPEG_STILL",
           "PROGRESSIVE_CHUNKS"]

_HERE = pathlib.Path(__file__).resolve().parent

#: Seconds a frame may take while moving (volvis serve: SRV_PREVIEW_BUDGET).
PREVIEW_BUDGET = 0.042
#: At most 30 frames a second while moving (SRV_MIN_PERIOD).
MIN_PERIOD = 1.0 / 30
#: Input older than this counts as stopped even without an "end" (SRV_STILL_AFTER).
STILL_AFTER = 0.5
#: JPEG qualities of moving and still frames (SRV_JPEG_MOVING, SRV_JPEG_STILL).
JPEG_MOVING = 60
JPEG_STILL = 90
#: Chunks a reduced frame of a file out of core may read (SRV_PROGRESSIVE_CHUNKS).
PROGRESSIVE_CHUNKS = 64

_MODES = ("composite", "mip", "minip", "xray", "iso", "attenuated-mip")
_AXES = ("axial", "coronal", "sagittal")
_MOTIONS = {"rotate": "VV_NAV_ROTATE", "pan": "VV_NAV_PAN", "zoom": "VV_NAV_ZOOM"}


def _encode(rgb, quality):
    """(bytes, mime) of an (h, w, 3) uint8 image: JPEG by Pillow, else PNG
    by the library (vv_image_write_png)."""
    try:
        from PIL import Image
    except ImportError:
        from .notebook import png_bytes
        return png_bytes(rgb), "image/png"
    buf = io.BytesIO()
    Image.fromarray(rgb, "RGB").save(buf, "JPEG", quality=int(quality))
    return buf.getvalue(), "image/jpeg"


def _to_rgb8(img, channels=3):
    """An 8-bit copy of a vv_image (gamma 1, as volvis serve encodes)."""
    a = np.empty((img.height, img.width, channels), np.uint8)
    lib.vv_image_to_8bit(img, channels, 1.0, ffi.from_buffer("uint8_t[]", a))
    return a


def _world_of(what, mode, size):
    if isinstance(what, World):
        return what
    if isinstance(what, (Volume, np.ndarray)):
        return World.for_volume(what, mode=mode or "composite", size=size)
    if isinstance(what, (str, pathlib.PurePath)) or hasattr(what, "__fspath__"):
        return World.open(what)
    raise InvalidError("View: expected a World, a Volume, an array or a path, got %s"
                       % type(what).__name__)


class View(anywidget.AnyWidget):
    """An interactive 3-D view of a World in a notebook (anywidget).

    ``View(world_or_path, mode=None, preset=None, size=None,
    renderer=None, slices=False)``: a :class:`volvis.World`, a
    :class:`volvis.Volume`, a numpy array (the default scene of ``volvis
    render FILE``) or a path :meth:`volvis.World.open` takes (a volume file,
    a folder, a scene). The World is shown and changed in place
    (``view.world``). size: (width, height) of the frame in pixels (None:
    the World's view size, (512, 384) for a path, a Volume or an array).
    renderer: a registry name (None: the World's, else "raycast").

    Synchronised properties (set them from Python to re-render; read them
    after the user drags to get the new values): ``eye``, ``at``, ``up``
    (world units, [x, y, z]) and ``fov`` (degrees): the World's camera
    (vv_view); ``mode`` ("composite", "mip", "minip", "xray", "iso",
    "attenuated-mip") of every
    volume object; ``preset`` (a :func:`volvis.tf_presets` name placed on
    each volume's values, or "": the transfer functions the World had, or the
    last ``tf`` set);
    ``tf``: the transfer function of the first volume object as
    ``{"opacity": [[value, a], ...], "color": [[value, r, g, b], ...],
    "unit_distance": d}`` (setting it sets every volume object's);
    ``width``, ``height`` (pixels of the frame); ``slices`` (show axial,
    coronal and sagittal slice views beside the 3-D view) and
    ``slice_index`` ({"axial": k, ...}; -1 the middle slice). Read only:
    ``presets``, ``modes``, ``slice_count``, ``status`` (the last frame's
    representation and time), ``frame_seq``.

    The render thread starts with the widget and stops with :meth:`close`.
    Thread-safety: use one View from one thread (the kernel's)."""

    _esm = _HERE / "_widget.js"
    _css = _HERE / "_widget.css"

    eye = tr.List(tr.Float(), minlen=3, maxlen=3).tag(sync=True)
    at = tr.List(tr.Float(), minlen=3, maxlen=3).tag(sync=True)
    up = tr.List(tr.Float(), minlen=3, maxlen=3).tag(sync=True)
    fov = tr.Float(30.0).tag(sync=True)
    mode = tr.Unicode("composite").tag(sync=True)
    preset = tr.Unicode("").tag(sync=True)
    tf = tr.Dict().tag(sync=True)
    width = tr.Int(512).tag(sync=True)
    height = tr.Int(384).tag(sync=True)
    slices = tr.Bool(False).tag(sync=True)
    slice_index = tr.Dict().tag(sync=True)
    slice_count = tr.Dict().tag(sync=True)
    presets = tr.List(tr.Unicode()).tag(sync=True)
    modes = tr.List(tr.Unicode()).tag(sync=True)
    status = tr.Unicode("").tag(sync=True)
    frame_seq = tr.Int(0).tag(sync=True)

    def __init__(self, world, mode=None, preset=None, size=None, renderer=None,
                 slices=False, **kw):
        if size is None and not isinstance(world, World):
            size = (512, 384)
        w = _world_of(world, mode, size)
        if size is not None:
            w.view.size = size
        self._world = w
        self._renderer = renderer or w.renderer or "raycast"
        out = ffi.new("vv_preview **")
        check(lib.vv_preview_new(out, cstr(self._renderer)))
        self._preview = ffi.gc(out[0], lib.vv_preview_free)
        if (w.renderer or "raycast") == self._renderer:
            # the World's render settings (options, quality) are its renderer's
            check(lib.vv_renderer_apply_settings(lib.vv_preview_final_renderer(self._preview),
                                                 ffi.addressof(w._c, "render")))
        self._policy = ffi.new("vv_preview_policy *")
        lib.vv_preview_policy_init(self._policy)
        self._cond = threading.Condition()
        self._gen = 1            # grows with every change of what the frame shows
        self._drawn_gen = 0      # of the newest frame drawn
        self._sharp_gen = 0      # of the newest full frame
        self._slice_gen = 1      # grows when the slices change
        self._slices_drawn = 0
        self._moving = False
        self._last_input = 0.0
        self._last_preview = -1e9
        self._input_seq = 0
        self._quit = False
        self._cancel = None      # the progress state of the full frame being drawn
        self._full = None        # (gen, (h, w, 4) uint8) of the newest full frame
        self._frame = None       # (header, bytes) of the newest frame sent
        self._slice_frames = {}  # axis -> (header, bytes)
        self._syncing = False
        self._stats = {"frames": 0, "previews": 0, "full": 0, "cancelled": 0, "inputs": 0,
                       "kinds": {}}
        v = w.view
        vol = self._first_volume()
        from .render import renderers
        info = renderers.get(self._renderer)
        modes = [m for m in _MODES if info is None or m in info.modes]
        self._syncing = True  # the traits take the World's values; nothing to apply
        super().__init__(eye=list(v.eye), at=list(v.at), up=list(v.up), fov=v.fov,
                         width=v.size[0], height=v.size[1],
                         mode=self._world_mode() if mode is None else mode,
                         presets=tf_presets(), modes=modes, slices=bool(slices),
                         tf=self._tf_dict(vol) if vol is not None else {},
                         slice_index={a: -1 for a in _AXES}, **kw)
        self._syncing = False
        self._keep_own_tfs()
        if mode is not None:
            self._apply_mode(mode)
        if preset:
            self.preset = preset
        self._count_slices()
        self.on_msg(self._on_page_msg)
        self._thread = threading.Thread(target=self._render_main, name="volvis-widget",
                                        daemon=True)
        self._thread.start()

    # ---- the World --------------------------------------------------------
    @property
    def world(self):
        """The World shown (changed in place by the camera, mode and transfer
        function properties). After changing it directly, call :meth:`redraw`."""
        return self._world

    def _volume_objects(self):
        wc = self._world._c
        return [wc.objects[i] for i in range(wc.n_objects)
                if wc.objects[i].type == lib.VV_OBJECT_VOLUME and
                wc.objects[i].volume != ffi.NULL]

    def _first_volume(self):
        objs = self._volume_objects()
        return objs[0] if objs else None

    def _world_mode(self):
        o = self._first_volume()
        if o is None:
            return "composite"
        for name in _MODES:
            if mode_code(name) == o.mode:
                return name
        return "composite"

    def _apply_mode(self, name):
        code = mode_code(name)
        wc = self._world._c
        for i in range(wc.n_objects):
            o = wc.objects[i]
            if o.type in (lib.VV_OBJECT_VOLUME, lib.VV_OBJECT_GRID):
                o.mode = code

    @staticmethod
    def _tf_dict(o):
        t = TransferFunction._at(ffi.addressof(o, "tf"), None)
        return {"opacity": [[float(x) for x in p] for p in t.opacity],
                "color": [[float(x) for x in p] for p in t.color],
                "unit_distance": float(t.unit_distance)}

    def redraw(self):
        """Draws the World again (after changing ``view.world`` directly)."""
        with self._cond:
            self._changed_locked(slices=True)

    # ---- property changes from Python or from the page ----------------------
    def _changed_locked(self, moving=False, slices=False):
        self._gen += 1
        if slices:
            self._slice_gen += 1
        if not moving:
            self._moving = False
        if self._cancel is not None:
            lib.vvpy_progress_cancel(self._cancel)
        self._cond.notify_all()

    @tr.validate("mode")
    def _valid_mode(self, proposal):
        m = proposal["value"]
        if m not in _MODES:
            raise tr.TraitError("mode: expected one of %s, got %r" % (", ".join(_MODES), m))
        return m

    @tr.validate("preset")
    def _valid_preset(self, proposal):
        p = proposal["value"]
        if p and p not in tf_presets():
            raise tr.TraitError("preset: expected one of %s, got %r"
                                % (", ".join(tf_presets()), p))
        return p

    @tr.validate("width", "height")
    def _valid_side(self, proposal):
        n = proposal["value"]
        if not 1 <= n <= 4096:
            raise tr.TraitError("width and height: %d is outside 1..4096" % n)
        return n

    @tr.validate("slice_index")
    def _valid_slice_index(self, proposal):
        d = proposal["value"]
        out = {}
        for k, i in d.items():
            if k not in _AXES or isinstance(i, bool) or not isinstance(i, (int, np.integer)):
                raise tr.TraitError("slice_index: expected {axis: int} with axes %s, got %r"
                                    % (", ".join(_AXES), d))
            out[k] = int(i)
        return out

    @tr.validate("fov")
    def _valid_fov(self, proposal):
        f = proposal["value"]
        if not 0 < f < 180:
            raise tr.TraitError("fov: %r degrees is outside (0, 180)" % f)
        return f

    @tr.observe("eye", "at", "up", "fov", "width", "height")
    def _camera_changed(self, change):
        if self._syncing:
            return
        with self._cond:
            v = self._world.view
            old = v.copy()
            try:
                v.eye, v.at, v.up, v.fov = self.eye, self.at, self.up, self.fov
                v.size = (self.width, self.height)
                if not lib.vv_nav_view_valid(v._c):
                    raise tr.TraitError("%s: the camera eye %s, at %s, up %s is degenerate "
                                        "(up parallel to the view direction, or eye = at)"
                                        % (change["name"], self.eye, self.at, self.up))
            except Exception:
                # the World keeps its camera, and the traits show it again
                self._world.view = old
                self._sync_camera()
                raise
            self._changed_locked()

    @tr.observe("mode")
    def _mode_changed(self, change):
        with self._cond:
            self._apply_mode(change["new"])
            self._changed_locked()

    def _keep_own_tfs(self):
        """Keeps the volume objects' transfer functions (preset "" restores them)."""
        self._own_tfs = [ffi.new("vv_tf *", o.tf) for o in self._volume_objects()]

    @tr.observe("preset")
    def _preset_changed(self, change):
        name = change["new"]
        if not name and self._syncing:
            return
        with self._cond:
            for i, o in enumerate(self._volume_objects()):
                if name:
                    check(lib.vv_tf_preset(ffi.addressof(o, "tf"), cstr(name), o.volume))
                elif i < len(self._own_tfs):
                    o.tf = self._own_tfs[i][0]
            o = self._first_volume()
            self._syncing = True
            try:
                if o is not None:
                    self.tf = self._tf_dict(o)
            finally:
                self._syncing = False
            self._changed_locked()

    @tr.observe("tf")
    def _tf_changed(self, change):
        if self._syncing or not change["new"]:
            return
        d = change["new"]
        t = TransferFunction(opacity=d.get("opacity") or None, color=d.get("color") or None,
                             unit_distance=d.get("unit_distance"))
        with self._cond:
            for o in self._volume_objects():
                o.tf = t._value()
            self._keep_own_tfs()
            self._syncing = True
            try:
                self.preset = ""
            finally:
                self._syncing = False
            self._changed_locked()

    @tr.observe("slices", "slice_index")
    def _slices_changed(self, change):
        with self._cond:
            self._slice_gen += 1
            self._cond.notify_all()

    def _sync_camera(self):
        """The camera traits from the World's view (after a drag)."""
        v = self._world.view
        self._syncing = True
        try:
            with self.hold_sync():
                self.eye, self.at, self.up, self.fov = list(v.eye), list(v.at), list(v.up), v.fov
        finally:
            self._syncing = False

    def orbit(self, azimuth=0.0, elevation=0.0, zoom=1.0):
        """Turns the camera as ``volvis render --azimuth --elevation --zoom``
        (degrees; zoom > 1 closer) and re-renders. Returns self."""
        with self._cond:
            self._world.view.turn(azimuth, elevation, zoom)
            self._changed_locked()
        self._sync_camera()
        return self

    # ---- messages of the page -------------------------------------------------
    def _on_page_msg(self, widget, content, buffers):
        """The page's messages: {"type": "ready"} (send the newest frame),
        {"type": "motion", "motion": "rotate"|"pan"|"zoom", "dx", "dy" (pixels
        of the frame), "factor" (zoom, > 1 closer)} while a gesture goes on,
        {"type": "end"} when it ends, {"type": "slice", "axis", "index"}."""
        if not isinstance(content, dict):
            return
        kind = content.get("type")
        if kind == "ready":
            with self._cond:
                frame = self._frame
                slices = list(self._slice_frames.values())
            if frame is not None:
                self.send(*frame)
            for s in slices:
                self.send(*s)
        elif kind == "motion":
            motion = _MOTIONS.get(content.get("motion"))
            if motion is None:
                return
            m = ffi.new("vv_nav_motion *")
            m.kind = getattr(lib, motion)
            m.dx = _num(content.get("dx"), 0.0)
            m.dy = _num(content.get("dy"), 0.0)
            m.factor = _num(content.get("factor"), 1.0)
            t = ffi.new("vv_nav_target *")
            t.kind = lib.VV_NAV_TARGET_VIEW
            with self._cond:
                st = lib.vv_nav_apply(self._world._c, t, m)
                self._stats["inputs"] += 1
                self._input_seq += 1
                if st == 0:
                    self._moving = True
                    self._last_input = time.monotonic()
                    self._changed_locked(moving=True)
            if st == 0:
                self._sync_camera()
        elif kind == "end":
            with self._cond:
                self._moving = False
                self._cond.notify_all()
        elif kind == "slice":
            axis = content.get("axis")
            if axis in _AXES:
                idx = dict(self.slice_index)
                idx[axis] = int(_num(content.get("index"), -1))
                self.slice_index = idx

    # ---- the render thread ------------------------------------------------------
    def _render_main(self):
        while True:
            with self._cond:
                if self._quit:
                    return
                t = time.monotonic()
                still = not self._moving or t - self._last_input > STILL_AFTER
                gen = self._gen
                if gen != self._drawn_gen and not still and t < self._last_preview + MIN_PERIOD:
                    self._cond.wait(self._last_preview + MIN_PERIOD - t)
                    continue
                if gen != self._drawn_gen and not still:
                    kind = lib.vv_preview_policy_choose(self._policy, PREVIEW_BUDGET)
                    self._last_preview = t
                elif gen != self._sharp_gen and still:
                    kind = lib.VV_PREVIEW_FULL
                elif self.slices and self._slice_gen != self._slices_drawn:
                    sgen = self._slice_gen
                    snap = self._world.clone()
                    index = dict(self.slice_index)
                    kind = None
                else:
                    # nothing to draw; a drag without its end stops after STILL_AFTER
                    self._cond.wait(None if still else self._last_input + STILL_AFTER - t + 1e-3)
                    continue
                if kind is not None:
                    snap = self._world.clone()
                    seq = self._input_seq
                    cancel = None
                    if kind == lib.VV_PREVIEW_FULL:
                        cancel = ffi.gc(lib.vvpy_progress_new(), lib.vvpy_progress_free)
                        self._cancel = cancel
            if kind is None:
                try:
                    self._draw_slices(snap, index, sgen)
                except Exception as e:  # shown on the page; the thread goes on
                    with self._cond:
                        self._slices_drawn = sgen
                    self._set_status("slices: %s" % e)
                continue
            try:
                self._draw(snap, kind, gen, seq, cancel)
            except Exception as e:  # shown on the page; the thread goes on
                with self._cond:
                    self._drawn_gen = self._sharp_gen = gen
                self._set_status("render: %s" % e)
            finally:
                with self._cond:
                    self._cancel = None

    def _draw(self, snap, kind, gen, seq, cancel):
        vw, vh = snap.view.size
        pw, ph = ffi.new("int *"), ffi.new("int *")
        lib.vv_preview_size(kind, vw, vh, pw, ph)
        img = ffi.new("vv_image **")
        check(lib.vv_image_new(img, pw[0], ph[0]))
        img = ffi.gc(img[0], lib.vv_image_free)
        ro = ffi.new("vv_render_options *")
        lib.vv_render_options_init(ro)
        q = snap._c.render.quality
        ro.quality = 2 if q < 0 else q
        if cancel is not None:
            ro.progress = lib.vvpy_progress_get(cancel)
        # files out of core: a full frame by level of detail as volvis.render (a
        # voxel at most a pixel); a reduced one progressive, reading at most 64
        # chunks, as volvis serve draws its previews
        lod = ffi.new("vv_lod *")
        lib.vv_lod_init(lod)
        if kind != lib.VV_PREVIEW_FULL:
            lod.progressive = 1
            lod.load_budget = PROGRESSIVE_CHUNKS
        ro.lod = lod
        t0 = time.perf_counter()
        st = lib.vv_preview_render(self._preview, snap._c, ffi.addressof(snap._c, "view"), kind,
                                   ro, img)
        secs = time.perf_counter() - t0
        full = kind == lib.VV_PREVIEW_FULL
        if st == lib.VV_ERR_CANCELLED:
            with self._cond:
                self._stats["cancelled"] += 1
            return
        check(st)
        if not full and not lib.vv_preview_last_warmup(self._preview):
            lib.vv_preview_policy_record(self._policy, kind, secs)
        name = pystr(lib.vv_preview_kind_name(kind))
        rgb = _to_rgb8(img, 3)
        data, mime = _encode(rgb, JPEG_STILL if full else JPEG_MOVING)
        with self._cond:
            if full:
                self._full = (gen, _to_rgb8(img, 4))
            self._stats["frames"] += 1
            self._stats["full" if full else "previews"] += 1
            self._stats["kinds"][name] = self._stats["kinds"].get(name, 0) + 1
            n = self._stats["frames"]
            header = {"type": "frame", "seq": n, "gen": gen, "input": seq, "kind": name,
                      "sharp": full, "width": pw[0], "height": ph[0],
                      "view_width": vw, "view_height": vh, "ms": round(1000 * secs, 1),
                      "mime": mime}
            self._frame = (header, [data])
        self.send(header, [data])
        with self._cond:
            self._drawn_gen = gen
            if full:
                self._sharp_gen = gen
            self._cond.notify_all()
        self._set_status("%s %dx%d %.0f ms" % (name, pw[0], ph[0], 1000 * secs), n)

    def _set_status(self, text, seq=None):
        with self.hold_sync():
            self.status = text
            if seq is not None:
                self.frame_seq = seq

    # ---- slices -------------------------------------------------------------------
    def _slice_plane(self, o, axis, index, size=192):
        """The plane of slice ``index`` (-1: the middle) along ``axis`` of
        object ``o`` and the number of slices along it (as volvis serve)."""
        box = lib.vv_object_world_box(o)
        c = ffi.new("vv_vec3 *", ((box.min.x + box.max.x) / 2, (box.min.y + box.max.y) / 2,
                                  (box.min.z + box.max.z) / 2))
        pl = ffi.new("vv_slice_plane *")
        check(lib.vv_slice_plane_standard(pl, _AXES.index(axis), o.volume.space, c[0], size,
                                          size, 1.0))
        n = lib.vv_slice_plane_normal(pl)
        nv = np.array([n.x, n.y, n.z])
        step = lib.vv_slice_step(o, n)
        corners = [np.array([bx, by, bz]) for bx in (box.min.x, box.max.x)
                   for by in (box.min.y, box.max.y) for bz in (box.min.z, box.max.z)]
        d = [float(q @ nv) for q in corners]
        lo, hi = min(d), max(d)
        if not step > 0 or not math.isfinite(lo) or not math.isfinite(hi):
            return None, 0, 0
        count = int(math.floor((hi - lo) / step + 1e-6)) + 1
        if index < 0 or index >= count:
            index = count // 2 if index < 0 else count - 1
        cv = np.array([c.x, c.y, c.z])
        cv = cv + nv * (lo + index * step - float(cv @ nv))
        pl.center.x, pl.center.y, pl.center.z = (float(x) for x in cv)
        lib.vv_slice_plane_fit(pl, box, 0.02)
        return pl, count, index

    def _count_slices(self):
        o = self._first_volume()
        counts = {}
        if o is not None:
            for a in _AXES:
                r = self._slice_plane(o, a, 0, 16)
                counts[a] = r[1]
        self.slice_count = counts

    def _draw_slices(self, snap, index, sgen):
        wc = snap._c
        o = None
        for i in range(wc.n_objects):
            if wc.objects[i].type == lib.VV_OBJECT_VOLUME and wc.objects[i].volume != ffi.NULL:
                o = wc.objects[i]
                break
        frames = {}
        if o is not None:
            win, lev = ffi.new("double *"), ffi.new("double *")
            lib.vv_slice_auto_window(o.volume, win, lev)
            black = ffi.new("vv_vec3 *", (0, 0, 0))
            for a in _AXES:
                r = self._slice_plane(o, a, int(index.get(a, -1)))
                if r[0] is None:
                    continue
                pl, count, k = r
                n = pl.width * pl.height
                values = np.empty(n, np.float32)
                check(lib.vv_slice_sample(o, pl, ffi.from_buffer("float[]", values)))
                rgba = np.empty((pl.height, pl.width, 4), np.uint8)
                lib.vv_slice_window_level(ffi.from_buffer("float[]", values), n, win[0], lev[0],
                                          black[0], ffi.from_buffer("uint8_t[]", rgba))
                data, mime = _encode(np.ascontiguousarray(rgba[:, :, :3]), JPEG_STILL)
                frames[a] = ({"type": "slice", "axis": a, "index": k, "count": count,
                              "width": pl.width, "height": pl.height, "mime": mime}, [data])
        with self._cond:
            self._slices_drawn = sgen
            self._slice_frames = frames
        for header, bufs in frames.values():
            self.send(header, bufs)

    # ---- Python API ---------------------------------------------------------------
    def wait(self, timeout=30.0):
        """Waits until the full frame of the current state is drawn (True),
        or ``timeout`` seconds pass (False)."""
        end = time.monotonic() + timeout
        with self._cond:
            while self._sharp_gen != self._gen or self._moving:
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(min(left, 0.05))
        return True

    def snapshot(self, alpha=True):
        """The current frame at full quality as a numpy array of shape
        (height, width, 4) uint8 RGBA (``alpha=False``: (h, w, 3) RGB): the
        World's renderer at full resolution, what ``volvis render`` of the
        same World writes (gamma 1), not the JPEG the page shows. The newest
        full frame when it shows the current state, else rendered now."""
        with self._cond:
            full = self._full
            gen = self._gen
            snap = None if (full is not None and full[0] == gen) else self._world.clone()
        if snap is not None:
            from .render import render
            a = render(snap, renderer=self._renderer)
        else:
            a = full[1].copy()
        a = np.asarray(a)
        return a if alpha else np.ascontiguousarray(a[:, :, :3])

    @property
    def stats(self):
        """Counts of the frames drawn: "frames", "previews", "full",
        "cancelled", "inputs" (motion messages) and "kinds" (frames per
        representation)."""
        with self._cond:
            s = dict(self._stats)
            s["kinds"] = dict(s["kinds"])
            return s

    def close(self):
        """Stops the render thread and closes the widget."""
        with self._cond:
            self._quit = True
            if self._cancel is not None:
                lib.vvpy_progress_cancel(self._cancel)
            self._cond.notify_all()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(30)
        super().close()

    def __del__(self):
        try:
            with self._cond:
                self._quit = True
                self._cond.notify_all()
        except Exception:
            pass


def _num(v, default):
    try:
        f = float(v)
    except (TypeError, ValueError):
        return default
    return f if math.isfinite(f) else default
