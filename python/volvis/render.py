"""Rendering: the renderer registry, persistent renderers and
``volvis.render``.

Every rendering method of the library is listed in ``volvis.renderers``
(a mapping name -> :class:`RendererInfo`; ``help(volvis.renderers["raytrace"])``
lists its options). :func:`render` draws a World or a Volume into a numpy
array; a :class:`Renderer` keeps its per-volume caches (gradients,
subvolume min/max) between frames, as the library's renderers do.
"""
import threading

import numpy as np

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import Volume, _sync_shared
from .world import World, mode_code

__all__ = ["Renderer", "RendererInfo", "renderers", "render", "Image", "option_text"]


def option_text(value):
    """A renderer option value as the library takes it: booleans "1"/"0",
    numbers with as few digits as read back the same double (as scene files
    store them), strings as they are."""
    if isinstance(value, (bool, np.bool_)):
        return "1" if value else "0"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        s = "%.15g" % v
        return s if float(s) == v else "%.17g" % v
    if isinstance(value, str):
        return value
    if hasattr(value, "__fspath__"):
        return value.__fspath__()
    raise InvalidError("renderer option: cannot pass a %s as text" % type(value).__name__)


_OPTION_TYPES = {0: "bool", 1: "int", 2: "real", 3: "enum", 4: "string"}
_KINDS = ["volume", "plane", "polygon", "sphere", "box", "cylinder", "mesh", "grid"]
_MODES = ["composite", "mip", "minip", "xray", "iso", "attenuated-mip"]
_CAPS = ["region", "quality", "preview", "progressive", "global", "channels"]


def _option(spec):
    """One entry of a renderer's typed option table as a dict."""
    words = []
    if spec.words != ffi.NULL:
        i = 0
        while spec.words[i] != ffi.NULL:
            words.append(pystr(spec.words[i]))
            i += 1
    kind = _OPTION_TYPES.get(spec.type, "unknown")
    d = {"type": kind, "default": pystr(getattr(spec, "def")), "doc": pystr(spec.doc),
         "values": words}
    if kind in ("int", "real"):
        d["min"] = spec.min
        d["max"] = spec.max
        d["min_open"] = bool(spec.flags & 1)
        d["max_open"] = bool(spec.flags & 2)
    buf = ffi.new("char[256]")
    d["accepts"] = pystr(lib.vv_option_describe(spec, buf, 256))
    return d


class RendererInfo:
    """A rendering method of the registry (vv_renderer_info): ``name``,
    ``description``, ``draws`` (object kinds), ``modes``, ``capabilities``,
    ``quality`` (what the quality level means to it) and ``options``, its
    typed option table: key -> {"type", "default", "min", "max", "values",
    "accepts", "doc"}, the table the CLI's --set and scene files are
    validated against. Calling it makes a :class:`Renderer`."""

    def __init__(self, info):
        self.name = pystr(info.name)
        self.description = pystr(info.description)
        self.draws = [k for i, k in enumerate(_KINDS) if info.draws & (1 << i)]
        self.modes = [m for i, m in enumerate(_MODES) if info.modes & (1 << i)]
        self.capabilities = [c for i, c in enumerate(_CAPS) if info.caps & (1 << i)]
        self.quality = pystr(info.quality)
        self.options = {pystr(info.options[k].key): _option(info.options + k)
                        for k in range(info.n_options)}
        lines = ["  %s=%s (default %s): %s" % (k, o["accepts"], o["default"] or "none", o["doc"])
                 for k, o in self.options.items()]
        self.__doc__ = "%s: %s\n\nDraws %s (%s); quality: %s\n\nOptions " \
            "(volvis.render(..., KEY=VALUE) or Renderer(%r, KEY=VALUE)):\n\n%s\n" % (
                self.name, self.description, ", ".join(self.draws), ", ".join(self.modes),
                self.quality, self.name, "\n".join(lines) or "  (none)")

    def __call__(self, **options):
        return Renderer(self.name, **options)

    def __repr__(self):
        return "<volvis renderer %r: %s>" % (self.name, self.description)


class _Registry(dict):
    """name -> RendererInfo of every method built into the library."""

    def __repr__(self):
        return "volvis.renderers(%s)" % ", ".join(self)


def _registry():
    reg = _Registry()
    for i in range(lib.vv_renderer_count()):
        info = RendererInfo(lib.vv_renderer_info_at(i))
        reg[info.name] = info
    return reg


#: Every rendering method of the library, name -> RendererInfo.
renderers = _registry()


class Image(np.ndarray):
    """A rendered image: a numpy array of shape (h, w, 4) (uint8 or float32
    RGBA, row 0 at the top) that Jupyter shows inline (``_repr_png_``)."""

    def _repr_png_(self):
        if self.ndim != 3 or self.shape[2] not in (3, 4):
            return None
        from .notebook import png_bytes
        return png_bytes(np.asarray(self))


