"""The napari reader of the VolVis plug-in (napari.yaml, ``volvis.read``):
the files VolVis opens and napari does not, through the library's one
opening call (vv_open, include/volvis/io.h), as napari layer data tuples.

A file the library reads out of core -- a pyramid (OME-Zarr, BigDataViewer
HDF5 or XML, Imaris, a .vvb with levels) by its chunks, a bricked file (a
.vvb without levels, a raw-encoded NRRD) by its bricks -- becomes a LAZY
layer: one :class:`LevelArray` per level (finest first, ``multiscale=True``
when there are several), wrapped in a dask array (:func:`lazy`), each
reading only the boxes napari's slices meet,
through the process's one cache (volvis.memory_limit). Any other file
(compressed NRRD, MetaImage, SLC, VTK, DICOM series, ...) is read whole by
its library reader, as the library always reads it.

Each channel is one layer: its name the file's channel name (else the
file's name and the channel index), its colormap from the file's channel
colour (black to that colour) when the file has one, additive blending.
The layers of a file of several channels read out of core share ONE
pyramid of them all (up to 16), each chunk holding every channel (read
once for all of them; the dock widget draws them as one object), and their
contrast limits are the channels' as `volvis render` gives them (the omero
window's start and end, else vv_channel_default_contrast of the coarsest
level). A file of one channel: its contrast limits
the library's automatic window (vv_slice_auto_window on the coarsest level
or the whole volume: the 1st to 99.5th percentile of the foreground),
scale the voxel spacing and translate the origin of voxel (0, 0, 0), both
in napari's (z, y, x) order. Time step 0 only; the direction matrix (an
oblique or flipped volume, e.g. a DICOM series in the library's RAS frame)
is not applied, only kept in ``metadata["volvis"]["direction"]`` (the
columns of i, j, k in x, y, z).
"""
import os

import numpy as np

from .._lib import check, cstr, ffi, lib, pystr
from .. import _lib
from ..errors import Error
from ..pyramid import Pyramid
from ..volume import Volume

__all__ = ["get_reader", "read", "LevelArray", "lazy", "level_array", "EXTENSIONS"]

#: file names the reader takes (napari.yaml lists the same patterns)
EXTENSIONS = (".vvb", ".xml", ".h5", ".ims", ".dcm", ".slc", ".nrrd", ".nhdr", ".mha", ".mhd",
              ".vtk", ".vti", ".zarr", ".vvc")


class LevelArray:
    """One level of a file read out of core, as an array-like napari (and
    numpy, dask) can slice: ``shape`` (z, y, x), ``dtype``, ``ndim`` 3,
    ``__getitem__`` with ints, slices (any step) and Ellipsis reading only
    the box asked for (vv_source_read_box through the process's cache), and
    ``__array__`` the whole level. ``pyramid`` is the :class:`volvis.Pyramid`
    it reads (the VolVis dock widget renders from it, out of core, by level
    of detail); ``level`` its index; ``channel`` the position in the
    pyramid's carried channels (the layers of a file's channels share one
    pyramid whose chunks hold them all). Thread-safe (the library's reads
    are)."""

    def __init__(self, pyramid, level, channel=0):
        lv = pyramid.levels[level]
        self.pyramid = pyramid
        self.level = int(level)
        self.channel = int(channel)
        self.shape = tuple(int(s) for s in lv.shape)
        self.dtype = np.dtype(lv.dtype)
        self.ndim = 3
        self.size = int(np.prod(self.shape))
        self.nbytes = self.size * self.dtype.itemsize

    def __len__(self):
        return self.shape[0]

    def __getitem__(self, key):
        if not isinstance(key, tuple):
            key = (key,)
        if any(k is Ellipsis for k in key):
            i = next(n for n, k in enumerate(key) if k is Ellipsis)
            key = key[:i] + (slice(None),) * (3 - (len(key) - 1)) + key[i + 1:]
        if len(key) > 3:
            raise IndexError("LevelArray: %d indices for 3 axes" % len(key))
        key = key + (slice(None),) * (3 - len(key))
        lo, hi, post, shape = [], [], [], []
        for k, n in zip(key, self.shape):
            if isinstance(k, (int, np.integer)):
                k = int(k) + (n if k < 0 else 0)
                if not 0 <= k < n:
                    raise IndexError("LevelArray: index %d outside 0..%d" % (k, n - 1))
                lo.append(k)
                hi.append(k)
                post.append(0)
            elif isinstance(k, slice):
                rng = range(*k.indices(n))
                shape.append(len(rng))
                if len(rng) == 0:
                    lo.append(0)
                    hi.append(0)
                    post.append(slice(0, 0))
                    continue
                a = min(rng[0], rng[-1])
                lo.append(a)
                hi.append(max(rng[0], rng[-1]))
                post.append(slice(rng[0] - a, None, rng.step))
            else:
                raise IndexError("LevelArray: unsupported index %r" % (k,))
        if 0 in shape:
            return np.empty(shape, dtype=self.dtype)
        # (i, j, k) boxes, inclusive
        block = self.pyramid.read(self.level, lo[::-1], hi[::-1], channel=self.channel)
        return block[tuple(post)]

    def __array__(self, dtype=None, copy=None):
        a = self.pyramid.read(self.level, channel=self.channel)
        return a if dtype is None else a.astype(dtype)

    def __repr__(self):
        return "<volvis LevelArray %s level %d channel %d of %r, shape %s %s>" % (
            self.pyramid.kind, self.level, self.channel, self.pyramid.path, self.shape,
            self.dtype)


