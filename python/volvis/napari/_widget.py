"""The "VolVis 3-D" dock widget of the napari plug-in (napari.yaml): renders
napari's visible 3-D image layers with VolVis, from napari's camera, and
follows it as the user turns the view (docs/python.md, "napari").

What it maps (napari -> VolVis, each layer one volume object of a World):

- data: a layer the VolVis reader opened (its arrays are
  :class:`volvis.napari._reader.LevelArray`) is drawn from its file out of
  core, by level of detail (each 64^3 node at the coarsest level whose voxel
  covers at most ``lod`` pixels: level 0 where the view needs it); any other
  layer from its level 0 in memory (a numpy array shared, a dask array
  computed once and kept while the layer's data is the same object).
  ``scale`` and ``translate`` (z, y, x) become the spacing and origin (x, y, z).
- rendering: translucent -> composite (emission-absorption, unshaded),
  mip -> mip, minip -> minip, average -> xray (the mean), iso -> iso at
  ``iso_threshold`` (shaded, in the colormap's colour at the threshold),
  attenuated_mip -> attenuated-mip (napari's method: the maximum of the
  sample values scaled by exp(-attenuation (S - 1) / step), S the running
  sum of the contrast-normalised values) with the layer's ``attenuation``
  at VisPy's relative step 0.8 (the step napari's exponent divides by),
  also for a layer drawn out of core (opened by the VolVis reader), whose
  nodes render by regions: each carries its own part of the sum, and the
  nodes combine front to back (docs/rendering.md, "Attenuated MIP"); with
  shadows the ray tracer draws it (its shadow rays too: one minus the
  opacity of the attenuated maximum along them), except a layer drawn out
  of core, drawn as mip then (the ray tracer's regions carry no
  attenuated sum; said in the status line); additive -> composite.
- colormap, contrast limits, gamma, opacity: a transfer function of up to
  130 points over the contrast limits (even in t and in t^gamma), colour ``colormap((t)^gamma)`` at data
  value ``lo + t (hi - lo)``; opacity there ``opacity * t^gamma`` per voxel
  (the smallest spacing) in composite, ``opacity`` in mip, minip and xray.
- channels: the layers of one file's channels opened by the VolVis reader
  (one pyramid whose chunks hold every channel) drawn in composite or mip
  become ONE multi-channel object out of core, drawn in one pass: each
  shown layer its channel with its transfer function, additive layers
  under VolVis's ``additive`` rule (composite) or ``maximum`` rule (mip),
  as napari adds them, translucent ones under the ``composite`` rule; a
  channel layer drawn otherwise (iso, minip, average, attenuated_mip) is
  an object of its own over a pyramid of that channel.
- blending: ``additive`` layers held in memory on the same grid (shape,
  scale, translate) and drawn in mip, or in translucent, are combined by
  their sum, as napari adds them: they become the channels of one
  multi-channel object under VolVis's ``maximum`` rule (a MIP per channel,
  the coloured maxima added) or ``additive`` rule (each channel composited
  on its own, the colours added). Every other case keeps VolVis's own rule
  for separate objects, which has no sum: composite and iso objects are
  composited along each ray (depth-correct, which is napari's
  ``translucent``), mip, minip, xray and attenuated-mip objects combined by
  the per-channel maximum and shown behind them; a layer whose blending
  that does not match (``opaque``, ``minimum``, ``translucent_no_depth``,
  or ``additive`` with nothing on its grid to add to) is named in the
  status line when more than one object is drawn.
- camera: ``viewer.camera``'s view and up directions (its angles and
  orientation), centre, zoom and perspective. napari's zoom is canvas
  pixels per world unit, so the view's world height is the canvas height
  / zoom; with perspective (a vertical field of view, degrees) the eye is
  at the distance that shows that height at the centre, as VisPy's camera
  puts it; orthographic otherwise. napari's display frame is right-handed
  or left-handed as its axis orientations say (the default, x right, y
  down, z towards the viewer, is left-handed); VolVis's views are
  right-handed (right = forward x up), so a left-handed frame is drawn
  mirrored left to right (``frame["mirror"]``).

Frames: a change (camera, layers, their properties) re-renders after a
short debounce, on a worker thread, newest request wins (an older render
is cancelled at its next progress report and its frames dropped):
first a quarter-size frame from what is in memory, then half-size frames
of the full-size frame's nodes, progressively (what the cache holds, while
the background loader reads what the view needs; a new frame after at
least twice the last one's render time, or when the loader is idle; at
most ``progressive_frames`` (4) started within ``progressive_s`` (2 s)),
then the full-size frame, which reads what is still missing. Shadows: the ``raytrace`` renderer with a
directional light from above the camera's left shoulder, every object
casting and receiving shadows.
"""
import math
import time

