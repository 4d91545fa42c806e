"""Multiresolution volumes out of core: OME-Zarr stores and BigDataViewer /
Imaris HDF5 pyramids read by chunks within a memory limit (vv_pyramid,
include/volvis/bricks.h; docs/parallel.md "OME-Zarr pyramids by level of
detail"), rendered by level of detail (vv_renderer_render_multires).

    pyr = volvis.Pyramid("cells.ome.zarr", memory_limit="512M")
    pyr.levels                      # [Level(shape=(z, y, x), spacing=..., ...), ...]
    block = pyr.read(1, (0, 0, 0), (63, 63, 63))   # a box of level 1, numpy [k, j, i]
    img = pyr.render(mode="mip", size=(512, 512))  # level of detail: 1 voxel a pixel
    img = volvis.render(pyr, mode="iso", isovalue=...)  # the same through volvis.render

    # progressive: draw what is resident now, let the loader fetch the rest
    img, info = pyr.render(size=(512, 512), progressive=True, return_lod=True)
    while info["pending"] and not info["stalled"]:
        pyr.wait(1.0)                   # a chunk arrived (or the loader is idle)
        img, info = pyr.render(size=(512, 512), progressive=True, return_lod=True)
    if info["pending"]:                 # more than the limit holds: stream the rest
        img = pyr.render(size=(512, 512))
"""
import collections
import os
import threading
import weakref

import numpy as np

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import Volume
from .world import VolumeObject, World

__all__ = ["Pyramid", "Level", "pyramids_of", "render_out_of_core"]

Level = collections.namedtuple("Level", "shape dtype spacing origin")
Level.__doc__ = """One level of a :class:`Pyramid`: ``shape`` (k, j, i) voxels, numpy
``dtype``, ``spacing`` and ``origin`` (i, j, k, world units; the level's
scale and translation)."""

_SUFFIX = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30}


# the pyramids whose proxies objects may show, by the proxy's address:
# volvis.render of a World draws those objects from their pyramids
_BY_PROXY = {}


def _address(ptr):
    return int(ffi.cast("uintptr_t", ptr))


def pyramids_of(world):
    """The pyramids (each once) whose proxies the objects of ``world`` show
    (:meth:`Pyramid.object`, :meth:`Pyramid.world`), in the objects' order."""
    found = []
    for i in range(world._c.n_objects):
        v = world._c.objects[i].volume
        ref = _BY_PROXY.get(_address(v)) if v != ffi.NULL else None
        p = ref() if ref is not None else None
        if p is not None and p._proxy is not None and _address(p._proxy._ptr) == _address(v) \
                and all(q is not p for q in found):
            found.append(p)
    return found


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


def _bytes(limit):
    """A memory limit: an int (bytes) or text with a K, M or G suffix."""
    if isinstance(limit, (int, np.integer)):
        n = int(limit)
    else:
        text = str(limit).strip().upper().rstrip("B").rstrip("I")
        unit = text[-1:] if text[-1:] in "KMG" else ""
        try:
            n = int(float(text[:-1] if unit else text) * _SUFFIX[unit])
        except ValueError:
            raise InvalidError("Pyramid: memory_limit %r is not a size (bytes, or a number with "
                               "K, M or G)" % (limit,)) from None
    if n <= 0:
        raise InvalidError("Pyramid: memory_limit must be positive, got %r" % (limit,))
    return n


