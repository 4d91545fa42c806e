"""The components of the VolVis paper over volumes: Filtering, Surface
extraction (Marching Cubes), Measurement, Modeling (voxelization by volume
sampling) and the .vvc codec. Each function calls the library's one
implementation with the GIL released; long ones take ``progress`` (None,
True for a tqdm bar, a callable, or a tqdm bar) and stop on Ctrl+C
(KeyboardInterrupt)."""
import dataclasses
import math
import os

import numpy as np

from . import _lib
from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .mesh import Mesh
from .render import option_text
from .volume import Histogram, Volume, _CODE, _histogram_from, _voxel_name
from .world import CutPlane

__all__ = ["filter", "filters", "isosurface", "measure", "Measurement", "colocalisation",
           "Colocalisation", "voxelize", "Shape", "compress", "decompress", "Compressed"]


def _as_volume(v):
    return v if isinstance(v, Volume) else Volume(v)


# ---- Filtering -----------------------------------------------------------------
def _filter_table():
    out = {}
    for i in range(lib.vv_filter_info_count()):
        f = lib.vv_filter_info_get(i)
        out[pystr(f.name)] = "--%s %s: %s" % (pystr(f.name), pystr(f.metavar), pystr(f.help))
    return out


#: The filters a chain knows, name -> "--name ARG: help" (as ``volvis filter --help``).
filters = _filter_table()


def _arg_text(value):
    if value is True or value is None:
        return None
    if isinstance(value, (tuple, list, np.ndarray)):
        return ",".join(option_text(float(x)) for x in value)
    return option_text(value)


def filter(volume, chain=None, threads=0, progress=None, **steps):
    """Runs a filter chain on a volume (docs/filtering.md) and returns a new
    Volume; the input is not changed.

    chain: command-line text ("--gaussian 1.5 --median 1", exactly as
    ``volvis filter``) or a list of (name, argument) pairs; or keyword
    arguments in order: ``filter(vol, gaussian=1.5, median=1,
    threshold="300:", fill_holes=True)`` (underscores become hyphens; a
    tuple becomes "a,b,c"; True is a filter without an argument). Both may
    be given (the text first). ``volvis.filters`` lists every filter with its
    argument syntax, units and output type.

    Errors: InvalidError naming the filter and argument; those of the steps
    ("step 2 (--median 1): ..."), CancelledError."""
    vol = _as_volume(volume)
    out = ffi.new("vv_filter_chain **")
    if isinstance(chain, str) or chain is None:
        check(lib.vv_filter_chain_parse(cstr(chain or ""), out))
        c = ffi.gc(out[0], lib.vv_filter_chain_free)
    else:
        check(lib.vv_filter_chain_new(out))
        c = ffi.gc(out[0], lib.vv_filter_chain_free)
        for name, arg in chain:
            a = _arg_text(arg)
            check(lib.vv_filter_chain_add(c, cstr(name), cstr(a)))
    for name, arg in steps.items():
        a = _arg_text(arg)
        if arg is False:
            continue
        check(lib.vv_filter_chain_add(c, cstr(name.replace("_", "-")), cstr(a)))
    o = ffi.new("vv_filter_options *")
    lib.vv_filter_options_init(o)
    o.threads = int(threads)
    res = ffi.new("vv_volume **")

    def run(prog):
        o.progress = prog
        return lib.vv_filter_chain_apply(c, vol._ptr, o, res)
    _lib.call_long(run, progress, desc="filter")
    return Volume._own(res[0])


# ---- Surface extraction ------------------------------------------------------------
def _roi(opt, roi):
    if roi is None:
        return
    lo, hi = roi
    for a in range(3):
        opt.roi_min[a] = int(lo[a])
        opt.roi_max[a] = int(hi[a])


def _cut_planes(opt, planes):
    planes = [p if isinstance(p, CutPlane) else CutPlane(*p) for p in (planes or [])]
    if len(planes) > lib.VV_MAX_CUT_PLANES:
        raise InvalidError("cut_planes: %d planes, at most %d" % (len(planes),
                                                                  lib.VV_MAX_CUT_PLANES))
    for i, p in enumerate(planes):
        opt.cut_planes[i] = p._value()
    opt.n_cut_planes = len(planes)