import numpy as np
from qtpy.QtCore import Qt, QTimer
from qtpy.QtGui import QImage, QPixmap
from qtpy.QtWidgets import (QCheckBox, QHBoxLayout, QLabel, QPushButton, QSizePolicy,
                            QVBoxLayout, QWidget)

import volvis
from .._lib import check, cstr
from .._volvis import ffi, lib
from ..errors import CancelledError, Error
from ..volume import VOXEL_TYPES
from ._reader import level_array

__all__ = ["VolVisWidget", "napari_view", "layer_object"]

_MODES = {"translucent": "composite", "additive": "composite", "mip": "mip",
          "minip": "minip", "average": "xray", "iso": "iso",
          "attenuated_mip": "attenuated-mip"}
#: VisPy's volume visual's relative step size (its default, which napari
#: keeps): napari's attenuated MIP divides its exponent by it
NAPARI_RELATIVE_STEP = 0.8


def napari_view(camera, canvas_hw, size, bounds=None):
    """The VolVis :class:`volvis.View` of napari's 3-D ``camera`` for a
    canvas of ``canvas_hw`` (height, width) pixels, rendered at ``size``
    (width, height); ``bounds`` ((min, max) world box, x, y, z) places an
    orthographic eye outside the scene. Returns (view, mirror): mirror True
    when napari's display frame is left-handed (flip the image left to
    right to see it as napari does)."""
    vd = np.asarray(camera.view_direction, dtype=float)[::-1]
    up = np.asarray(camera.up_direction, dtype=float)[::-1]
    at = np.asarray(camera.center, dtype=float)[-3:][::-1]
    height = float(canvas_hw[0]) / float(camera.zoom)  # world units shown vertically
    v = volvis.View(size=size, up=tuple(up))
    fov = float(camera.perspective)
    if fov > 0:
        dist = height / (2.0 * math.tan(math.radians(fov) / 2.0))
        v.projection = "perspective"
        v.fov = fov
    else:
        dist = 1.0
        if bounds is not None:
            lo, hi = (np.asarray(b, dtype=float) for b in bounds)
            dist = float(np.linalg.norm(at - 0.5 * (lo + hi)) + np.linalg.norm(hi - lo) + 1.0)
        v.projection = "orthographic"
        v.ortho_height = height
    v.at = tuple(at)
    v.eye = tuple(at - vd * dist)
    # VisPy's 3-D camera frame is (right, down, away); each napari axis
    # orientation that differs is a reflection
    o = [str(getattr(a, "value", a)) for a in camera.orientation]  # (depth, vertical, horizontal)
    flips = (o[0] != "away") + (o[1] != "down") + (o[2] != "right")
    return v, bool(flips % 2)


def viewer_camera(viewer):
    """napari's camera model: ``viewer.scene.camera`` (napari >= 0.9), else
    ``viewer.camera``."""
    scene = getattr(viewer, "scene", None)
    return scene.camera if scene is not None and hasattr(scene, "camera") else viewer.camera


def _volume_array(arr):
    a = np.asarray(arr)
    if a.dtype not in VOXEL_TYPES.values():
        a = a.astype(np.float32)
    return np.ascontiguousarray(a)


