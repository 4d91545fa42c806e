"""Volumes: numpy arrays shared with the library, and volume files.

Axis order: a volume of ``dims = (ni, nj, nk)`` voxels is the numpy array
``vol.array`` of shape ``(nk, nj, ni)``, indexed ``[k, j, i]``: C order, i
fastest, exactly the library's layout (``data[k][j][i]``, include/volvis/
volume.h). World position of voxel (i, j, k) = origin + direction @
(spacing * (i, j, k)), node-centred, in world units (usually mm).
"""
import dataclasses
import itertools
import os
import sys

import numpy as np

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError

__all__ = ["Volume", "open", "Histogram", "VOXEL_TYPES"]

#: numpy dtype of each library voxel type
VOXEL_TYPES = {
    "u8": np.dtype(np.uint8), "i8": np.dtype(np.int8), "u16": np.dtype(np.uint16),
    "i16": np.dtype(np.int16), "u32": np.dtype(np.uint32), "i32": np.dtype(np.int32),
    "f32": np.dtype(np.float32), "f64": np.dtype(np.float64),
}
_CODE = {"u8": lib.VV_U8, "i8": lib.VV_I8, "u16": lib.VV_U16, "i16": lib.VV_I16,
         "u32": lib.VV_U32, "i32": lib.VV_I32, "f32": lib.VV_F32, "f64": lib.VV_F64}
_BY_KIND = {(d.kind, d.itemsize): name for name, d in VOXEL_TYPES.items()}

# Arrays shared with library volumes, kept alive until the library drops its
# last reference to the volume (vvpy_release): key -> _Shared, and the
# volume's address -> _Shared for the write check before a render.
_shared = {}
_shared_by_addr = {}
_keys = itertools.count(1)


class _Shared:
    __slots__ = ("array", "addr", "nbytes", "hash")

    def __init__(self, array):
        self.array = array
        self.addr = 0
        self.nbytes = array.nbytes
        self.hash = None


@ffi.def_extern(onerror=lambda *exc: None)
def vvpy_release(user, data):
    """The library dropped its last reference to a volume sharing an array."""
    if sys.is_finalizing():
        return
    entry = _shared.pop(int(ffi.cast("uintptr_t", user)), None)
    if entry is not None:
        _shared_by_addr.pop(entry.addr, None)


def _sync_shared(ptr):
    """Before a render: when the numpy array a volume shares was written since
    the last check (its content hash changed), recompute the volume's range
    and bump its modification count so renderer caches see the change."""
    entry = _shared_by_addr.get(int(ffi.cast("uintptr_t", ptr)))
    if entry is None:
        return
    h = lib.vvpy_hash(ptr.data, entry.nbytes)
    if entry.hash != h:
        if entry.hash is not None:
            lib.vv_volume_update_range(ptr)
        entry.hash = h


def _voxel_name(dtype):
    dtype = np.dtype(dtype)
    name = _BY_KIND.get((dtype.kind, dtype.itemsize)) if dtype.kind in "uif" else None
    if name is None:
        # the library's own message lists the voxel types it has
        t = ffi.new("vv_voxel_type *")
        check(lib.vv_voxel_type_parse(cstr(str(dtype)), t))
        name = ffi.string(lib.vv_voxel_type_name(t[0])).decode()
    return name


def _vec3(v, what):
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InvalidError("%s: expected 3 finite numbers, got %r" % (what, v))
    return a


@dataclasses.dataclass
class Histogram:
    """A histogram of voxel values (vv_measure_histogram).

    counts: uint64 array of ``bins`` counts; edges: float64 array of
    ``bins + 1`` bin edges over [lo, hi]; total: voxels counted (NaN
    excluded), outside: of those, values outside [lo, hi]; nan: NaN voxels;
    min, max, mean, sd of the voxels (value units)."""
    counts: np.ndarray
    edges: np.ndarray
    lo: float
    hi: float
    total: int
    outside: int
    nan: int
    min: float
    max: float
    mean: float
    sd: float


def _histogram_from(h):
    n = h.nbins
    counts = np.frombuffer(ffi.buffer(h.counts, 8 * n), dtype=np.uint64).copy()
    return Histogram(counts=counts, edges=np.linspace(h.lo, h.hi, n + 1), lo=h.lo, hi=h.hi,
                     total=int(h.total), outside=int(h.outside), nan=int(h.nan), min=h.min,
                     max=h.max, mean=h.mean, sd=h.sd)