def isosurface(volume, isovalue, normals=True, roi=None, cut_planes=None, scalars=None,
               threads=0, progress=None):
    """Marching Cubes with the asymptotic decider (vv_isosurface_extract;
    docs/surface.md): the surface value == ``isovalue`` (inside: value >=
    isovalue) in world coordinates, closed where it does not leave the
    region. roi: ((i0, j0, k0), (i1, j1, k1)) inclusive voxel box; cut_planes:
    CutPlane or (point, normal) pairs clipping it exactly; scalars: a volume
    of the same dims interpolated onto the vertices. Returns a
    :class:`Mesh` (``vertices, triangles = isosurface(...)``; normals point
    towards lower values). An isovalue outside the range gives an empty mesh.
    Errors: InvalidError, LimitError, CancelledError."""
    vol = _as_volume(volume)
    o = ffi.new("vv_isosurface_options *")
    lib.vv_isosurface_options_init(o)
    o.threads = int(threads)
    o.compute_normals = 1 if normals else 0
    _roi(o, roi)
    _cut_planes(o, cut_planes)
    sv = None
    if scalars is not None:
        sv = _as_volume(scalars)
        o.scalar_volume = sv._ptr
    out = ffi.new("vv_mesh **")

    def run(prog):
        o.progress = prog
        return lib.vv_isosurface_extract(out, vol._ptr, float(isovalue), o)
    _lib.call_long(run, progress, desc="isosurface")
    return Mesh._own(out[0])


# ---- Measurement -------------------------------------------------------------------
@dataclasses.dataclass
class Measurement:
    """What :func:`measure` found. Lengths, areas and volumes are in world
    units of the volume (``unit``); None where not measured.

    isovalue, method ("mc" or "voxel"), area (isosurface area, caps
    excluded), volume (of the inside region), cut_area (where the inside
    meets the region's boundary), voxels (inside voxels), n_triangles,
    area_bias (expected measured/true area: 1.5 for voxel faces, 1 for MC),
    seed_voxel (when seeded); histogram (:class:`volvis.Histogram` of the
    region) with its counts and edges arrays."""
    unit: str
    histogram: Histogram
    counts: np.ndarray
    edges: np.ndarray
    isovalue: float = None
    method: str = None
    area: float = None
    volume: float = None
    cut_area: float = None
    voxels: int = None
    n_triangles: int = None
    area_bias: float = None
    seed_voxel: tuple = None


@dataclasses.dataclass(frozen=True)
class Colocalisation:
    """Colocalisation of two channels (vv_measure_colocalisation): the voxels
    measured, Pearson's r, Manders' M1 and M2 (NaN where undefined), the
    thresholds and the channels' means."""
    voxels: int
    pearson: float
    manders_m1: float
    manders_m2: float
    thresholds: tuple
    means: tuple


def colocalisation(a, b, mask=None, thresholds=(0.0, 0.0)):
    """Pearson's correlation coefficient and Manders' M1, M2 of two channels
    ``a`` and ``b`` (Volumes or numpy arrays (nk, nj, ni) of the same shape)
    over the voxels where ``mask`` (None: all; else the same shape) is
    non-zero and both values are finite. ``thresholds`` (tA, tB): values above
    them count as signal for M1 and M2 (0, 0: Manders' original
    coefficients). Manders, Verbeek and Aten, J. Microscopy 169 (1993).
    Errors: InvalidError (shapes that differ, a threshold not finite)."""
    va, vb = _as_volume(a), _as_volume(b)
    vm = _as_volume(mask) if mask is not None else None
    out = ffi.new("vv_colocalisation *")
    ta, tb = (float(t) for t in thresholds)
    check(lib.vv_measure_colocalisation(va._ptr, vb._ptr, vm._ptr if vm is not None else ffi.NULL,
                                        ta, tb, out))
    return Colocalisation(int(out.voxels), out.pearson, out.manders_m1, out.manders_m2,
                          (out.threshold[0], out.threshold[1]), (out.mean[0], out.mean[1]))


def _region(volume, roi, cut_planes):
    r = ffi.new("vv_roi *")
    lib.vv_roi_init(r)
    if roi is not None:
        for a in range(3):
            r.roi_min[a], r.roi_max[a] = int(roi[0][a]), int(roi[1][a])
    _cut_planes(r, cut_planes)
    return r