class Pyramid:
    """A multiresolution volume read by boxes within ``memory_limit`` bytes
    of decoded chunks (an int, or text such as "512M"; default "1G"):
    an OME-Zarr store or plain Zarr v2 array (a folder), or a BigDataViewer
    HDF5 or Imaris ``.ims`` file; channel ``channel`` at time step ``time``
    of every level. Opening reads the metadata and the coarsest level only.

    Errors: FileError, FormatError (inconsistent multiscales, neither HDF5
    layout), LimitError (a limit below one box's working set), with the
    library's message naming the store. One Pyramid is used from one thread
    at a time (a lock serialises its calls); its background loader's
    methods (:attr:`loading`, :meth:`wait`, :meth:`cancel`, :attr:`stats`)
    from any."""

    def __init__(self, path, channel=0, time=None, memory_limit="1G"):
        self.path = os.fspath(path)
        out = ffi.new("vv_pyramid **")
        info = ffi.new("vv_load_info *")
        limit = _bytes(memory_limit)
        t = -1 if time is None else int(time)
        _lib.call_long(lambda prog: lib.vv_pyramid_open(out, cstr(self.path), int(channel), t,
                                                        limit, info), None)
        self._c = ffi.gc(out[0], lib.vv_pyramid_free)
        self._lock = threading.Lock()
        self.memory_limit = limit
        self.channels = int(info.n_channels)  # in the file
        self.times = int(info.n_times)
        self._proxy = None

    # ---- what it holds
    @property
    def levels(self):
        """The levels, finest first, as :class:`Level` tuples."""
        from .volume import VOXEL_TYPES
        out = []
        for L in range(lib.vv_pyramid_levels(self._c)):
            h = lib.vv_pyramid_level(self._c, L)
            out.append(Level(shape=(h.dims[2], h.dims[1], h.dims[0]),
                             dtype=VOXEL_TYPES[pystr(lib.vv_voxel_type_name(h.type))],
                             spacing=tuple(h.spacing[a] for a in range(3)),
                             origin=tuple(h.origin[a] for a in range(3))))
        return out

    @property
    def range(self):
        """(min, max) of the values: the omero window, else the coarsest level's."""
        h = lib.vv_pyramid_level(self._c, 0)
        return (h.range[0], h.range[1])

    @property
    def stats(self):
        """What the pyramid did since it was opened (vv_pyramid_stats): chunk
        reads per level, cache hits, missing chunks, evictions, bytes read,
        the cache's peak, frames and the most reads of one chunk in a frame;
        the background loader's chunks read, cancelled (a newer request
        dropped them), stopped (the cache was full of wanted chunks) and
        failed, and how many it has queued or in flight now."""
        st = ffi.new("vv_pyramid_stats *")
        lib.vv_pyramid_stats_get(self._c, st)
        n = lib.vv_pyramid_levels(self._c)
        return {"chunk_reads": [int(st.chunk_reads[L]) for L in range(n)],
                "chunk_hits": int(st.chunk_hits), "missing": int(st.missing),
                "evictions": int(st.evictions), "bytes_read": int(st.bytes_read),
                "peak_bytes": int(st.peak_bytes), "frames": int(st.frames),
                "max_reads_per_frame": int(st.max_reads_per_frame),
                "loaded": int(st.loaded), "cancelled": int(st.cancelled),
                "load_stopped": int(st.load_stopped), "load_errors": int(st.load_errors),
                "loading": int(st.loading), "stalled": int(st.stalled)}

    # ---- the background loader
    @property
    def loading(self):
        """Chunks the background loader has queued or is reading (0: idle).
        Thread-safe."""
        return int(lib.vv_pyramid_loading(self._c))

    def wait(self, seconds=1.0):
        """Waits up to ``seconds`` until the background loader finishes a
        chunk or has nothing left to do (vv_pyramid_wait), with the GIL
        released; returns :attr:`loading` then. Thread-safe."""
        return int(lib.vv_pyramid_wait(self._c, float(seconds)))

    def cancel(self):
        """Drops what the background loader has queued (chunks being read
        finish). Thread-safe."""
        check(lib.vv_pyramid_request(self._c, 0, ffi.NULL, ffi.NULL, ffi.NULL))

    # ---- voxels
    def read(self, level=0, lo=(0, 0, 0), hi=None):
        """Voxels ``lo`` .. ``hi`` (inclusive, (i, j, k); default the whole
        level) of level ``level`` as a numpy array [k, j, i] (a copy),
        assembled from the cached chunks and those read for it. Errors:
        InvalidError (a box outside the level), LimitError (it does not fit
        the memory limit), those of reading a chunk."""
        vol = self._read(level, lo, hi)
        return np.array(vol.array, copy=True)

    def _read(self, level, lo, hi):
        n = lib.vv_pyramid_levels(self._c)
        if not 0 <= int(level) < n:
            raise InvalidError("Pyramid.read: level %d of %d" % (int(level), n))
        h = lib.vv_pyramid_level(self._c, int(level))
        if hi is None:
            hi = (h.dims[0] - 1, h.dims[1] - 1, h.dims[2] - 1)
        clo = ffi.new("int[3]", [int(x) for x in lo])
        chi = ffi.new("int[3]", [int(x) for x in hi])
        out = ffi.new("vv_volume **")
        with self._lock:
            _lib.call_long(lambda prog: lib.vv_pyramid_read_box(self._c, int(level), clo, chi,
                                                                out), None)
        return Volume._own(out[0])

    def proxy(self):
        """The coarsest level as a :class:`Volume` stretched over level 0's
        box (what ``volvis render STORE`` frames the view and chooses the
        default transfer function from); kept after the first call."""
        if self._proxy is None:
            out = ffi.new("vv_volume **")
            with self._lock:
                _lib.call_long(lambda prog: lib.vv_pyramid_proxy(self._c, 0, out), None)
            self._proxy = Volume._own(out[0])
            for k in [k for k, r in _BY_PROXY.items() if r() is None]:
                del _BY_PROXY[k]
            _BY_PROXY[_address(self._proxy._ptr)] = weakref.ref(self)
        return self._proxy

    def world(self, mode="composite", tf_range=None, isovalue=None, size=None, azimuth=0.0,
              elevation=0.0, zoom=1.0):
        """The default scene of ``volvis render STORE``: World.for_volume of
        the :meth:`proxy`, its default transfer function's opacity per level
        0's smallest voxel spacing (as the CLI sets it)."""
        proxy = self.proxy()
        w = World.for_volume(proxy, mode=mode, tf_range=tf_range, isovalue=isovalue, size=size,
                             azimuth=azimuth, elevation=elevation, zoom=zoom)
        for i in range(w._c.n_objects):
            self._level0_opacity_unit(w._c.objects[i].tf)
        return w

    def _level0_opacity_unit(self, tf):
        """A default transfer function made from the proxy (its opacity per
        the proxy's smallest voxel spacing) made per level 0's instead."""
        f = lib.vv_pyramid_level(self._c, 0)
        ph = min(f.spacing[a] for a in range(3))
        pp = min(self.proxy().spacing)
        if abs(tf.opacity_unit_distance - pp) <= 1e-12 * pp:
            tf.opacity_unit_distance = ph

    def object(self, name=None, **properties):
        """A :class:`VolumeObject` of the :meth:`proxy` for a World of
        several objects, which :func:`render_out_of_core` draws from this
        pyramid: its default transfer function's opacity per level 0's
        smallest voxel spacing (as :meth:`world`), then ``properties`` as
        VolumeObject takes them (position, mode, tf, ...)."""
        obj = VolumeObject(self.proxy(), name)
        self._level0_opacity_unit(obj._c.tf)
        for k, v in properties.items():
            if not hasattr(VolumeObject, k) or k.startswith("_"):
                raise InvalidError("Pyramid.object: unknown property %r" % (k,))
            if v is not None:
                setattr(obj, k, v)
        return obj

    # ---- measurement
    def measure(self, isovalue=None, method="mc", bins=256, histogram_range=None, progress=None):
        """The Measurement component of level 0, read box by box through the
        cache (vv_measure_histogram_boxes, vv_measure_isosurface_boxes), so
        that a volume larger than memory is measured at full resolution:
        the histogram (``bins`` bins over ``histogram_range`` or the values'
        range; the counts those of the whole volume exactly) and, with an
        ``isovalue``, the isosurface's area and enclosed volume by Marching
        Cubes (``method="mc"``: each box's surface closed by caps on its
        faces, which cancel between neighbours) or voxel counting
        ("voxel"), to the rounding of :func:`volvis.measure` of the whole
        volume in memory. No region or seed (a surface-tracked section
        needs the whole volume). Returns a :class:`volvis.Measurement`.
        Errors: InvalidError (no surface at that isovalue, an unknown
        method), LimitError (a box and its chunks exceed the memory limit),
        CancelledError, those of reading chunks."""
        from .components import Measurement
        from .volume import _histogram_from
        if method not in ("mc", "voxel"):
            raise InvalidError("Pyramid.measure: method must be 'mc' or 'voxel', got %r"
                               % (method,))
        hdr = lib.vv_pyramid_level(self._c, 0)
        read = ffi.addressof(lib, "vv_pyramid_level0_box")
        lo, hi = (0.0, 0.0) if histogram_range is None else map(float, histogram_range)
        hp = ffi.new("vv_histogram **")
        res = ffi.new("vv_isosurface_measure *")
        code = lib.VV_MEASURE_MC if method == "mc" else lib.VV_MEASURE_VOXEL

        def run(prog):
            pp = ffi.new("vv_progress *", prog)
            st = lib.vv_measure_histogram_boxes(hp, hdr, read, self._c, int(bins), lo, hi, pp)
            if st == 0 and isovalue is not None:
                st = lib.vv_measure_isosurface_boxes(res, hdr, read, self._c, float(isovalue),
                                                     code, pp)
            return st

        try:
            with self._lock:
                _lib.call_long(run, progress, desc="measure")
            hist = _histogram_from(hp[0])
        finally:
            lib.vv_histogram_free(hp[0])
        unit = pystr(lib.vv_unit_name(hdr.unit))
        m = Measurement(unit=unit, histogram=hist, counts=hist.counts, edges=hist.edges)
        if isovalue is not None:
            m.isovalue, m.method = res.isovalue, method
            m.area, m.volume, m.cut_area = res.area, res.volume, res.cut_area
            m.voxels, m.n_triangles = int(res.voxels), int(res.n_triangles)
            m.area_bias = res.area_bias
        return m

    # ---- rendering
    def render(self, world=None, renderer=None, mode=None, size=None, lod=1.0, level=None,
               quality=None, view=None, dtype=np.uint8, depth=False, gamma=1.0, alpha=True,
               threads=0, progress=None, return_lod=False, progressive=False, **options):
        """Renders the pyramid out of core by level of detail
        (vv_renderer_render_multires) and returns the image as
        :func:`volvis.render` does.

        world: a :class:`World` whose object 0 is the volume object to draw
        (its own volume gives the defaults, the geometry comes from the
        pyramid; no other visible object), default :meth:`world` (``mode``
        and ``size`` applied). lod: each node of the volume at the coarsest
        level whose voxel projects to at most ``lod`` pixels; level: every
        node at this level instead (0: full resolution, which equals the
        in-memory render of level 0: MIP, MinIP, X-ray and the isosurface
        bit for bit, composite to the rounding of compositing). renderer:
        one with the region contract ("raycast", the default, draws every
        mode; "raytrace"). return_lod: also return a dict of the nodes
        drawn per level, the nodes skipped unread, the nodes drawn coarser
        than their level ("pending"), the boxes asked of the loader
        ("requested") and "stalled" (1: the loader stopped because the view
        needs more chunks than the memory limit holds; waiting will not
        sharpen the image, a render without progressive streams the
        converged one).

        progressive: draw at once from what the cache holds -- a node whose
        chunks are not resident at its level is drawn at the finest coarser
        level that is -- reading nothing, and ask the background loader for
        the missing chunks (coarse levels first, then the nodes nearest the
        eye; replacing the previous request, so a new view cancels what the
        old one still wanted). Render again after :meth:`wait` to see them;
        when "pending" is 0 the image is the converged one, bit for bit.

        Errors: UnsupportedError (a renderer without regions, other visible
        objects), those of reading chunks and rendering."""
        from .render import _finish, _prepare
        if world is None:
            world = self.world(mode=mode or "composite", size=size)
            mode = None
        if renderer is None:
            renderer = "raycast"
        w, r, vc, img, ro = _prepare(world, renderer, mode, size, quality, view, dtype, threads,
                                     options)
        src = ffi.new("vv_multires_source *")
        lib.vv_pyramid_source(self._c, src)
        lodc = _lod(lod, level, progressive, "Pyramid.render")

        def run(prog):
            ro.progress = prog
            return lib.vv_renderer_render_multires(r._c, w._c, 0, src, vc, ro, lodc, img)

        with self._lock, r._lock:
            _lib.call_long(run, progress, desc="render")
        out = _finish(img, vc, dtype, depth, gamma, alpha)
        if return_lod:
            return out, _lod_info(lodc, lib.vv_pyramid_levels(self._c))
        return out

    def __repr__(self):
        lv = self.levels
        return "<volvis.Pyramid %r: %d levels, %s %s, limit %d MiB>" % (
            self.path, len(lv), "x".join(str(x) for x in lv[0].shape[::-1]), lv[0].dtype,
            self.memory_limit >> 20)