class _ArrayHolder:
    """Keeps a Volume alive behind a numpy view of its library-owned voxels."""

    def __init__(self, owner, address, shape, dtype, readonly=True):
        self.owner = owner
        self.__array_interface__ = {"data": (address, readonly), "shape": shape,
                                    "typestr": dtype.str, "version": 3}


class Volume:
    """A rectilinear scalar volume of the library (vv_volume).

    ``Volume(array, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None,
    axes="kji", copy=None, unit=None)``

    array: a 3-D numpy array of uint8, int8, uint16, int16, uint32, int32,
    float32 or float64 (a 2-D array is one slice), indexed ``[k, j, i]``
    (``axes="kji"``, the default) or ``[i, j, k]`` (``axes="ijk"``, e.g.
    nibabel's arrays). When the array's memory is i-fastest and contiguous
    (C order for "kji", Fortran order for "ijk"), aligned and in native byte
    order, the volume shares it (no copy; ``copy=None`` or ``False``) and
    keeps the array alive for as long as the library holds the volume (a
    World, a renderer's cache). A write to a shared array is seen by the next
    render: before rendering, the package hashes the shared voxels
    (memory-bandwidth bound, about 1 ms per 10 MB) and, when they changed,
    recomputes the volume's range and invalidates the renderers' caches.
    An array contiguous in the other order is copied (``copy=False`` refuses
    it); any other layout raises :class:`volvis.InvalidError` unless
    ``copy=True``. Other dtypes raise :class:`volvis.InvalidError` with the
    library's list of voxel types.

    spacing: world units between voxel centres along i, j, k (> 0); origin:
    world position of voxel (0, 0, 0); direction: 3x3 matrix whose columns
    are the unit directions of i, j, k (identity by default); unit: "mm",
    "um", "nm", "m", "in", "ft" or None.

    Thread-safety: reading and rendering from several threads is safe;
    changing the geometry while another thread renders is not.
    """

    __slots__ = ("_ptr", "__weakref__")

    def __init__(self, array, spacing=None, origin=None, direction=None, axes="kji", copy=None,
                 unit=None):
        arr = np.asarray(array)
        if arr.ndim == 2:
            arr = arr[np.newaxis] if axes == "kji" else arr[..., np.newaxis]
        if arr.ndim != 3:
            raise InvalidError("volvis.Volume: expected a 3-D array, got shape %s" % (arr.shape,))
        if axes not in ("kji", "ijk"):
            raise InvalidError("volvis.Volume: axes must be 'kji' or 'ijk', got %r" % (axes,))
        name = _voxel_name(arr.dtype)
        dims = arr.shape[::-1] if axes == "kji" else arr.shape
        ifast = arr.flags.c_contiguous if axes == "kji" else arr.flags.f_contiguous
        other = arr.flags.f_contiguous if axes == "kji" else arr.flags.c_contiguous
        native = arr.dtype.isnative
        share = ifast and native and arr.flags.aligned and not copy
        if not share:
            if copy is False:
                raise InvalidError(
                    "volvis.Volume: copy=False, but the array (shape %s, strides %s bytes, %s) "
                    "is not i-fastest contiguous memory in native byte order for axes '%s'"
                    % (arr.shape, arr.strides, arr.dtype, axes))
            if not (ifast or other) and copy is None:
                raise InvalidError(
                    "volvis.Volume: the array of shape %s has strides %s bytes, which are not "
                    "contiguous in C or Fortran order; pass copy=True to copy it (or "
                    "np.ascontiguousarray)" % (arr.shape, arr.strides))
        cdims = ffi.new("int[3]", [int(d) for d in dims])
        out = ffi.new("vv_volume **")
        if share:
            entry = _Shared(arr)
            key = next(_keys)
            _shared[key] = entry
            st = lib.vv_volume_wrap(out, cdims, _CODE[name], ffi.cast("void *", arr.ctypes.data),
                                    lib.vvpy_release, ffi.cast("void *", key))
            if st != 0:
                _shared.pop(key, None)
                check(st)
            entry.addr = int(ffi.cast("uintptr_t", out[0]))
            _shared_by_addr[entry.addr] = entry
            entry.hash = lib.vvpy_hash(out[0].data, entry.nbytes)
        else:
            check(lib.vv_volume_new(out, cdims, _CODE[name]))
        self._ptr = ffi.gc(out[0], lib.vv_volume_free, size=arr.nbytes)
        if not share:
            view = self._view(writeable=True)
            view[...] = arr if axes == "kji" else arr.transpose(2, 1, 0)
            lib.vv_volume_update_range(self._ptr)
        if spacing is not None:
            self.spacing = spacing
        if origin is not None:
            self.origin = origin
        if direction is not None:
            self.direction = direction
        if unit is not None:
            self.unit = unit

    @classmethod
    def _own(cls, ptr):
        """Wraps a vv_volume * whose one reference the caller hands over."""
        self = cls.__new__(cls)
        nbytes = int(lib.vv_volume_voxel_count(ptr)) * int(lib.vv_voxel_type_size(ptr.type))
        self._ptr = ffi.gc(ptr, lib.vv_volume_free, size=nbytes)
        return self

    @classmethod
    def _borrow(cls, ptr):
        """A new Python reference (vv_volume_ref) to a library volume."""
        return cls._own(lib.vv_volume_ref(ptr))

    def _view(self, writeable=False):
        p = self._ptr
        shape = (p.dims[2], p.dims[1], p.dims[0])
        addr = int(ffi.cast("uintptr_t", p.data))
        return np.asarray(_ArrayHolder(self, addr, shape, self.dtype, readonly=not writeable))

    # ---- voxels -----------------------------------------------------------
    @property
    def array(self):
        """The voxels as a read-only numpy view of shape (nk, nj, ni) (no copy)."""
        entry = _shared_by_addr.get(int(ffi.cast("uintptr_t", self._ptr)))
        if entry is not None:
            a = entry.array
            if a.flags.f_contiguous and not a.flags.c_contiguous:
                a = a.transpose(2, 1, 0)  # an "ijk" array seen as [k, j, i]
            a = a.reshape(self.shape).view()
            a.flags.writeable = False
            return a
        return self._view()

    def __array__(self, dtype=None, copy=None):
        a = self.array
        return a if dtype is None else a.astype(dtype)

    @property
    def dims(self):
        """Voxels along (i, j, k)."""
        return tuple(self._ptr.dims)

    @property
    def shape(self):
        """The numpy shape (nk, nj, ni)."""
        d = self._ptr.dims
        return (d[2], d[1], d[0])

    @property
    def dtype(self):
        """numpy dtype of the voxels."""
        return VOXEL_TYPES[ffi.string(lib.vv_voxel_type_name(self._ptr.type)).decode()]

    @property
    def shares_memory(self):
        """True when the voxels are a numpy array's memory (no copy was made)."""
        return int(ffi.cast("uintptr_t", self._ptr)) in _shared_by_addr

    @property
    def range(self):
        """(min, max) voxel value (NaNs ignored)."""
        return (self._ptr.range[0], self._ptr.range[1])

    def update(self):
        """Recomputes the range after the voxels changed and invalidates the
        renderers' caches (vv_volume_update_range); render() does this by
        itself for shared arrays."""
        lib.vv_volume_update_range(self._ptr)
        entry = _shared_by_addr.get(int(ffi.cast("uintptr_t", self._ptr)))
        if entry is not None:
            entry.hash = lib.vvpy_hash(self._ptr.data, entry.nbytes)

    # ---- geometry ---------------------------------------------------------
    def _touch(self):
        self._ptr.modified += 1

    @property
    def spacing(self):
        """World units between voxel centres along (i, j, k), each > 0."""
        return tuple(self._ptr.spacing)

    @spacing.setter
    def spacing(self, value):
        s = _vec3(value, "spacing")
        if np.any(s <= 0):
            raise InvalidError("spacing: every value must be > 0, got %s" % (tuple(s),))
        for a in range(3):
            self._ptr.spacing[a] = s[a]
        self._touch()

    @property
    def origin(self):
        """World position of voxel (0, 0, 0)."""
        return tuple(self._ptr.origin)

    @origin.setter
    def origin(self, value):
        o = _vec3(value, "origin")
        for a in range(3):
            self._ptr.origin[a] = o[a]
        self._touch()

    @property
    def direction(self):
        """3x3 float64 array whose columns are the world directions of i, j, k."""
        return np.array(list(self._ptr.direction), dtype=np.float64).reshape(3, 3)

    @direction.setter
    def direction(self, value):
        d = np.asarray(value, dtype=np.float64)
        if d.shape != (3, 3) or not np.all(np.isfinite(d)) or abs(np.linalg.det(d)) < 1e-12:
            raise InvalidError("direction: expected an invertible 3x3 matrix, got %r" % (value,))
        for n, x in enumerate(d.reshape(-1)):
            self._ptr.direction[n] = x
        self._touch()

    @property
    def unit(self):
        """Length unit of spacing and origin ("mm", "um", ...; "unknown")."""
        return pystr(lib.vv_unit_name(self._ptr.unit))

    @unit.setter
    def unit(self, name):
        self._ptr.unit = lib.vv_unit_parse(cstr(name or "unknown"))

    def index_to_world(self):
        """4x4 float64 matrix mapping (i, j, k, 1) to world coordinates."""
        return _mat4(lib.vv_volume_index_to_world(self._ptr))

    def world_box(self):
        """(min, max) corners of the world bounding box, float64 arrays."""
        b = lib.vv_volume_world_box(self._ptr)
        return (np.array([b.min.x, b.min.y, b.min.z]), np.array([b.max.x, b.max.y, b.max.z]))

    # ---- measurement and files -------------------------------------------
    def histogram(self, bins=256, range=None):
        """Histogram of all voxels into ``bins`` bins over ``range`` (lo, hi)
        (None: the voxels' own range); see :class:`Histogram`. Errors:
        InvalidError (bins outside 1..1048576, non-finite range)."""
        lo, hi = (0.0, 0.0) if range is None else (float(range[0]), float(range[1]))
        out = ffi.new("vv_histogram **")
        check(lib.vv_measure_histogram(out, self._ptr, int(bins), lo, hi, ffi.NULL))
        try:
            return _histogram_from(out[0])
        finally:
            lib.vv_histogram_free(out[0])

    def save(self, path, format=None, strict=False):
        """Writes the volume (vv_volume_save, atomically): format None picks
        it from the extension (.nrrd/.nhdr, .slc, .nii/.nii.gz, .mha/.mhd,
        .vtk, .vti, .tif/.tiff, .ome.tif/.ome.tiff, .ome.zarr/.zarr), or a
        format's name ("nrrd", "nifti", "mhd", "vti", "tiff", "zarr", ...;
        ``volvis convert --help`` lists them). What a format cannot hold is
        converted (SLC: rescaled to 8 bits; VTK legacy, TIFF and OME-Zarr:
        the direction matrix dropped) unless ``strict`` (then UnsupportedError).
        Errors: FileError, InvalidError, UnsupportedError."""
        fmt = lib.VV_FORMAT_AUTO
        if format is not None:
            f = ffi.new("vv_format *")
            check(lib.vv_format_parse(cstr(format), f))
            fmt = f[0]
        check(lib.vv_volume_save(self._ptr, cstr(path), fmt, 1 if strict else 0))

    def copy(self):
        """A new volume with its own copy of the voxels and the same geometry."""
        v = Volume(self.array, copy=True)
        for name in ("spacing", "origin", "direction"):
            setattr(v, name, getattr(self, name))
        v._ptr.unit = self._ptr.unit
        v._ptr.space = self._ptr.space
        return v

    def __repr__(self):
        return "<volvis.Volume %dx%dx%d %s spacing %s %s range [%g, %g]%s>" % (
            *self.dims, self.dtype, tuple(round(s, 6) for s in self.spacing), self.unit,
            *self.range, " shared" if self.shares_memory else "")

    def _repr_png_(self):
        from .render import render
        from .notebook import png_bytes
        return png_bytes(render(self, size=(256, 256)))