def measure(volume, isovalue=None, method="mc", seed=None, roi=None, cut_planes=None, bins=256,
            histogram_range=None, threads=0, progress=None):
    """The Measurement component (vv_measure_histogram, vv_measure_isosurface;
    docs/surface.md): the histogram of the region (``bins`` bins over
    ``histogram_range`` or the region's range) and, with an ``isovalue``, the
    isosurface's area and enclosed volume by Marching Cubes (``method="mc"``,
    with caps where the region cuts it) or voxel counting ("voxel"); ``seed``
    (voxel index coordinates) measures only the surface-tracked section
    grown from it. Returns a :class:`Measurement`. Errors: InvalidError (no
    surface at that isovalue, bad region or seed), CancelledError."""
    vol = _as_volume(volume)
    region = _region(vol, roi, cut_planes)
    lo, hi = (0.0, 0.0) if histogram_range is None else map(float, histogram_range)
    hp = ffi.new("vv_histogram **")
    check(lib.vv_measure_histogram(hp, vol._ptr, int(bins), lo, hi, region))
    try:
        hist = _histogram_from(hp[0])
    finally:
        lib.vv_histogram_free(hp[0])
    m = Measurement(unit=vol.unit, histogram=hist, counts=hist.counts, edges=hist.edges)
    if isovalue is None:
        return m
    o = ffi.new("vv_isosurface_measure_options *")
    lib.vv_isosurface_measure_options_init(o)
    if method not in ("mc", "voxel"):
        raise InvalidError("measure: method must be 'mc' or 'voxel', got %r" % (method,))
    o.method = lib.VV_MEASURE_MC if method == "mc" else lib.VV_MEASURE_VOXEL
    if seed is not None:
        o.has_seed = 1
        for a in range(3):
            o.seed[a] = float(seed[a])
    o.region = region[0]
    o.threads = int(threads)
    res = ffi.new("vv_isosurface_measure *")

    def run(prog):
        o.progress = prog
        return lib.vv_measure_isosurface(res, vol._ptr, float(isovalue), o)
    _lib.call_long(run, progress, desc="measure")
    m.isovalue, m.method = res.isovalue, method
    m.area, m.volume, m.cut_area = res.area, res.volume, res.cut_area
    m.voxels, m.n_triangles, m.area_bias = int(res.voxels), int(res.n_triangles), res.area_bias
    if seed is not None:
        m.seed_voxel = tuple(res.seed_voxel)
    return m


