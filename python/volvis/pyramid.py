"""Volumes out of core: multiresolution pyramids (OME-Zarr stores,
BigDataViewer HDF5 and XML, Imaris, .vvb files with levels) read by chunks,
and bricked files (.vvb, raw, uncompressed NRRD) read by bricks, within
the process's one cache (vv_open, include/volvis/io.h; the cache,
include/volvis/source.h; docs/parallel.md "OME-Zarr pyramids by level of
detail"). An object of a World made from one (:meth:`Pyramid.object`,
:meth:`Pyramid.world`) holds the file's source, and :func:`volvis.render`
draws it out of core, by level of detail, like any other World.

    volvis.memory_limit("512M")                     # the process's cache (every file)
    pyr = volvis.Pyramid("cells.ome.zarr")
    pyr.levels                      # [Level(shape=(z, y, x), spacing=..., ...), ...]
    block = pyr.read(1, (0, 0, 0), (63, 63, 63))   # a box of level 1, numpy [k, j, i]
    img = volvis.render(pyr.world(mode="mip", size=(512, 512)))  # 1 voxel a pixel
    w = pyr.world(size=(800, 400))
    w.add(volvis.Pyramid("right.ome.zarr").object(position=(300, 0, 0), mode="mip"))
    img = volvis.render(w)                          # both out of core, one call

    # progressive: draw what is resident now, let the loader fetch the rest
    img, info = volvis.render(w, progressive=True, return_lod=True)
    while info["pending"] and not info["stalled"]:
        pyr.wait(1.0)                   # a chunk arrived (or the loader is idle)
        img, info = volvis.render(w, progressive=True, return_lod=True)
    if info["pending"]:                 # more than the cache holds: stream the rest
        img = volvis.render(w)
"""
import collections
import os
import threading

import numpy as np

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import Volume
from .world import VolumeObject, World

__all__ = ["Pyramid", "Level", "memory_limit", "remote_stats"]

Level = collections.namedtuple("Level", "shape dtype spacing origin")
Level.__doc__ = """One level of a :class:`Pyramid`: ``shape`` (k, j, i) voxels, numpy
``dtype``, ``spacing`` and ``origin`` (i, j, k, world units; the level's
scale and translation)."""

_SUFFIX = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30}


def _bytes(limit, what="memory_limit"):
    """A memory limit: an int (bytes) or text with a K, M or G suffix."""
    if isinstance(limit, (int, np.integer)):
        n = int(limit)
    else:
        text = str(limit).strip().upper().rstrip("B").rstrip("I")
        unit = text[-1:] if text[-1:] in "KMG" else ""
        try:
            n = int(float(text[:-1] if unit else text) * _SUFFIX[unit])
        except ValueError:
            raise InvalidError("%s %r is not a size (bytes, or a number with K, M or G)"
                               % (what, limit)) from None
    if n <= 0:
        raise InvalidError("%s must be positive, got %r" % (what, limit))
    return n


def memory_limit(size=None):
    """The budget of the process's one cache, in bytes: every brick and
    chunk read out of core by any file (every :class:`Pyramid`, every World
    drawn out of core) is held in it, least recently used first out, never
    more than the budget together (vv_cache_process). ``size``: an int
    (bytes) or text such as "512M" sets it first (default 1 GiB); lowering
    it evicts at the next read. Returns the budget."""
    c = lib.vv_cache_process()
    if size is not None:
        lib.vv_cache_set_limit(c, _bytes(size))
    return int(lib.vv_cache_limit(c))


def remote_stats():
    """What the remote transport (every HTTP, HTTPS and S3 read of the
    stores opened by URL in this process, docs/formats.md "Remote data")
    has pending and has done since the process started (vv_remote_stats_get),
    as a dict of ints: ``pending`` (reads -- chunks, shard indexes, metadata
    files -- asked for and not yet answered), ``pending_bytes`` (bytes of
    them not yet received: a range's length, a whole object's once the
    server says its length), ``in_flight`` (HTTP requests on the wire now),
    ``completed`` (reads answered: received, absent or failed), ``failed``
    (of those, failed for good), ``requests`` (HTTP requests sent, each
    retry and redirect counted), ``bytes_received`` (bytes of response
    bodies, every try) and ``cancelled`` (reads dropped unanswered because
    no view wanted them any more: not sent, or abandoned in flight; not in
    ``completed``). Thread-safe; a snapshot whose fields are each read
    atomically, so two of them may be a moment apart while reads go on."""
    st = ffi.new("vv_remote_stats *")
    lib.vv_remote_stats_get(st)
    return {k: int(getattr(st, k)) for k in ("pending", "pending_bytes", "in_flight",
                                             "completed", "failed", "requests",
                                             "bytes_received", "cancelled")}