class Renderer:
    """A renderer of the library (vv_renderer) that keeps its caches between
    renders: ``Renderer("raycast", early_termination=0.99)``.

    Options are the method's (``help(volvis.renderers[name])``), set with
    vv_renderer_set_option; an unknown key or a bad value raises
    :class:`volvis.InvalidError` with the library's message. One Renderer
    must not render from two threads at once; use one per thread."""

    def __init__(self, name="raycast", **options):
        out = ffi.new("vv_renderer **")
        check(lib.vv_renderer_new(out, cstr(name)))
        self._c = ffi.gc(out[0], lib.vv_renderer_free)
        self._lock = threading.Lock()
        self.set(**options)

    @classmethod
    def _own(cls, ptr):
        r = cls.__new__(cls)
        r._c = ffi.gc(ptr, lib.vv_renderer_free)
        r._lock = threading.Lock()
        return r

    @property
    def name(self):
        """The method's registry name."""
        return pystr(lib.vv_renderer_name(self._c))

    def set(self, **options):
        """Sets options (vv_renderer_set_option). Returns self."""
        for k, v in options.items():
            check(lib.vv_renderer_set_option(self._c, cstr(k), cstr(option_text(v))))
        return self

    def render(self, scene, **kw):
        """Renders like :func:`render` with this renderer (its options set
        before stay; ``**kw`` as there)."""
        return render(scene, renderer=self, **kw)

    def __repr__(self):
        return "<volvis.Renderer %r>" % self.name


def _apply_mode(world, mode):
    code = mode_code(mode)
    for i in range(world._c.n_objects):
        o = world._c.objects[i]
        if o.type in (lib.VV_OBJECT_VOLUME, lib.VV_OBJECT_GRID):
            o.mode = code


def render(scene, renderer=None, mode=None, size=None, quality=None, view=None, dtype=np.uint8,
           depth=False, gamma=1.0, alpha=True, threads=0, progress=None, lod=1.0, level=None,
           progressive=False, return_lod=False, **options):
    """Renders a World or a Volume and returns the image as a numpy array,
    through the library's one render call (vv_renderer_render).

    scene: a :class:`World`, a :class:`Volume` or a numpy array (shown in
    the default scene of ``volvis render FILE``, World.for_volume), or a
    :class:`Pyramid` (its :meth:`Pyramid.world`). A World whose objects
    show files out of core (:meth:`Pyramid.object`, :meth:`Pyramid.world`)
    draws them from their files, object by object: a pyramid by level of
    detail, a bricked file brick by brick; every other volume object from
    its own volume (the library chooses: docs/python.md).
    lod: each node of a pyramid at the coarsest level whose voxel projects
    to at most ``lod`` pixels; level: every node at this level instead (0:
    full resolution, which equals the in-memory render of level 0: MIP,
    MinIP, X-ray and the isosurface bit for bit, composite to the rounding
    of compositing). progressive: draw at once from what the cache holds --
    a node whose chunks are not resident at its level is drawn at the
    finest coarser level that is -- reading nothing, and ask the background
    loader for the missing chunks (replacing the previous request); render
    again after :meth:`Pyramid.wait` to see them; when "pending" is 0 the
    image is the converged one. return_lod: also return a dict of the nodes
    drawn per level, the nodes skipped unread, the nodes drawn coarser than
    their level ("pending"), the boxes asked of the loader ("requested")
    and "stalled" (1: the loader stopped because the view needs more chunks
    than the cache holds: a render without progressive streams the rest).
    renderer: a registry name (``volvis.renderers``), a :class:`Renderer`
    (keeps its caches between calls), or None: the World's render settings,
    else "raycast". mode: "composite", "mip", "minip", "xray", "iso" or
    "attenuated-mip" for
    every volume and grid object (on a snapshot; the World is unchanged).
    size: (width, height) in pixels, default the view's. quality: 0 draft ..
    2 final (default the World's, else 2). view: a :class:`View` in place of
    the World's. options: renderer options (KEY=VALUE, after the World's).

    Returns an :class:`Image` (a numpy array) of shape (h, w, 4): uint8 RGBA
    (``round(255 * v^(1/gamma))``; ``alpha=False``: (h, w, 3) RGB) for
    ``dtype=np.uint8``, or the library's float32 RGBA for
    ``dtype=np.float32``; with ``depth=True`` a pair (image, depth), depth a
    float32 (h, w) array of world distances from the eye (inf where nothing
    was hit). Row 0 is the top.

    The library renders with the GIL released, on ``threads`` threads (0:
    all cores). progress: None, True (a tqdm bar when tqdm is installed), a
    callable f(fraction) (returning True cancels: CancelledError) or a tqdm
    bar. Ctrl+C cancels the render and raises KeyboardInterrupt. A numpy
    array a volume shares is checked for writes first (see Volume).
    Errors: InvalidError (unknown renderer or option, bad size), NoMemoryError,
    and the renderer's own errors, with the library's message."""
    if not isinstance(scene, (World, Volume)) and callable(getattr(scene, "world", None)):
        scene = scene.world(mode=mode or "composite", size=size)  # a Pyramid
        mode = None
    frame = _prepare(scene, renderer, mode, size, quality, view, dtype, threads, options)
    world, r, vc, img, ro = frame
    lodc = _lod(lod, level, progressive, "render")

    def run(prog):
        ro.progress = prog
        ro.lod = lodc
        return lib.vv_renderer_render(r._c, world._c, vc, ro, img)

    with r._lock:
        _lib.call_long(run, progress, desc="render")
    out = _finish(img, vc, dtype, depth, gamma, alpha)
    if return_lod:
        levels = max([lib.vv_source_levels(world._c.objects[i].source)
                      for i in range(world._c.n_objects)
                      if world._c.objects[i].source != ffi.NULL] + [1])
        return out, _lod_info(lodc, levels)
    return out