# ---- Modeling ------------------------------------------------------------------------
class Shape:
    """A geometric model for voxelization (vv_shape; docs/modeling.md):
    primitives, transforms and CSG. A Shape is a value: combining or
    transforming returns a new Shape, and the library's tree is built when
    :func:`voxelize` runs.

    Primitives (sizes in the shape's own units, > 0): ``Shape.sphere(r)``,
    ``ellipsoid((rx, ry, rz))``, ``box((sx, sy, sz), rounding=0)``,
    ``cylinder(r, height)``, ``cone(r_bottom, r_top, height)``,
    ``torus(major, minor)``, ``polygon(vertices, thickness)``,
    ``revolution(profile)`` ((n, 2) of (r, z)), ``extrusion(polygon,
    height)``, ``helix(profile, pitch, z0, z1)``, ``mesh(mesh_or_path,
    mode="auto", thickness=0)``. CSG: ``a | b`` (union), ``a & b``
    (intersection), ``a - b`` (difference). Transforms: ``translate``,
    ``rotate(axis, degrees)``, ``scale``."""

    def __init__(self, kind, args=(), children=(), transforms=()):
        self._kind = kind
        self._args = args
        self._children = tuple(children)
        self._transforms = tuple(transforms)

    @classmethod
    def sphere(cls, radius):
        return cls("sphere", (float(radius),))

    @classmethod
    def ellipsoid(cls, radii):
        return cls("ellipsoid", (tuple(map(float, radii)),))

    @classmethod
    def box(cls, size, rounding=0.0):
        return cls("box", (tuple(map(float, size)), float(rounding)))

    @classmethod
    def cylinder(cls, radius, height):
        return cls("cylinder", (float(radius), float(height)))

    @classmethod
    def cone(cls, r_bottom, r_top, height):
        return cls("cone", (float(r_bottom), float(r_top), float(height)))

    @classmethod
    def torus(cls, major, minor):
        return cls("torus", (float(major), float(minor)))

    @classmethod
    def polygon(cls, vertices, thickness):
        return cls("polygon", (np.asarray(vertices, dtype=np.float64).reshape(-1, 3),
                               float(thickness)))

    @classmethod
    def revolution(cls, profile):
        return cls("revolution", (np.asarray(profile, dtype=np.float64).reshape(-1, 2),))

    @classmethod
    def extrusion(cls, polygon, height):
        return cls("extrusion", (np.asarray(polygon, dtype=np.float64).reshape(-1, 2),
                                 float(height)))

    @classmethod
    def helix(cls, profile, pitch, z0, z1):
        return cls("helix", (np.asarray(profile, dtype=np.float64).reshape(-1, 2), float(pitch),
                             float(z0), float(z1)))

    @classmethod
    def mesh(cls, mesh, mode="auto", thickness=0.0):
        modes = {"auto": lib.VV_MESH_AUTO, "solid": lib.VV_MESH_SOLID,
                 "shell": lib.VV_MESH_SHELL}
        if mode not in modes:
            raise InvalidError("mesh mode: expected auto, solid or shell, got %r" % (mode,))
        if not isinstance(mesh, (Mesh, str, os.PathLike)):
            mesh = Mesh(*mesh)
        return cls("mesh", (mesh, modes[mode], float(thickness)))

    def _with(self, m):
        return Shape(self._kind, self._args, self._children, self._transforms + (m,))

    def translate(self, offset):
        """Moved by ``offset`` (world units)."""
        return self._with(("translate", tuple(map(float, offset))))

    def rotate(self, axis, degrees):
        """Turned by ``degrees`` about ``axis`` through the origin."""
        return self._with(("rotate", tuple(map(float, axis)), float(degrees)))

    def scale(self, factors):
        """Scaled by a number or (sx, sy, sz)."""
        f = (float(factors),) * 3 if np.isscalar(factors) else tuple(map(float, factors))
        return self._with(("scale", f))

    def __or__(self, other):
        return Shape("csg", (lib.VV_CSG_UNION,), (self, other))

    def __and__(self, other):
        return Shape("csg", (lib.VV_CSG_INTERSECTION,), (self, other))

    def __sub__(self, other):
        return Shape("csg", (lib.VV_CSG_DIFFERENCE,), (self, other))

    def _build(self):
        """A new library tree (the caller owns it)."""
        out = ffi.new("vv_shape **")
        k, a = self._kind, self._args

        def v3(t):
            return ffi.new("vv_vec3 *", {"x": t[0], "y": t[1], "z": t[2]})[0]
        if k == "sphere":
            check(lib.vv_shape_sphere(out, a[0]))
        elif k == "ellipsoid":
            check(lib.vv_shape_ellipsoid(out, v3(a[0])))
        elif k == "box":
            check(lib.vv_shape_box(out, v3(a[0]), a[1]))
        elif k == "cylinder":
            check(lib.vv_shape_cylinder(out, *a))
        elif k == "cone":
            check(lib.vv_shape_cone(out, *a))
        elif k == "torus":
            check(lib.vv_shape_torus(out, *a))
        elif k == "polygon":
            verts = ffi.new("vv_vec3[]", [{"x": p[0], "y": p[1], "z": p[2]} for p in a[0]])
            check(lib.vv_shape_polygon(out, len(a[0]), verts, a[1]))
        elif k in ("revolution", "extrusion", "helix"):
            pts = ffi.new("double[]", a[0].reshape(-1).tolist())
            if k == "revolution":
                check(lib.vv_shape_revolution(out, len(a[0]), pts))
            elif k == "extrusion":
                check(lib.vv_shape_extrusion(out, len(a[0]), pts, a[1]))
            else:
                check(lib.vv_shape_helix(out, len(a[0]), pts, a[1], a[2], a[3]))
        elif k == "mesh":
            m, mode, thick = a
            if isinstance(m, Mesh):
                check(lib.vv_shape_mesh(out, m._ptr, mode, thick))
            else:
                check(lib.vv_shape_mesh_load(out, cstr(m), mode, thick))
        elif k == "csg":
            kids = ffi.new("vv_shape *[]", len(self._children))
            try:
                for i, c in enumerate(self._children):
                    kids[i] = c._build()
            except BaseException:
                for i in range(len(self._children)):
                    lib.vv_shape_free(kids[i])
                raise
            check(lib.vv_shape_csg(out, a[0], len(self._children), kids))
        elif k == "file":
            raise InvalidError("a model file is voxelized by voxelize(path)")
        for t in self._transforms:
            if t[0] == "translate":
                m = lib.vv_mat4_translate(v3(t[1]))
            elif t[0] == "scale":
                m = lib.vv_mat4_scale(v3(t[1]))
            else:
                m = lib.vv_mat4_rotate(v3(t[1]), math.radians(t[2]))
            lib.vv_shape_transform(out[0], m)
        return out[0]

    def bounds(self):
        """(min, max) conservative bounding box (vv_shape_bounds)."""
        s = self._build()
        try:
            b = lib.vv_shape_bounds(s)
        finally:
            lib.vv_shape_free(s)
        return (np.array([b.min.x, b.min.y, b.min.z]), np.array([b.max.x, b.max.y, b.max.z]))

    def __repr__(self):
        if self._kind == "csg":
            op = pystr(lib.vv_csg_op_name(self._args[0]))
            return "Shape.%s(%s)" % (op, ", ".join(map(repr, self._children)))
        return "Shape.%s(...)" % self._kind