class Pyramid:
    """A volume read out of core: a multiresolution pyramid -- an OME-Zarr
    store or plain Zarr v2 array (a folder), a BigDataViewer HDF5 file or
    its dataset XML, an Imaris ``.ims`` file, a ``.vvb`` with levels -- by
    its levels' chunks, or a bricked file (a ``.vvb`` without levels, a raw
    file described by ``raw``, an uncompressed NRRD) by its bricks (one
    level), opened once through the format table (vv_open); channel
    ``channel`` at time step ``time``, or with ``channels`` (a list of the
    file's channel indices, up to 16) those channels at once: each chunk
    then holds them all (read, cached and counted together), ``carried``
    lists them, :meth:`read` and :meth:`proxy` take the position of one in
    that list, and :meth:`object` is an object of them all. Opening reads
    the metadata (and a pyramid's coarsest level) only. What it reads is
    held in the process's one cache (:func:`memory_limit`; ``memory_limit``
    here sets it first).

    Errors: FileError, FormatError (inconsistent multiscales, neither HDF5
    layout, a file read whole only), LimitError (a budget below one box's
    working set), with the library's message naming the file. Reads are
    thread-safe; its background loader's methods (:attr:`loading`,
    :meth:`wait`, :meth:`cancel`, :attr:`stats`) too."""

    def __init__(self, path, channel=0, time=None, memory_limit=None, raw=None, channels=None):
        self.path = os.fspath(path)
        if memory_limit is not None:
            globals()["memory_limit"](memory_limit)
        oo = ffi.new("vv_open_options *")
        lib.vv_open_options_init(oo)
        oo.mode = lib.VV_OPEN_OUT_OF_CORE_ONLY
        oo.levels = 1
        oo.load.channel = int(channel)
        carried = [int(channel)]
        if channels is not None:
            carried = [int(c) for c in channels]
            if not 1 <= len(carried) <= lib.VV_MAX_CHANNELS or any(c < 0 for c in carried):
                raise InvalidError("Pyramid: channels %r: 1 to %d indices, each >= 0"
                                   % (list(channels), lib.VV_MAX_CHANNELS))
            if len(carried) > 1:
                oo.n_channels = len(carried)
                for i, c in enumerate(carried):
                    oo.channels[i] = c
            else:
                oo.load.channel = carried[0]
        oo.load.time = -1 if time is None else int(time)
        if raw is not None:
            from .volume import _raw_params
            oo.load.has_raw = 1
            oo.load.format = lib.VV_FORMAT_RAW
            _raw_params(oo.load.raw, raw)
        od = ffi.new("vv_opened *")
        st = _lib.call_long(lambda prog: lib.vv_open(od, cstr(self.path), oo), None,
                            allow=(lib.VV_ERR_UNSUPPORTED,))
        if st == lib.VV_ERR_UNSUPPORTED:
            raise InvalidError("Pyramid: %s cannot be read out of core (by levels: a pyramid; "
                               "by bricks: a .vvb, raw or uncompressed NRRD file); "
                               "volvis.open reads it whole" % self.path)
        self._c = ffi.gc(lib.vv_source_ref(od.source), lib.vv_source_free)
        self.channels = int(od.info.n_channels)  # in the file
        self.times = int(od.info.n_times)
        self.channel_name = pystr(od.info.channel_name)
        self.carried = carried
        self.channel_names = [pystr(od.ch_info[i].channel_name) for i in range(len(carried))] \
            if len(carried) > 1 else [self.channel_name]
        lib.vv_opened_clear(od)
        self._proxy = None
        self._proxies = {}
        self._lock = threading.Lock()

    @classmethod
    def _own(cls, src, path):
        """A Pyramid of an opened source (a new reference is taken)."""
        p = cls.__new__(cls)
        p.path = os.fspath(path)
        p._c = ffi.gc(lib.vv_source_ref(src), lib.vv_source_free)
        p.channels = p.times = 1
        p.channel_name = ""
        p.carried = list(range(int(lib.vv_source_channels(src))))
        p.channel_names = [""] * len(p.carried)
        p._proxy = None
        p._proxies = {}
        p._lock = threading.Lock()
        return p

    @property
    def kind(self):
        """"pyramid" (read by levels) or "bricks" (one level, read by bricks)."""
        return pystr(lib.vv_source_kind_name(lib.vv_source_get_kind(self._c)))

    @property
    def memory_limit(self):
        """The budget of the cache its pieces live in (the process's)."""
        return int(lib.vv_cache_limit(lib.vv_source_cache(self._c)))

    # ---- what it holds
    @property
    def levels(self):
        """The levels, finest first, as :class:`Level` tuples."""
        from .volume import VOXEL_TYPES
        out = []
        for L in range(lib.vv_source_levels(self._c)):
            h = lib.vv_source_level(self._c, L)
            out.append(Level(shape=(h.dims[2], h.dims[1], h.dims[0]),
                             dtype=VOXEL_TYPES[pystr(lib.vv_voxel_type_name(h.type))],
                             spacing=tuple(h.spacing[a] for a in range(3)),
                             origin=tuple(h.origin[a] for a in range(3))))
        return out

    @property
    def range(self):
        """(min, max) of the values: the omero window, else the coarsest level's."""
        h = lib.vv_source_level(self._c, 0)
        return (h.range[0], h.range[1])

    @property
    def stats(self):
        """What it did since it was opened (vv_source_stats): chunk reads per
        level (a pyramid) or bricks read (bricks), cache hits, missing
        chunks, evictions, bytes read, its peak in the cache, frames and the
        most reads of one chunk in a frame; the background loader's chunks
        read, cancelled (a newer request dropped them from its queue),
        cancelled_in_flight (a newer request dropped them while a remote
        store's fetch was in flight), stopped (the cache was full of wanted
        chunks) and failed, and how many it has queued or in flight now."""
        st = ffi.new("vv_source_stats *")
        lib.vv_source_stats_get(self._c, st)
        n = lib.vv_source_levels(self._c)
        return {"chunk_reads": [int(st.chunk_reads[L]) for L in range(n)],
                "chunk_hits": int(st.chunk_hits), "missing": int(st.missing),
                "bricks_read": int(st.loads), "bricks_skipped": int(st.skipped),
                "evictions": int(st.evictions), "bytes_read": int(st.bytes_read),
                "peak_bytes": int(st.peak_bytes), "held_bytes": int(st.held_bytes),
                "frames": int(st.frames), "max_reads_per_frame": int(st.max_reads_per_frame),
                "loaded": int(st.loaded), "cancelled": int(st.cancelled),
                "cancelled_in_flight": int(st.cancelled_in_flight),
                "load_stopped": int(st.load_stopped), "load_errors": int(st.load_errors),
                "loading": int(st.loading), "stalled": int(st.stalled)}

    # ---- the background loader
    @property
    def loading(self):
        """Chunks the background loader has queued or is reading (0: idle).
        Thread-safe."""
        return int(lib.vv_source_loading(self._c))

    def wait(self, seconds=1.0):
        """Waits up to ``seconds`` until the background loader finishes a
        chunk or has nothing left to do (vv_source_wait), with the GIL
        released; returns :attr:`loading` then. Thread-safe."""
        return int(lib.vv_source_wait(self._c, float(seconds)))

    def cancel(self):
        """Drops what the background loader has queued (chunks being read
        finish). Thread-safe."""
        lib.vv_source_cancel(self._c)

    # ---- voxels
    def read(self, level=0, lo=(0, 0, 0), hi=None, channel=0):
        """Voxels ``lo`` .. ``hi`` (inclusive, (i, j, k); default the whole
        level) of level ``level`` as a numpy array [k, j, i] (a copy),
        assembled from the cached pieces and those read for it; ``channel``
        the position in :attr:`carried` (0: the one channel). Errors:
        InvalidError (a box outside the level, no such channel), LimitError
        (it does not fit the budget), those of reading a piece."""
        vol = self._read(level, lo, hi, channel)
        return np.array(vol.array, copy=True)

    def _read(self, level, lo, hi, channel=0):
        n = lib.vv_source_levels(self._c)
        if not 0 <= int(level) < n:
            raise InvalidError("Pyramid.read: level %d of %d" % (int(level), n))
        h = lib.vv_source_level(self._c, int(level))
        if hi is None:
            hi = (h.dims[0] - 1, h.dims[1] - 1, h.dims[2] - 1)
        clo = ffi.new("int[3]", [int(x) for x in lo])
        chi = ffi.new("int[3]", [int(x) for x in hi])
        out = ffi.new("vv_volume **")
        _lib.call_long(lambda prog: lib.vv_source_channel_read_box(self._c, int(channel),
                                                                   int(level), clo, chi, out),
                       None)
        return Volume._own(out[0])

    def proxy(self, channel=0):
        """A coarse whole volume as a :class:`Volume` over level 0's box (a
        pyramid's coarsest level, a bricked file's every f-th voxel: what
        ``volvis render FILE`` frames the view and chooses the default
        transfer function from) of channel ``channel`` (its position in
        :attr:`carried`); kept after the first call."""
        c = int(channel)
        if c not in self._proxies:
            out = ffi.new("vv_volume **")
            with self._lock:
                _lib.call_long(lambda prog: lib.vv_source_channel_proxy(self._c, c, 0, out), None)
            self._proxies[c] = Volume._own(out[0])
        if c == 0:
            self._proxy = self._proxies[0]
        return self._proxies[c]

    def world(self, mode="composite", tf_range=None, isovalue=None, size=None, azimuth=0.0,
              elevation=0.0, zoom=1.0):
        """The default scene of ``volvis render FILE``: World.for_volume of
        the :meth:`proxy`, its object showing this file out of core
        (vv_object_attach_source: :func:`volvis.render` reads it from here;
        the default transfer function's opacity per level 0's smallest voxel
        spacing)."""
        proxy = self.proxy()
        w = World.for_volume(proxy, mode=mode, tf_range=tf_range, isovalue=isovalue, size=size,
                             azimuth=azimuth, elevation=elevation, zoom=zoom)
        for i in range(w._c.n_objects):
            if len(self.carried) > 1:  # every channel it carries, in the default colours
                check(lib.vv_object_set_channels_source(w._c.objects[i], self._c, 0, ffi.NULL))
            else:
                check(lib.vv_object_attach_source(w._c.objects[i], self._c, 0))
        return w

    def object(self, name=None, **properties):
        """A :class:`VolumeObject` of the :meth:`proxy` showing this file out
        of core, for a World of several (``World.add``): :func:`volvis.render`
        draws it from here, the World's other volume objects from their own
        volumes; then ``properties`` as VolumeObject takes them (position,
        mode, tf, ...)."""
        obj = VolumeObject(self.proxy(), name)
        if len(self.carried) > 1:  # an object of every channel it carries
            cnames = [ffi.new("char[]", cstr((n or "channel %d" % c)[:60]))
                      for n, c in zip(self.channel_names, self.carried)]
            check(lib.vv_object_set_channels_source(obj._c, self._c, 0,
                                                    ffi.new("char *[]", cnames)))
            for i, c in enumerate(self.carried):
                obj._c.channels[i].index = c
        else:
            check(lib.vv_object_attach_source(obj._c, self._c, 0))
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
        hdr = lib.vv_source_level(self._c, 0)
        read = ffi.addressof(lib, "vv_source_box")
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
    def render(self, world=None, mode=None, size=None, **kw):
        """:func:`volvis.render` of this file out of core, by level of detail
        (``lod``, ``level``, ``progressive``, ``return_lod`` and the other
        arguments as :func:`volvis.render` takes them).

        world: default :meth:`world` (``mode`` and ``size`` applied); a
        World of your own is drawn with its object 0 showing this file (a
        snapshot, World.clone, gets this file's source in place of its own:
        ``world`` is not changed)."""
        from .render import render
        if world is None:
            world = self.world(mode=mode or "composite", size=size)
            mode = None
        elif world._c.n_objects > 0 and world._c.objects[0].source != self._c:
            world = world.clone()
            check(lib.vv_object_attach_source(world._c.objects[0], self._c, 0))
        return render(world, mode=mode, size=size, **kw)

    def __repr__(self):
        lv = self.levels
        return "<volvis.Pyramid %r: %s, %d levels, %s %s, cache %d MiB>" % (
            self.path, self.kind, len(lv), "x".join(str(x) for x in lv[0].shape[::-1]),
            lv[0].dtype, self.memory_limit >> 20)