def layer_tf(layer, unit_distance):
    """(mode, TransferFunction, iso colour) of a napari Image layer."""
    lo, hi = (float(x) for x in layer.contrast_limits)
    if not hi > lo:
        hi = lo + 1.0
    rendering = str(getattr(layer.rendering, "value", layer.rendering))
    mode = _MODES.get(rendering, "composite")
    gamma = float(layer.gamma)
    opacity = float(layer.opacity)
    # points even in t and even in t^gamma (the colormap's argument, steep
    # near 0 for gamma < 1), at most 130 of the table's 256
    t = np.unique(np.concatenate([np.linspace(0.0, 1.0, 65),
                                  np.linspace(0.0, 1.0, 65) ** (1.0 / max(gamma, 1e-3))]))
    rgba = np.asarray(layer.colormap.map(t ** gamma), dtype=float)
    values = lo + t * (hi - lo)
    if mode == "composite":
        alpha = opacity * t ** gamma
    else:
        alpha = np.full_like(t, opacity)
    tf = volvis.TransferFunction(opacity=np.column_stack([values, alpha]),
                                 color=np.column_stack([values, np.clip(rgba[:, :3], 0, 1)]),
                                 unit_distance=unit_distance)
    iso_t = (float(layer.iso_threshold) - lo) / (hi - lo)
    iso_rgb = np.clip(np.asarray(layer.colormap.map(np.array([min(max(iso_t, 0.0), 1.0)
                                                              ** gamma]))[0][:3],
                                 dtype=float), 0, 1)
    return mode, tf, tuple(iso_rgb), rendering


#: napari's rendering under additive blending -> VolVis's channel rule that
#: adds the layers' images (vv_channel_blend)
_ADDITIVE_RULES = {"mip": lib.VV_BLEND_MAXIMUM, "composite": lib.VV_BLEND_ADDITIVE}


def _blending(layer):
    return str(getattr(layer.blending, "value", layer.blending))


def additive_object(objs, names):
    """One multi-channel :class:`volvis.VolumeObject` adding ``objs`` (2..16
    in-memory volume objects on one grid, all mip or all composite, from
    :func:`layer_object`): their volumes its channels, each with its
    object's transfer function, under VolVis's maximum rule (mip: a MIP per
    channel, the coloured maxima added) or additive rule (composite: each
    channel composited alone, the colours added). napari's additive
    blending of those layers."""
    base = objs[0]
    vols = ffi.new("vv_volume *[]", [o._c.volume for o in objs])
    cnames = [ffi.new("char[]", cstr(n[:60])) for n in names]
    check(lib.vv_object_set_channels(base._c, len(objs), vols, ffi.new("char *[]", cnames)))
    for c, o in enumerate(objs):
        base._c.channels[c].tf = o._c.tf
    base._c.blend = _ADDITIVE_RULES[base.mode]
    base.name = "+".join(names)[:60]
    return base


def channels_object(pyr, layers):
    """One :class:`volvis.VolumeObject` of the channels of ``pyr`` (a
    :class:`volvis.Pyramid` carrying several, the VolVis reader's layers of
    one file's channels: each chunk holds them all) drawn by ``layers``
    (napari Image layers of them, composite or mip), out of core in one pass:
    a channel is shown when one of the layers shows it, with that layer's
    transfer function (:func:`layer_tf`); additive layers combine by
    VolVis's additive rule (composite: each channel composited alone, the
    colours added) or maximum rule (mip: a MIP per channel, the coloured
    maxima added), as napari adds them; translucent ones by the composite
    rule (the channels mixed sample by sample). ``scale`` and ``translate``
    from the first layer."""
    first = layers[0]
    obj = pyr.object(name="+".join(layer.name for layer in layers)[:60])
    lv = pyr.levels[0]
    scale = np.asarray(first.scale, dtype=float)[-3:][::-1]
    translate = np.asarray(first.translate, dtype=float)[-3:][::-1]
    sp, org = np.asarray(lv.spacing, dtype=float), np.asarray(lv.origin, dtype=float)
    factor = scale / sp
    if not np.allclose(factor, 1.0) or not np.allclose(translate, org):
        obj.scale = tuple(factor)
        obj.position = tuple(translate - factor * org)
    c = obj._c
    for k in range(c.n_channels):
        c.channels[k].visible = 0
    modes, blends = set(), set()
    for layer in layers:
        k = level_array(layer.data[0] if layer.multiscale else layer.data).channel
        mode, tf, _, _ = layer_tf(layer, float(np.min(scale)))
        c.channels[k].tf = tf._value()
        c.channels[k].visible = 1
        modes.add(mode)
        blends.add(_blending(layer))
    mode = modes.pop() if len(modes) == 1 else "composite"
    if blends == {"additive"}:
        c.blend = _ADDITIVE_RULES[mode]
    else:
        c.blend = lib.VV_BLEND_MAXIMUM if mode == "mip" else lib.VV_BLEND_COMPOSITE
    obj.shading = False
    return obj