def _open_source(path, series, channel, format, raw, time, out_of_core):
    """volvis.open with out_of_core: vv_open, a Volume or a Pyramid."""
    from .pyramid import Pyramid
    oo = ffi.new("vv_open_options *")
    lib.vv_open_options_init(oo)
    oo.mode = lib.VV_OPEN_AUTO if out_of_core == "auto" else lib.VV_OPEN_OUT_OF_CORE
    oo.levels = 1
    if format is not None:
        f = ffi.new("vv_format *")
        check(lib.vv_format_parse(cstr(format), f))
        oo.load.format = f[0]
    if series is not None:
        oo.load.series = int(series)
    if channel is not None:
        oo.load.channel = int(channel)
    if time is not None:
        oo.load.time = int(time)
    if raw is not None:
        oo.load.has_raw = 1
        oo.load.format = lib.VV_FORMAT_RAW
        _raw_params(oo.load.raw, raw)
    od = ffi.new("vv_opened *")
    _lib.call_long(lambda prog: lib.vv_open(od, cstr(path), oo), None)
    try:
        if od.kind != lib.VV_DATA_VOLUME:
            raise InvalidError("volvis.open: %s is not a volume file" % os.fspath(path))
        whole = lib.vv_source_volume(od.source)
        if whole != ffi.NULL:
            return Volume._own(lib.vv_volume_ref(whole))
        p = Pyramid._own(od.source, path)
        p.channels, p.times = int(od.info.n_channels), int(od.info.n_times)
        p.channel_name = pystr(od.info.channel_name)
        return p
    finally:
        lib.vv_opened_clear(od)