def lazy(level_array):
    """A LevelArray as napari gets it: a dask array over it (napari indexes
    a multiscale level with every non-displayed axis whole and only then
    picks the slice, which with a dask array reads nothing until the slice
    is computed: then only the chunks that meet it), each dask chunk read
    by LevelArray.__getitem__; ``volvis_level`` is the LevelArray. Without
    dask, the LevelArray itself."""
    try:
        import dask.array as da
    except ImportError:
        return level_array
    z, y, x = level_array.shape
    arr = da.from_array(level_array, chunks=(min(z, 64), min(y, 256), min(x, 256)),
                        asarray=False, fancy=False, lock=False,
                        meta=np.empty((0, 0, 0), dtype=level_array.dtype),
                        name="volvis-%s-%d-%d-%x" % (os.path.basename(level_array.pyramid.path),
                                                     level_array.level, level_array.channel,
                                                     id(level_array)))
    arr.volvis_level = level_array
    return arr


def level_array(data):
    """The LevelArray behind a layer's array (lazy() or itself), or None."""
    if isinstance(data, LevelArray):
        return data
    la = getattr(data, "volvis_level", None)
    return la if isinstance(la, LevelArray) else None


def _is_dicom_file(path):
    try:
        with open(path, "rb") as f:
            head = f.read(132)
        return len(head) == 132 and head[128:132] == b"DICM"
    except OSError:
        return False


def _accepts(path):
    """Whether the VolVis reader takes ``path`` (by its name; a folder: a
    Zarr store or a DICOM series)."""
    p = os.fspath(path)
    low = p.lower().rstrip("/")
    if os.path.isdir(p):
        if low.endswith(".zarr") or any(os.path.exists(os.path.join(p, n))
                                        for n in ("zarr.json", ".zattrs", ".zarray", "DICOMDIR")):
            return True
        try:
            names = sorted(os.listdir(p))[:16]
        except OSError:
            return False
        return any(_is_dicom_file(os.path.join(p, n)) for n in names)
    if low.endswith(".nii.gz"):
        return False
    if low.endswith(".xml"):  # BigDataViewer's dataset XML only
        try:
            with open(p, "rb") as f:
                return b"<SpimData" in f.read(4096)
        except OSError:
            return False
    return low.endswith(EXTENSIONS) or (not os.path.splitext(low)[1] and _is_dicom_file(p))


def get_reader(path):
    """npe2 reader: the reader function for ``path`` (a str or a list of
    str), or None when VolVis does not take it."""
    paths = path if isinstance(path, (list, tuple)) else [path]
    if not paths or not all(_accepts(p) for p in paths):
        return None
    return read


def _open(path, channel, channels=None):
    """vv_open out of core where the file can be: (Pyramid or None, Volume
    or None, info dict); with ``channels`` (a list of several) a pyramid of
    them all, or (None, None, None) when the file cannot be read so."""
    oo = ffi.new("vv_open_options *")
    lib.vv_open_options_init(oo)
    oo.mode = lib.VV_OPEN_OUT_OF_CORE
    oo.levels = 1
    oo.load.channel = int(channel)
    if channels:
        oo.mode = lib.VV_OPEN_OUT_OF_CORE_ONLY
        oo.n_channels = len(channels)
        for i, c in enumerate(channels):
            oo.channels[i] = c
        od = ffi.new("vv_opened *")
        st = _lib.call_long(lambda prog: lib.vv_open(od, cstr(path), oo), None,
                            allow=(lib.VV_ERR_UNSUPPORTED,))
        if st == lib.VV_ERR_UNSUPPORTED:
            return None, None, None
        try:
            p = Pyramid._own(od.source, path)
            p.carried = list(channels)
            infos = []
            for i in range(len(channels)):
                inf = od.ch_info[i]
                infos.append({"channel_name": pystr(inf.channel_name),
                              "color": tuple(float(c) for c in inf.color) if inf.has_color
                              else None,
                              "window": (float(inf.window[0]), float(inf.window[1]))
                              if inf.has_window else None})
            return p, None, infos
        finally:
            lib.vv_opened_clear(od)
    od = ffi.new("vv_opened *")
    _lib.call_long(lambda prog: lib.vv_open(od, cstr(path), oo), None)
    try:
        if od.kind != lib.VV_DATA_VOLUME:
            raise Error("volvis napari reader: %s holds a %s, not a volume" % (
                path, "grid" if od.kind == lib.VV_DATA_GRID else "mesh"))
        inf = od.info
        info = {"n_channels": int(inf.n_channels), "n_times": int(inf.n_times),
                "n_levels": int(inf.n_levels), "channel_name": pystr(inf.channel_name),
                "color": tuple(float(c) for c in inf.color) if inf.has_color else None,
                "is_label": bool(inf.is_label)}
        whole = lib.vv_source_volume(od.source)
        if whole != ffi.NULL:
            return None, Volume._own(lib.vv_volume_ref(whole)), info
        return Pyramid._own(od.source, path), None, info
    finally:
        lib.vv_opened_clear(od)