def layer_object(layer, cache=None):
    """A :class:`volvis.VolumeObject` showing napari Image ``layer`` (3-D)
    as the module docstring says; ``cache`` (a dict) keeps in-memory
    volumes between calls. Returns (object, pyramid or None, note)."""
    data = layer.data[0] if layer.multiscale else layer.data
    scale = np.asarray(layer.scale, dtype=float)[-3:][::-1]
    translate = np.asarray(layer.translate, dtype=float)[-3:][::-1]
    pyr = None
    la = level_array(data)
    if la is not None and len(la.pyramid.carried) > 1:
        # one channel of a pyramid of several, drawn alone (an iso, minip,
        # xray or attenuated-mip layer): a pyramid of that channel
        key = ("channel", id(la.pyramid), la.channel)
        one = cache.get(key) if cache is not None else None
        if one is None or one[0] is not la.pyramid:
            one = (la.pyramid, volvis.Pyramid(la.pyramid.path,
                                              channel=la.pyramid.carried[la.channel]))
            if cache is not None:
                cache[key] = one
        pyr = one[1]
    elif la is not None:
        pyr = la.pyramid
    if pyr is not None:  # the layer's placement over level 0's own
        obj = pyr.object(name=layer.name[:60])
        lv = pyr.levels[0]
        sp, org = np.asarray(lv.spacing, dtype=float), np.asarray(lv.origin, dtype=float)
        factor = scale / sp
        if not np.allclose(factor, 1.0) or not np.allclose(translate, org):
            obj.scale = tuple(factor)
            obj.position = tuple(translate - factor * org)
        spacing = scale
    else:
        key = id(data)
        vol = cache.get(key) if cache is not None else None
        if vol is None or vol[0] is not data:
            vol = (data, volvis.Volume(_volume_array(data)))
            if cache is not None:
                cache[key] = vol
        v = vol[1]
        v.spacing = tuple(scale)
        v.origin = tuple(translate)
        obj = volvis.VolumeObject(v, name=layer.name[:60])
        spacing = scale
    mode, tf, iso_rgb, rendering = layer_tf(layer, float(np.min(spacing)))
    note = ""
    if mode == "attenuated-mip":
        obj.attenuation = float(getattr(layer, "attenuation", 0.05))
        obj.step = NAPARI_RELATIVE_STEP
    obj.mode = mode
    obj.tf = tf
    if mode == "iso":
        obj.isovalue = float(layer.iso_threshold)
        obj.material.color = iso_rgb
        obj.shading = True
    else:
        obj.shading = False
    return obj, pyr, note