def _lod(lod, level, progressive, what):
    """The vv_lod of a render: every node at ``level``, or by ``lod``
    pixels a voxel; progressive: from what is resident, loading the rest
    in the background."""
    lodc = ffi.new("vv_lod *")
    lib.vv_lod_init(lodc)
    if progressive:
        lodc.progressive = 1
        lodc.background = 1
        lodc.load_budget = 0
    if level is not None:
        lodc.level = int(level)
    else:
        if not float(lod) > 0:
            raise InvalidError("%s: lod must be > 0, got %r" % (what, lod))
        lodc.voxel_pixels = float(lod)
    return lodc


def _lod_info(lodc, n_levels):
    """What a frame drew (return_lod)."""
    return {"nodes": [int(lodc.nodes[L]) for L in range(n_levels)],
            "skipped": int(lodc.skipped), "pending": int(lodc.pending),
            "requested": int(lodc.requested), "stalled": int(lodc.stalled)}


def _prepare(scene, renderer, mode, size, quality, view, dtype, threads, options):
    """What a render call sets up: (world, renderer, view, image, options),
    as :func:`render` documents its arguments."""
    dtype = np.dtype(dtype)
    if dtype not in (np.dtype(np.uint8), np.dtype(np.float32)):
        raise InvalidError("render: dtype must be uint8 or float32, got %s" % dtype)
    if isinstance(scene, World):
        world = scene
    elif isinstance(scene, (Volume, np.ndarray)):
        world = World.for_volume(scene, mode=mode or "composite", size=size)
        mode = None
    else:
        raise InvalidError("render: expected a World, a Volume or an array, got %s"
                           % type(scene).__name__)
    if mode is not None:
        world = world.clone()
        _apply_mode(world, mode)
    wc = world._c
    for i in range(wc.n_objects):
        o = wc.objects[i]
        if o.volume != ffi.NULL:
            _sync_shared(o.volume)
        if o.solid_texture.volume != ffi.NULL:
            _sync_shared(o.solid_texture.volume)
    rs = ffi.addressof(wc, "render")
    if renderer is None:
        renderer = pystr(lib.vv_render_settings_renderer(rs))
    if isinstance(renderer, Renderer):
        r = renderer
        if options:
            r.set(**options)
    else:
        r = Renderer(renderer)
        if pystr(lib.vv_render_settings_renderer(rs)) == r.name:
            check(lib.vv_renderer_apply_settings(r._c, rs))
        r.set(**options)
    vc = ffi.new("vv_view *", (view._c[0] if view is not None else wc.view))
    if size is not None:
        w, h = int(size[0]), int(size[1])
        if not (1 <= w <= lib.VV_IMAGE_MAX_SIDE and 1 <= h <= lib.VV_IMAGE_MAX_SIDE):
            raise InvalidError("render: size %dx%d is outside 1..%d" % (w, h,
                                                                        lib.VV_IMAGE_MAX_SIDE))
        vc.width, vc.height = w, h
    img = ffi.new("vv_image **")
    check(lib.vv_image_new(img, vc.width, vc.height))
    img = ffi.gc(img[0], lib.vv_image_free)
    ro = ffi.new("vv_render_options *")
    lib.vv_render_options_init(ro)
    ro.threads = int(threads)
    ro.quality = lib.vv_render_settings_quality(rs) if quality is None else int(quality)
    if not 0 <= ro.quality <= 2:
        raise InvalidError("render: quality %d is outside 0..2" % ro.quality)
    return world, r, vc, img, ro


def _finish(img, vc, dtype, depth, gamma, alpha):
    """The rendered vv_image as :func:`render` returns it."""
    dtype = np.dtype(dtype)
    hgt, wid = vc.height, vc.width
    if dtype == np.uint8:
        ch = 4 if alpha else 3
        out = np.empty((hgt, wid, ch), dtype=np.uint8)
        lib.vv_image_to_8bit(img, ch, float(gamma), ffi.from_buffer("uint8_t[]", out))
    else:
        out = np.frombuffer(ffi.buffer(img.rgba, 16 * wid * hgt),
                            dtype=np.float32).reshape(hgt, wid, 4).copy()
    out = out.view(Image)
    if depth:
        d = np.frombuffer(ffi.buffer(img.depth, 4 * wid * hgt),
                          dtype=np.float32).reshape(hgt, wid).copy()
        return out, d
    return out