def channel_contrast(volume, window):
    """(lo, hi) of a channel of several: the file's omero window (start, end)
    when it has one, else vv_channel_default_contrast of ``volume`` (the
    coarsest level): the contrast `volvis render`, the GUI and the browser
    give the channel (the door's, src/scene/world_open.c)."""
    if window is not None:
        return window
    lo, hi = ffi.new("double *"), ffi.new("double *")
    lib.vv_channel_default_contrast(volume._ptr, lo, hi)
    return (float(lo[0]), float(hi[0]) if hi[0] > lo[0] else float(lo[0]) + 1.0)


def auto_contrast(volume):
    """(lo, hi) data values: the library's automatic window
    (vv_slice_auto_window) of a Volume; hi > lo."""
    w = ffi.new("double *")
    c = ffi.new("double *")
    lib.vv_slice_auto_window(volume._ptr, w, c)
    lo, hi = c[0] - 0.5 * w[0], c[0] + 0.5 * w[0]
    if not hi > lo:
        hi = lo + 1.0
    return (float(lo), float(hi))


def _colormap(name, rgb):
    from napari.utils.colormaps import Colormap
    return Colormap(colors=np.array([[0, 0, 0, 1], [rgb[0], rgb[1], rgb[2], 1]], dtype=float),
                    name=name)


_DEFAULT_CHANNEL_COLORS = ("magenta", "green", "cyan", "yellow", "red", "blue")


def layer_data(path):
    """The layer data tuples of ``path``: [(data, kwargs, "image" or
    "labels"), ...], one a channel. Errors: volvis.Error subclasses with the
    library's one-line message naming the file."""
    path = os.fspath(path)
    base = os.path.basename(path.rstrip("/"))
    out = []
    first = _open(path, 0)
    n = first[2]["n_channels"]
    # a file of several channels out of core: one pyramid whose chunks hold
    # every channel (up to 16), each layer a channel of it (as napari's
    # channel_axis makes a layer a channel)
    shared, infos = None, None
    if n > 1 and first[0] is not None:
        shared, _, infos = _open(path, 0, list(range(min(n, lib.VV_MAX_CHANNELS))))
    for c in range(min(n, lib.VV_MAX_CHANNELS) if shared is not None else n):
        if shared is not None:
            pyr, vol, info = shared, None, dict(first[2], **infos[c])
        else:
            pyr, vol, info = first if c == 0 else _open(path, c)
        if pyr is not None:
            k = c if shared is not None else 0
            levels = pyr.levels
            data = [lazy(LevelArray(pyr, L, k)) for L in range(len(levels))]
            spacing, origin = levels[0].spacing, levels[0].origin
            contrast = channel_contrast(pyr.proxy(k), info.get("window")) if shared is not None \
                else auto_contrast(pyr.proxy(k))
            direction = np.asarray(pyr.proxy(k).direction)
        else:
            data = [vol.array]
            spacing, origin = vol.spacing, vol.origin
            contrast = auto_contrast(vol)
            direction = np.asarray(vol.direction)
        name = info["channel_name"] or (base if n == 1 else "%s [%d]" % (base, c))
        kw = {"name": name, "scale": tuple(float(s) for s in spacing[::-1]),
              "translate": tuple(float(o) for o in origin[::-1]),
              "metadata": {"volvis": {"path": path, "channel": c, "n_channels": n,
                                      "n_times": info["n_times"],
                                      "out_of_core": pyr is not None,
                                      "kind": pyr.kind if pyr is not None else "whole",
                                      "direction": direction.tolist()}}}
        if len(data) > 1:
            kw["multiscale"] = True
        else:
            data = data[0]
        if info["is_label"]:
            out.append((data, kw, "labels"))
            continue
        kw["contrast_limits"] = contrast
        if info["color"] is not None:
            kw["colormap"] = _colormap(name, info["color"])
        elif n > 1:
            kw["colormap"] = _DEFAULT_CHANNEL_COLORS[c % len(_DEFAULT_CHANNEL_COLORS)]
        if n > 1:
            kw["blending"] = "additive"
        out.append((data, kw, "image"))
    return out


def read(path):
    """npe2 reader function: a path or a list of paths -> layer data tuples."""
    paths = path if isinstance(path, (list, tuple)) else [path]
    out = []
    for p in paths:
        out.extend(layer_data(p))
    return out