class VolVisWidget(QWidget):
    """The "VolVis 3-D" dock widget: ``VolVisWidget(napari_viewer)``.

    Attributes for scripts and tests: ``image`` the last frame shown ((h, w,
    4) uint8 RGBA, as napari's canvas would show it), ``frame`` a dict of
    it (pass "coarse", "progressive" or "final"; world, view, renderer,
    mirror, lod (nodes drawn per level, pending, stalled), seconds since
    the request, generation), ``frames`` and ``finals`` counters, ``passes``
    the (generation, pass, nodes pending) of the latest request's frames, ``error``
    the last error's message or None. ``max_side`` caps the frame's longer
    side (the canvas's aspect is kept), ``lod`` the pixels a voxel may
    cover, ``debounce_ms`` the wait after a change. Methods:
    :meth:`request` (render now), :meth:`wait_final` (tests)."""

    def __init__(self, napari_viewer, max_side=512, lod=1.0, debounce_ms=120):
        super().__init__()
        self.viewer = napari_viewer
        self.max_side = int(max_side)
        self.lod = float(lod)
        # progressive half-size frames while the loader reads: at most this
        # many, started within this many seconds; then the full-size frame
        # reads what is missing itself (by the render's parallel reads,
        # faster than the one background loader)
        self.progressive_frames = 4
        self.progressive_s = 2.0
        self.image = None
        self.frame = None
        self.frames = 0
        self.finals = 0
        self.passes = []  # (generation, pass, pending) of the request's frames shown
        self.error = None
        self._generation = 0
        self._worker = None
        self._cache = {}
        self._hooked = set()

        self.label = QLabel("VolVis 3-D: no visible 3-D image layer")
        self.label.setAlignment(Qt.AlignCenter)
        self.label.setMinimumSize(256, 256)
        self.label.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.shadows = QCheckBox("Ray-traced shadows")
        self.follow = QCheckBox("Follow the camera")
        self.follow.setChecked(True)
        self.button = QPushButton("Render")
        self.status = QLabel("")
        self.status.setWordWrap(True)
        row = QHBoxLayout()
        for w in (self.shadows, self.follow, self.button):
            row.addWidget(w)
        lay = QVBoxLayout(self)
        lay.addWidget(self.label, 1)
        lay.addLayout(row)
        lay.addWidget(self.status)

        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(int(debounce_ms))
        self._timer.timeout.connect(self.request)
        self.button.clicked.connect(self.request)
        self.shadows.toggled.connect(self._changed)
        viewer_camera(napari_viewer).events.connect(self._camera_changed)
        napari_viewer.dims.events.ndisplay.connect(self._changed)
        napari_viewer.layers.events.inserted.connect(self._layers_changed)
        napari_viewer.layers.events.removed.connect(self._layers_changed)
        napari_viewer.layers.events.moved.connect(self._changed)
        self._layers_changed()

    # ---- events
    def _layers_changed(self, event=None):
        for layer in self.viewer.layers:
            if id(layer) not in self._hooked:
                layer.events.connect(self._layer_event)
                self._hooked.add(id(layer))
        alive = {id(x) for x in self.viewer.layers}
        self._cache = {k: v for k, v in self._cache.items()
                       if any(v[0] is (x.data[0] if x.multiscale else x.data)
                              for x in self.viewer.layers)}
        self._hooked &= alive
        self._changed()

    _LAYER_EVENTS = {"visible", "colormap", "contrast_limits", "gamma", "opacity", "rendering",
                     "iso_threshold", "blending", "data", "scale", "translate",
                     "attenuation"}

    def _layer_event(self, event):
        if getattr(event, "type", None) in self._LAYER_EVENTS:
            self._changed()

    def _camera_changed(self, event=None):
        if self.follow.isChecked():
            self._changed()

    def _changed(self, *args):
        try:
            self._timer.start()
        except RuntimeError:  # the Qt widget was deleted: stop listening
            self._disconnect()

    def _disconnect(self):
        v = self.viewer
        pairs = [(viewer_camera(v).events, self._camera_changed),
                 (v.dims.events.ndisplay, self._changed),
                 (v.layers.events.inserted, self._layers_changed),
                 (v.layers.events.removed, self._layers_changed),
                 (v.layers.events.moved, self._changed)]
        pairs += [(layer.events, self._layer_event) for layer in v.layers]
        for emitter, cb in pairs:
            try:
                emitter.disconnect(cb)
            except (RuntimeError, ValueError, TypeError):
                pass

    # ---- rendering
    def _canvas_hw(self):
        canvas = getattr(self.viewer, "canvas", None)  # napari >= 0.6: the canvas model
        hw = None
        if canvas is not None:
            hw = canvas.viewbox_size(self.viewer.layers) if hasattr(canvas, "viewbox_size") \
                else getattr(canvas, "size", None)
        if hw is None:
            hw = getattr(self.viewer, "_canvas_size", None)  # older napari
        if hw is None or min(hw) < 2:
            return (self.label.height(), self.label.width())
        return (int(hw[0]), int(hw[1]))

    def frame_size(self):
        """(width, height) of a full frame: the canvas's aspect, longer side
        at most max_side."""
        h, w = self._canvas_hw()
        s = min(1.0, self.max_side / float(max(h, w)))
        return (max(1, int(round(w * s))), max(1, int(round(h * s))))

    def build(self):
        """(world, view, renderer name, mirror, pyramids, notes) of the
        current state, or None when no visible 3-D image layer."""
        from napari.layers import Image
        world = volvis.World()
        pyramids, notes = [], []
        out_of_core = set()  # the names of the objects drawn from a pyramid
        additive = {}  # (mode, grid) -> [(layer name, object)]: summed layers
        channels = {}  # id(pyramid) -> (pyramid, [layers]): a file's channels, one object
        blend_notes = []
        for layer in self.viewer.layers:
            if not isinstance(layer, Image) or not layer.visible or layer.rgb:
                continue
            if layer.ndim != 3:
                notes.append("%s: %d-D, not drawn" % (layer.name, layer.ndim))
                continue
            la = level_array(layer.data[0] if layer.multiscale else layer.data)
            if la is not None and len(la.pyramid.carried) > 1 and \
                    _MODES.get(str(getattr(layer.rendering, "value", layer.rendering))) in \
                    _ADDITIVE_RULES:
                channels.setdefault(id(la.pyramid), (la.pyramid, []))[1].append(layer)
                continue
            obj, pyr, note = layer_object(layer, self._cache)
            if note:
                notes.append("%s: %s" % (layer.name, note))
            blending = _blending(layer)
            if blending == "additive" and pyr is None and obj.mode in _ADDITIVE_RULES:
                # summed with the others on its grid (below)
                key = (obj.mode, tuple(obj.volume.shape), tuple(obj.volume.spacing),
                       tuple(obj.volume.origin))
                additive.setdefault(key, []).append((layer.name, obj))
                continue
            world.add(obj)
            if pyr is not None:
                pyramids.append(pyr)
                out_of_core.add(obj.name)
            if blending not in ("translucent",):
                blend_notes.append("%s: blending %s drawn by VolVis's rule"
                                   % (layer.name, blending))
        for pyr, layers in channels.values():  # one pass over every channel shown
            obj = channels_object(pyr, layers)
            world.add(obj)
            pyramids.append(pyr)
            out_of_core.add(obj.name)
            if len(layers) > 1 and len({_blending(x) for x in layers}) > 1:
                blend_notes.append("%s: blendings %s drawn by VolVis's composite rule"
                                   % (obj.name, "/".join(sorted({_blending(x) for x in layers}))))
        for group in additive.values():
            if len(group) == 1 or len(group) > lib.VV_MAX_CHANNELS:
                for name, obj in group:
                    world.add(obj)
                    blend_notes.append("%s: blending additive drawn by VolVis's rule (nothing "
                                       "on its grid to add to)" % name)
                continue
            world.add(additive_object([o for _, o in group], [n for n, _ in group]))
        if len(world.objects) > 1:  # (one object over the background: any rule draws it so)
            notes += blend_notes
        if len(world.objects) == 0:
            return None
        size = self.frame_size()
        view, mirror = napari_view(viewer_camera(self.viewer), self._canvas_hw(), size, world.bounds())
        world.view = view
        shadows = self.shadows.isChecked()
        world.clear_lights()
        if shadows:
            f = np.subtract(view.at, view.eye)
            f /= np.linalg.norm(f)
            u = np.asarray(view.up, dtype=float)
            r = np.cross(f, u)
            r /= np.linalg.norm(r)
            u = np.cross(r, f)
            d = f - 0.8 * u + 0.4 * r  # from above, beside the eye
            world.add_light(direction=tuple(d / np.linalg.norm(d)), intensity=0.9)
            world.add_light(headlight=True, intensity=0.3)
            for obj in world.objects:
                obj.casts_shadows = True
                obj.receives_shadows = True
                obj.shading = True
                if obj.mode == "attenuated-mip" and obj.name in out_of_core:
                    obj.mode = "mip"  # raytrace's regions carry no attenuated sum
                    notes.append("%s: attenuated_mip drawn as mip with shadows (out of core)"
                                 % obj.name)
        else:
            world.add_light(headlight=True)
        return world, view, ("raytrace" if shadows else "raycast"), mirror, pyramids, notes

    def request(self):
        """Renders the current state now (on a worker thread), cancelling an
        older request."""
        self._timer.stop()
        self._generation += 1
        gen = self._generation
        if self._worker is not None:
            self._worker.quit()
            self._worker = None
        try:
            built = self.build()
        except Error as e:
            self._fail(str(e))
            return
        if built is None:
            self.status.setText("no visible 3-D image layer")
            return
        from napari.qt.threading import thread_worker
        worker = thread_worker(self._frames, start_thread=False)(gen, *built)
        worker.yielded.connect(self._show)
        worker.errored.connect(lambda e: self._fail(str(e)))
        self._worker = worker
        worker.start()

    def _stale(self, gen):
        return gen != self._generation

    def _frames(self, gen, world, view, renderer, mirror, pyramids, notes):
        t0 = time.perf_counter()
        w, h = view.size
        cancel = (lambda fraction: self._stale(gen))
        common = dict(renderer=renderer, progress=cancel)

        def frame(kind, size, lod=None, **kw):
            v = view.copy()
            v.size = size
            try:
                img, info = volvis.render(world, view=v, size=size, return_lod=True,
                                          lod=self.lod if lod is None else lod, **common, **kw)
            except CancelledError:
                return None
            except Error as e:  # the library's one-line message, shown in the status line
                return dict(error=str(e), generation=gen)
            return dict(pass_=kind, image=img, world=world, view=v, renderer=renderer,
                        mirror=mirror, lod=info, notes=notes, generation=gen,
                        seconds=time.perf_counter() - t0)

        small = (max(1, w // 4), max(1, h // 4))
        half = (max(1, w // 2), max(1, h // 2))
        f = frame("coarse", small, progressive=bool(pyramids))
        if f is None or self._stale(gen):
            return
        yield f
        if "error" in f:
            return
        if pyramids:
            t_prog = time.perf_counter()
            for _ in range(self.progressive_frames):
                if time.perf_counter() - t_prog > self.progressive_s:
                    break  # the full-size frame reads the rest, in parallel
                t_frame = time.perf_counter()
                # half size, the nodes of the full-size frame (lod halved):
                # a quarter of the cost while the loader reads them
                f = frame("progressive", half, lod=0.5 * self.lod, progressive=True)
                if f is None or self._stale(gen):
                    return
                if "error" in f or not f["lod"]["pending"] or f["lod"]["stalled"]:
                    break
                yield f
                # let the loader work: the next frame after at least twice
                # this one's render time (and 0.5 s), or when it is idle, so
                # that redrawing costs at most a third of the time
                t_next = time.perf_counter() + max(0.5, 2 * (time.perf_counter() - t_frame))
                while time.perf_counter() < t_next and not self._stale(gen) and \
                        any(p.loading for p in pyramids):
                    for p in pyramids:
                        p.wait(0.1)
            if "error" in f:
                yield f
                return
            f = frame("final", (w, h))  # streams what is still missing
            if f is None or self._stale(gen):
                return
            yield f
        else:
            f = frame("final", (w, h))
            if f is None or self._stale(gen):
                return
            yield f

    def _show(self, f):
        if f["generation"] != self._generation:
            return
        if "error" in f:
            self._fail(f["error"])
            return
        img = np.asarray(f["image"])
        if f["mirror"]:
            img = img[:, ::-1]
        img = np.ascontiguousarray(img)
        self.image = img
        self.frame = dict(f)
        self.frame["pass"] = self.frame.pop("pass_")
        if self.passes and self.passes[-1][0] != f["generation"]:
            self.passes = []
        self.passes.append((f["generation"], self.frame["pass"], f["lod"]["pending"]))
        self.frames += 1
        if self.frame["pass"] == "final":
            self.finals += 1
        self.error = None
        h, w = img.shape[:2]
        qimg = QImage(img.data, w, h, 4 * w, QImage.Format_RGBA8888).copy()
        pix = QPixmap.fromImage(qimg)
        if self.label.width() > 1 and self.label.height() > 1:
            pix = pix.scaled(self.label.size(), Qt.KeepAspectRatio, Qt.SmoothTransformation)
        self.label.setPixmap(pix)
        lod = f["lod"]
        levels = ", ".join("L%d %d" % (i, n) for i, n in enumerate(lod["nodes"]) if n)
        text = "%s %dx%d %.2f s (%s)%s%s" % (
            self.frame["pass"], w, h, f["seconds"], f["renderer"],
            "; nodes " + levels if levels else "",
            "; pending %d" % lod["pending"] if lod["pending"] else "")
        if f["notes"]:
            text += "; " + "; ".join(f["notes"])
        self.status.setText(text)

    def _fail(self, msg):
        self.error = msg
        self.status.setText("VolVis: " + msg)

    def closeEvent(self, event):
        self._generation += 1
        if self._worker is not None:
            self._worker.quit()
        self._timer.stop()
        self._disconnect()
        self._hooked.clear()
        super().closeEvent(event)