def _mat4(m):
    return np.array([[m.m[r][c] for c in range(4)] for r in range(4)], dtype=np.float64)


def _raw_params(r, raw):
    """Fills the vv_raw_params @p r from the dict ``raw`` of :func:`open`."""
    raw = dict(raw)
    dims = raw.pop("dims")
    for a in range(3):
        r.dims[a] = int(dims[a])
    r.type = _CODE[_voxel_name(raw.pop("dtype", np.uint8))]
    r.big_endian = 1 if raw.pop("big_endian", False) else 0
    for key in ("spacing", "origin"):
        if key in raw:
            v = _vec3(raw.pop(key), key)
            for a in range(3):
                getattr(r, key)[a] = v[a]
    r.header_skip = int(raw.pop("header_skip", 0))
    if raw:
        raise InvalidError("volvis.open: unknown raw keys %s" % sorted(raw))


def open(path, series=None, channel=None, format=None, raw=None, time=None, slices=None,
         out_of_core=False):
    """Loads a volume file of any format the library reads (vv_volume_load):
    SLC, NRRD, NIfTI, MetaImage, VTK legacy, TIFF stacks, DICOM series
    (folders, DICOMDIR), raw files, and .vvc compressed volumes (decoded).

    series: DICOM series number (1-based as ``volvis info`` lists them; None:
    the only one). channel: the file's channel (0-based; None: 0): TIFF and
    DICOM samples or OME/ImageJ channels, NIfTI dim[5], NRRD's axis of a
    channel kind. time: the file's time step (0-based; None: 0): OME-TIFF and
    ImageJ hyperstacks, NIfTI dim[4], NRRD's axis of kind time. format:
    "slc", "nrrd", "nifti", "mhd", "vtk", "raw", "tiff", "dicom" or None
    (detect). raw: for raw files, a dict with dims (i, j, k), dtype, and
    optionally spacing, origin, big_endian, header_skip (bytes).
    slices: ``(first, count)``, slices first .. first + count - 1 only (0-based;
    None: all) of a TIFF stack, whose other pages are not decoded: a
    sub-stack of a stack larger than memory, its origin that of slice first;
    other formats raise UnsupportedError, a range past the stack InvalidError.

    out_of_core: False (read whole, the default); True: out of core where
    the file allows -- a pyramid by its levels, a .vvb, raw or uncompressed
    NRRD file by bricks -- as a :class:`Pyramid`, else whole; "auto": so
    when the volume's level 0 holds more than a quarter of the process's
    cache (:func:`volvis.memory_limit`), as the GUI opens files.

    Returns a :class:`Volume` that owns its voxels, or a :class:`Pyramid`
    (out of core). Errors: FileError, FormatError, LimitError,
    UnsupportedError, InvalidError with the library's message naming the
    file."""
    p = cstr(path)
    if out_of_core:
        return _open_source(path, series, channel, format, raw, time, out_of_core)
    if raw is None and format is None and lib.vv_vvc_detect(p):
        from .components import decompress
        return decompress(path)
    opt = ffi.new("vv_load_options *")
    lib.vv_load_options_init(opt)
    if format is not None:
        f = ffi.new("vv_format *")
        check(lib.vv_format_parse(cstr(format), f))
        opt.format = f[0]
    if series is not None:
        opt.series = int(series)
    if channel is not None:
        opt.channel = int(channel)
    if time is not None:
        opt.time = int(time)
    if slices is not None:
        first, count = (int(x) for x in slices)
        if first < 0 or count < 1:
            raise InvalidError("volvis.open: slices (%d, %d): first >= 0 and count >= 1"
                               % (first, count))
        opt.z_first, opt.z_count = first, count
    if raw is not None:
        opt.has_raw = 1
        opt.format = lib.VV_FORMAT_RAW
        _raw_params(opt.raw, raw)
    out = ffi.new("vv_volume **")
    _lib.call_long(lambda prog: lib.vv_volume_load(out, p, opt), None)
    return Volume._own(out[0])
