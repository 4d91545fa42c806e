"""The Animator (VolVis paper, section 4): keyframe tracks and sequences
(orbit, object turn, flight, cut-plane sweep), World snapshots per frame,
and the final render to a PNG sequence, MP4 or WebM
(docs/animation-format.md).

Time is in seconds; frame k of N = round(duration * fps) is drawn at k /
fps. Angles are degrees (view.fov keys, orbit and turn angles)."""
import math
import os

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .render import Renderer
from .world import TransferFunction, World, _set_v3

__all__ = ["Animation", "orbit", "render_movie"]

_INTERP = {"spline": lib.VV_INTERP_SPLINE, "linear": lib.VV_INTERP_LINEAR,
           "step": lib.VV_INTERP_STEP}
_EASE = {"linear": lib.VV_EASE_LINEAR, "in": lib.VV_EASE_IN, "out": lib.VV_EASE_OUT,
         "in_out": lib.VV_EASE_IN_OUT}


class Animation:
    """An animation (vv_animation): ``Animation(duration=1, fps=30)``, then
    :meth:`add_track` and the sequences :meth:`orbit`, :meth:`rotate_object`,
    :meth:`fly`, :meth:`sweep_cut`; :meth:`world_at` evaluates a frame and
    :meth:`render` makes the movie. ``Animation.load(path)`` reads a file."""

    def __init__(self, duration=None, fps=None):
        out = ffi.new("vv_animation **")
        check(lib.vv_animation_new(out))
        self._c = ffi.gc(out[0], lib.vv_animation_free)
        if duration is not None:
            self.duration = duration
        if fps is not None:
            self.fps = fps

    @classmethod
    def load(cls, path):
        """Reads an animation file (vv_animation_load). Errors: FileError,
        FormatError with file:line:column and the key path."""
        out = ffi.new("vv_animation **")
        check(lib.vv_animation_load(out, cstr(path)))
        a = cls.__new__(cls)
        a._c = ffi.gc(out[0], lib.vv_animation_free)
        return a

    def save(self, path):
        """Writes an animation file, atomically (vv_animation_save)."""
        check(lib.vv_animation_save(self._c, cstr(path)))

    @property
    def duration(self):
        """Seconds, > 0."""
        return self._c.duration

    @duration.setter
    def duration(self, s):
        if not float(s) > 0:
            raise InvalidError("duration: %r is not > 0" % (s,))
        self._c.duration = float(s)

    @property
    def fps(self):
        """Frames per second, > 0."""
        return self._c.fps

    @fps.setter
    def fps(self, f):
        if not float(f) > 0:
            raise InvalidError("fps: %r is not > 0" % (f,))
        self._c.fps = float(f)

    @property
    def frames(self):
        """Number of frames, round(duration * fps)."""
        return lib.vv_animation_frame_count(self._c)

    @property
    def tracks(self):
        """The tracks' property paths, in order."""
        return [ffi.string(self._c.tracks[i].property).decode() for i in range(self._c.n_tracks)]

    def add_track(self, property, keys, interp="spline", closed=False):
        """Adds a keyframe track of ``property`` ("view.eye", "view.fov",
        "objects[0].tf", "objects.head.position", "lights[0].color", ...;
        docs/animation-format.md) with ``keys``: (time, value) pairs or dicts
        with time, value and optionally tension, continuity, bias (Kochanek-
        Bartels, each in [-1, 1]) and easing ("linear", "in", "out",
        "in_out"). Values: a number, a 3-vector, a quaternion (w, x, y, z),
        or a TransferFunction for ".tf"; view.fov in degrees. interp:
        "spline", "linear" or "step". Errors: InvalidError naming the track."""
        if interp not in _INTERP:
            raise InvalidError("interp: expected spline, linear or step, got %r" % (interp,))
        idx = ffi.new("int *")
        check(lib.vv_animation_add_track(self._c, cstr(property), idx))
        t = self._c.tracks[idx[0]]
        t.interp = _INTERP[interp]
        t.closed = 1 if closed else 0
        fov = property.strip() == "view.fov"
        for k in keys:
            if not isinstance(k, dict):
                k = {"time": k[0], "value": k[1]}
            key = ffi.new("vv_anim_key *")
            lib.vv_anim_key_init(key, float(k["time"]))
            v = k["value"]
            tfv = None
            if t.kind == lib.VV_ANIM_TF:
                if not isinstance(v, TransferFunction):
                    raise InvalidError("%s: a key's value must be a TransferFunction" % property)
                tfv = v
                key.tf = v._c
            elif t.kind == lib.VV_ANIM_SCALAR:
                key.value[0] = math.radians(float(v)) if fov else float(v)
            else:
                vals = [float(x) for x in v]
                need = 4 if t.kind == lib.VV_ANIM_QUAT else 3
                if len(vals) != need:
                    raise InvalidError("%s: a key needs %d numbers, got %r" % (property, need, v))
                for n, x in enumerate(vals):
                    key.value[n] = x
            key.tension = float(k.get("tension", 0))
            key.continuity = float(k.get("continuity", 0))
            key.bias = float(k.get("bias", 0))
            e = k.get("easing", "linear")
            if e not in _EASE:
                raise InvalidError("easing: expected one of %s, got %r" % (", ".join(_EASE), e))
            key.easing = _EASE[e]
            check(lib.vv_anim_track_add_key(ffi.addressof(self._c.tracks[idx[0]]), key))
            del tfv
        return self

    def _sequence(self, kind, **fields):
        s = ffi.new("vv_anim_sequence *")
        s.type = kind
        s.zoom = 1.0
        for k, v in fields.items():
            if k in ("axis", "offset", "point", "normal"):
                _set_v3(getattr(s, k), v, k)
            elif k == "object":
                s.object = cstr(v)
            else:
                setattr(s, k, float(v))
        check(lib.vv_animation_add_sequence(self._c, s))
        return self

    def orbit(self, degrees=360.0, azimuth=0.0, elevation=0.0, zoom=1.0):
        """Orbits the camera about the view's up axis by ``degrees`` over the
        animation, from the still view turned by azimuth, elevation (degrees)
        and zoom (``volvis render --azimuth --elevation --zoom``)."""
        return self._sequence(lib.VV_SEQ_ORBIT, degrees=degrees, azimuth=azimuth,
                              elevation=elevation, zoom=zoom)

    def rotate_object(self, name, axis=(0, 0, 1), degrees=360.0):
        """Turns object ``name`` by ``degrees`` about ``axis`` through its centre."""
        return self._sequence(lib.VV_SEQ_ROTATE_OBJECT, object=name, axis=axis, degrees=degrees)

    def fly(self, offset):
        """Moves eye and look-at point by ``offset`` (world units) over the animation."""
        return self._sequence(lib.VV_SEQ_FLY, offset=offset)

    def sweep_cut(self, point, normal, distance):
        """Sweeps a new global cut plane from ``point`` along ``normal`` by ``distance``."""
        return self._sequence(lib.VV_SEQ_SWEEP_CUT, point=point, normal=normal,
                              distance=distance)

    def world_at(self, world, frame=None, time=None):
        """The World of ``frame`` (or at ``time`` seconds): a snapshot of
        ``world`` (unchanged) with the animation applied."""
        out = ffi.new("vv_world **")
        if frame is not None:
            check(lib.vv_animation_eval_frame(self._c, world._c, int(frame), out))
        else:
            check(lib.vv_animation_eval(self._c, world._c, float(time or 0.0), out))
        return World._own(out[0])

    def render(self, path, world, renderer=None, quality=None, size=None, gamma=1.0,
               alpha=False, resume=True, crf=None, threads=0, progress=None, on_frame=None,
               **options):
        """The final render of every frame (vv_animation_render) to ``path``:
        a PNG pattern ("out/frame_%04d.png"), an existing folder, or a .mp4
        (H.264) / .webm (VP9) video, written atomically and resumable.
        renderer, quality and options as :func:`volvis.render`; size
        (width, height) overrides the view's. on_frame(frame, image) is
        called with each finished frame as a float32 (h, w, 4) array.
        Returns a dict of frames, rendered, reused, render_s, total_s.
        Errors: InvalidError, FileError, UnsupportedError (no codec),
        CancelledError; KeyboardInterrupt on Ctrl+C (frames done are kept)."""
        check(lib.vv_animation_validate(self._c))
        base = world
        if size is not None:
            base = world.clone()
            base.view.size = size
        check(lib.vv_animation_check_world(self._c, base._c))
        rs = ffi.addressof(base._c, "render")
        if isinstance(renderer, Renderer):
            r = renderer
            r.set(**options)
        else:
            name = renderer or pystr(lib.vv_render_settings_renderer(rs))
            r = Renderer(name)
            if pystr(lib.vv_render_settings_renderer(rs)) == r.name:
                check(lib.vv_renderer_apply_settings(r._c, rs))
            r.set(**options)
        o = ffi.new("vv_anim_render_options *")
        lib.vv_anim_render_options_init(o)
        out_path = ffi.new("char[]", cstr(os.fspath(path)))
        o.output = out_path
        o.render.threads = int(threads)
        o.render.quality = lib.vv_render_settings_quality(rs) if quality is None else int(quality)
        o.gamma = float(gamma)
        o.alpha = 1 if alpha else 0
        o.resume = 1 if resume else 0
        if crf is not None:
            o.video.crf = int(crf)
        cb = None
        if on_frame is not None:
            import numpy as np

            @ffi.callback("void(void *, int, const vv_image *, int)")
            def cb(user, frame, img, reused):
                w, h = img.width, img.height
                a = np.frombuffer(ffi.buffer(img.rgba, 16 * w * h), dtype=np.float32)
                on_frame(frame, a.reshape(h, w, 4).copy())
            o.on_frame = cb
        stats = ffi.new("vv_anim_render_stats *")

        def run(prog):
            o.progress = prog
            return lib.vv_animation_render(self._c, base._c, r._c, o, stats)
        _lib.call_long(run, progress, desc="movie")
        del cb
        return dict(frames=stats.frames, rendered=stats.rendered, reused=stats.reused,
                    render_s=stats.render_s, total_s=stats.total_s)

    def __repr__(self):
        return "<volvis.Animation %g s at %g fps (%d frames), tracks %s, %d sequences>" % (
            self.duration, self.fps, self.frames, self.tracks, self._c.n_sequences)


def orbit(degrees=360.0, frames=120, fps=30.0, azimuth=0.0, elevation=0.0, zoom=1.0):
    """An Animation of ``frames`` frames at ``fps`` orbiting the camera by
    ``degrees`` (``volvis animate --orbit``)."""
    a = Animation(duration=frames / float(fps), fps=fps)
    return a.orbit(degrees, azimuth, elevation, zoom)


def render_movie(path, world, animation=None, **kw):
    """Renders ``animation`` (default: a 360-degree orbit of 120 frames at
    30 fps) of ``world`` to ``path`` (see :meth:`Animation.render`)."""
    from .volume import Volume
    if not isinstance(world, World):
        world = World.for_volume(world if isinstance(world, Volume) else Volume(world))
    if animation is None:
        animation = orbit()
    return animation.render(path, world, **kw)