def voxelize(model, size=None, voxel_spacing=None, dims=None, spacing=None, origin=None,
             filter=None, radius=None, dtype=None, margin=None, threads=0, progress=None):
    """Volume-samples a geometric model into a Volume (vv_voxelize; Wang and
    Kaufman's method, docs/modeling.md): each voxel gets the sampling-kernel
    table density of its signed distance to the surface (1 inside, 0
    outside, 0.5 on it; u8 stores 255 * density, surface at 127.5).

    model: a :class:`Shape`, a :class:`Mesh` (or (vertices, triangles)), or
    a file: a mesh Assimp reads or a scene file whose "geometry" objects are
    united (their voxelization keys apply unless given here). Grid: ``dims``
    with ``spacing`` and ``origin`` (explicit), else the model's bounding
    box plus ``margin`` voxels, with ``voxel_spacing`` world units or
    ``size`` voxels along the longest axis (default 128). filter: the
    sampling kernel, "box", "tent" (default) or "gauss" of ``radius``
    voxels (default 1.5); dtype: "u8" (default) or "f32". Errors:
    InvalidError, LimitError, CancelledError."""
    o = ffi.new("vv_voxelize_options *")
    lib.vv_voxelize_options_init(o)
    if isinstance(model, (str, os.PathLike)):
        out = ffi.new("vv_shape **")
        check(lib.vv_shape_load(out, cstr(model), o))
        shape = ffi.gc(out[0], lib.vv_shape_free)
    else:
        if isinstance(model, Mesh) or isinstance(model, tuple):
            model = Shape.mesh(model)
        if not isinstance(model, Shape):
            raise InvalidError("voxelize: expected a Shape, a Mesh or a file, got %s"
                               % type(model).__name__)
        shape = ffi.gc(model._build(), lib.vv_shape_free)
    if filter is not None:
        f = ffi.new("vv_sampling_kernel_kind *")
        check(lib.vv_sampling_kernel_parse(cstr(filter), f))
        o.kernel = f[0]
    if radius is not None:
        o.radius = float(radius)
    if dtype is not None:
        name = _voxel_name(dtype) if not isinstance(dtype, str) else dtype
        if name not in ("u8", "f32"):
            raise InvalidError("voxelize: dtype must be u8 or f32, got %r" % (dtype,))
        o.type = _CODE[name]
    if dims is not None:
        for a in range(3):
            o.dims[a] = int(dims[a])
            o.spacing[a] = float(spacing[a]) if spacing is not None else 1.0
            o.origin[a] = float(origin[a]) if origin is not None else 0.0
    if voxel_spacing is not None:
        o.voxel_spacing = float(voxel_spacing)
    if size is not None:
        o.size = int(size)
    if margin is not None:
        o.margin = float(margin)
    o.threads = int(threads)
    res = ffi.new("vv_volume **")

    def run(prog):
        o.progress = prog
        return lib.vv_voxelize(res, shape, o)
    _lib.call_long(run, progress, desc="voxelize")
    return Volume._own(res[0])