def render_out_of_core(world, pyramids, renderer=None, lod=1.0, level=None, progressive=False,
                       return_lod=False, mode=None, size=None, quality=None, view=None,
                       dtype=np.uint8, depth=False, gamma=1.0, alpha=True, threads=0,
                       progress=None, **options):
    """Renders a World of several volume objects, those made by
    :meth:`Pyramid.object` (or :meth:`Pyramid.world`) of the ``pyramids``
    drawn from them out of core by level of detail, every other visible
    volume object from its own volume in memory
    (vv_renderer_render_sources): each object alone into a layer, the
    layers combined as the ray caster combines objects along a ray
    (composite and iso objects front to back, MIP, MinIP and X-ray by the
    largest colour behind them). lod, level, progressive and return_lod as
    :meth:`Pyramid.render` (the counts summed over the objects); the other
    arguments as :func:`volvis.render`.

        a, b = volvis.Pyramid("left.ome.zarr"), volvis.Pyramid("right.ome.zarr")
        w = a.world(size=(800, 400))
        w.add(b.object(position=(300, 0, 0), mode="mip"))
        v = w.view
        w.view = v.frame(*w.bounds())
        img = volvis.render_out_of_core(w, [a, b])

    Errors: InvalidError (a pyramid that no object of the World shows),
    UnsupportedError (overlapping composite or iso objects, a geometric
    object, several objects by the ray tracer, a renderer without regions:
    the library's message names them), those of reading and rendering."""
    from .render import _finish, _prepare
    pyramids = list(pyramids)
    w, r, vc, img, ro = _prepare(world, renderer, mode, size, quality, view, dtype, threads,
                                 options)
    entries = []
    for p in pyramids:
        if not isinstance(p, Pyramid):
            raise InvalidError("render_out_of_core: expected Pyramid objects, got %s"
                               % type(p).__name__)
        ptr = p.proxy()._ptr
        shown = [i for i in range(w._c.n_objects) if w._c.objects[i].volume == ptr]
        if not shown:
            raise InvalidError("render_out_of_core: no object of the World shows %s (add "
                               "pyramid.object())" % (p.path,))
        entries += [(i, p) for i in shown]
    n = len(entries)
    src = ffi.new("vv_object_source[]", max(n, 1))
    ms = ffi.new("vv_multires_source[]", max(n, 1))
    for k, (i, p) in enumerate(entries):
        lib.vv_pyramid_source(p._c, ffi.addressof(ms, k))
        lib.vv_object_source_init(ffi.addressof(src, k), i)
        src[k].multires = ffi.addressof(ms, k)
    lodc = _lod(lod, level, progressive, "render_out_of_core")

    def run(prog):
        ro.progress = prog
        return lib.vv_renderer_render_sources(r._c, w._c, src, n, vc, ro, lodc, img)

    # each pyramid's lock once, in one order
    locks = list({id(p): p._lock for p in pyramids}.items())
    locks.sort()
    for _, lk in locks:
        lk.acquire()
    try:
        with r._lock:
            _lib.call_long(run, progress, desc="render")
    finally:
        for _, lk in reversed(locks):
            lk.release()
    out = _finish(img, vc, dtype, depth, gamma, alpha)
    if return_lod:
        levels = max([lib.vv_pyramid_levels(p._c) for p in pyramids] + [1])
        return out, _lod_info(lodc, levels)
    return out