# ---- compression -------------------------------------------------------------------
class Compressed:
    """A .vvc compressed volume held in memory (vv_vvc; docs/file-formats.md):
    ``info`` (dict of the header: dims, dtype, quality, ratio,
    bits_per_voxel, max_error, ...), ``bytes`` (the encoded file),
    :meth:`save`, :meth:`decompress`. ``Compressed.load(path)`` or
    ``Compressed.from_bytes(data)`` read one (every section's CRC checked)."""

    @classmethod
    def _own(cls, ptr):
        c = cls.__new__(cls)
        c._ptr = ffi.gc(ptr, lib.vv_vvc_free)
        return c

    @classmethod
    def load(cls, path):
        out = ffi.new("vv_vvc **")
        check(lib.vv_vvc_load(out, cstr(path)))
        return cls._own(out[0])

    @classmethod
    def from_bytes(cls, data, name=None):
        data = bytes(data)
        out = ffi.new("vv_vvc **")
        check(lib.vv_vvc_from_memory(out, data, len(data), cstr(name)))
        return cls._own(out[0])

    @property
    def info(self):
        i = ffi.new("vv_vvc_info *")
        lib.vv_vvc_get_info(self._ptr, i)
        return dict(version=i.version, dims=tuple(i.dims),
                    dtype=pystr(lib.vv_voxel_type_name(i.type)), spacing=tuple(i.spacing),
                    origin=tuple(i.origin), range=tuple(i.range), block=i.block,
                    quality=i.quality, slope=i.slope, max_error=i.max_error,
                    file_bytes=int(i.file_bytes), raw_bytes=int(i.raw_bytes), ratio=i.ratio,
                    bits_per_voxel=i.bits_per_voxel)

    @property
    def bytes(self):
        n = ffi.new("size_t *")
        p = lib.vv_vvc_bytes(self._ptr, n)
        return ffi.buffer(p, n[0])[:]

    def save(self, path):
        """Writes the .vvc file atomically."""
        check(lib.vv_vvc_save(self._ptr, cstr(path)))

    def decompress(self, threads=0, progress=None):
        """The decoded Volume (native type restored, header exact)."""
        out = ffi.new("vv_volume **")
        holder = {}

        def run(prog):
            holder["p"] = ffi.new("vv_progress *", prog)
            return lib.vv_vvc_decompress(out, self._ptr, int(threads), holder["p"])
        _lib.call_long(run, progress, desc="decompress")
        return Volume._own(out[0])

    def __repr__(self):
        i = self.info
        return "<volvis.Compressed %dx%dx%d %s, %.3f bits/voxel, ratio %.1f>" % (
            *i["dims"], i["dtype"], i["bits_per_voxel"], i["ratio"])


def compress(volume, quality=None, rate=None, max_error=None, block=16, slope=0.5, version=0,
             threads=0, progress=None):
    """Compresses a volume with the Fourier-domain .vvc codec (vv_vvc_compress;
    Chiueh et al. 1997): one of ``quality`` in [0, 100] (default 75), ``rate``
    (bits per voxel, whole file) or ``max_error`` (value units, every
    voxel). block: subcube side 8, 16 or 32. Returns a :class:`Compressed`.
    Errors: InvalidError, CancelledError."""
    vol = _as_volume(volume)
    p = ffi.new("vv_vvc_params *")
    lib.vv_vvc_params_init(p)
    given = [x is not None for x in (quality, rate, max_error)]
    if sum(given) > 1:
        raise InvalidError("compress: give one of quality, rate and max_error")
    if rate is not None:
        p.target, p.rate = lib.VV_VVC_RATE, float(rate)
    elif max_error is not None:
        p.target, p.max_error = lib.VV_VVC_MAX_ERROR, float(max_error)
    else:
        p.target = lib.VV_VVC_QUALITY
        if quality is not None:
            p.quality = float(quality)
    p.block, p.slope, p.version, p.threads = int(block), float(slope), int(version), int(threads)
    out = ffi.new("vv_vvc **")

    def run(prog):
        p.progress = prog
        return lib.vv_vvc_compress(out, vol._ptr, p)
    _lib.call_long(run, progress, desc="compress")
    return Compressed._own(out[0])


def decompress(data, threads=0, progress=None):
    """Decodes a :class:`Compressed`, a .vvc file path or .vvc bytes into a Volume."""
    if isinstance(data, Compressed):
        c = data
    elif isinstance(data, (bytes, bytearray, memoryview)):
        c = Compressed.from_bytes(data)
    else:
        c = Compressed.load(data)
    return c.decompress(threads=threads, progress=progress)
