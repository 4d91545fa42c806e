"""Triangle meshes (vv_mesh) and irregular grids (vv_grid)."""
import dataclasses

import numpy as np

from ._lib import check, cstr, ffi, lib, pystr
from .errors import InvalidError
from .volume import _ArrayHolder

__all__ = ["Mesh", "load_mesh", "Grid", "load_grid", "MeshTopology"]


@dataclasses.dataclass
class MeshTopology:
    """Edge topology of a mesh (vv_mesh_topology_compute)."""
    vertices_used: int
    edges: int
    boundary_edges: int
    nonmanifold_edges: int
    misoriented_edges: int
    degenerate: int
    euler: int
    closed: bool
    oriented: bool


def _view(owner, ptr, count, width, dtype):
    if ptr == ffi.NULL or count == 0:
        return np.empty((0, width) if width > 1 else (0,), dtype=dtype)
    shape = (count, width) if width > 1 else (count,)
    a = np.asarray(_ArrayHolder(owner, int(ffi.cast("uintptr_t", ptr)), shape, np.dtype(dtype)))
    a.flags.writeable = False
    return a


class Mesh:
    """An indexed triangle mesh: ``Mesh(vertices, triangles, normals=None,
    scalars=None)`` with vertices an (n, 3) array (world units, stored as
    float32), triangles an (m, 3) array of vertex indices (uint32),
    normals (n, 3) unit vectors, scalars (n,). The arrays are copied into
    the library's mesh. Counter-clockwise triangles seen from outside give
    a positive signed volume. Unpacks as ``vertices, triangles = mesh``."""

    def __init__(self, vertices, triangles, normals=None, scalars=None):
        v = np.ascontiguousarray(vertices, dtype=np.float32).reshape(-1, 3)
        t = np.asarray(triangles)
        if t.size and (t.min() < 0 or t.max() >= len(v)):
            raise InvalidError("Mesh: a triangle index is outside 0..%d (got %d..%d)"
                               % (len(v) - 1, t.min(), t.max()))
        t = np.ascontiguousarray(t, dtype=np.uint32).reshape(-1, 3)
        out = ffi.new("vv_mesh **")
        check(lib.vv_mesh_new(out))
        self._ptr = ffi.gc(out[0], lib.vv_mesh_free)
        m = self._ptr
        check(lib.vv_mesh_reserve(m, len(v), len(t)))
        check(lib.vv_mesh_enable_attributes(m, normals is not None, scalars is not None))
        check(lib.vv_mesh_reserve(m, len(v), len(t)))
        ffi.memmove(m.positions, ffi.from_buffer(v), v.nbytes)
        ffi.memmove(m.triangles, ffi.from_buffer(t), t.nbytes)
        if normals is not None:
            n = np.ascontiguousarray(normals, dtype=np.float32).reshape(len(v), 3)
            ffi.memmove(m.normals, ffi.from_buffer(n), n.nbytes)
        if scalars is not None:
            s = np.ascontiguousarray(scalars, dtype=np.float32).reshape(len(v))
            ffi.memmove(m.scalars, ffi.from_buffer(s), s.nbytes)
        m.n_vertices = len(v)
        m.n_triangles = len(t)

    @classmethod
    def _own(cls, ptr):
        self = cls.__new__(cls)
        self._ptr = ffi.gc(ptr, lib.vv_mesh_free)
        return self

    @property
    def vertices(self):
        """(n, 3) float32 read-only view of the vertex positions."""
        return _view(self, self._ptr.positions, self._ptr.n_vertices, 3, np.float32)

    @property
    def triangles(self):
        """(m, 3) uint32 read-only view of the triangles' vertex indices."""
        return _view(self, self._ptr.triangles, self._ptr.n_triangles, 3, np.uint32)

    @property
    def normals(self):
        """(n, 3) float32 unit normals, or None."""
        if self._ptr.normals == ffi.NULL:
            return None
        return _view(self, self._ptr.normals, self._ptr.n_vertices, 3, np.float32)

    @property
    def scalars(self):
        """(n,) float32 per-vertex scalars, or None."""
        if self._ptr.scalars == ffi.NULL:
            return None
        return _view(self, self._ptr.scalars, self._ptr.n_vertices, 1, np.float32)

    def __iter__(self):
        return iter((self.vertices, self.triangles))

    def __len__(self):
        return 2

    def area(self):
        """Total triangle area, world units squared."""
        return lib.vv_mesh_area(self._ptr)

    def signed_volume(self):
        """Signed enclosed volume by the divergence theorem, world units cubed."""
        return lib.vv_mesh_signed_volume(self._ptr)

    def volume(self):
        """Enclosed volume of a closed mesh (vv_measure_mesh_volume). Errors:
        InvalidError for an open or non-manifold mesh."""
        out = ffi.new("double *")
        check(lib.vv_measure_mesh_volume(self._ptr, out))
        return out[0]

    def topology(self):
        """The mesh's edge topology, a :class:`MeshTopology`."""
        t = ffi.new("vv_mesh_topology *")
        check(lib.vv_mesh_topology_compute(self._ptr, t))
        return MeshTopology(t.n_vertices_used, t.n_edges, t.n_boundary_edges,
                            t.n_nonmanifold_edges, t.n_misoriented_edges, t.n_degenerate,
                            t.euler, bool(t.closed), bool(t.oriented))

    def bounds(self):
        """(min, max) of the vertices."""
        b = lib.vv_mesh_bounds(self._ptr)
        return (np.array([b.min.x, b.min.y, b.min.z]), np.array([b.max.x, b.max.y, b.max.z]))

    def compute_normals(self):
        """Sets area-weighted vertex normals. Returns self."""
        check(lib.vv_mesh_compute_normals(self._ptr))
        return self

    def transform(self, matrix):
        """Transforms in place by a 4x4 matrix (normals by its inverse
        transpose). Returns self."""
        m = np.asarray(matrix, dtype=np.float64).reshape(4, 4)
        c = ffi.new("vv_mat4 *")
        for r in range(4):
            for k in range(4):
                c.m[r][k] = m[r, k]
        lib.vv_mesh_transform(self._ptr, c[0])
        return self

    def distance(self, other, threads=0):
        """(distance, point on self, point on other): the minimum distance
        between two meshes' surfaces (vv_measure_mesh_distance)."""
        d = ffi.new("double *")
        pa, pb = ffi.new("vv_vec3 *"), ffi.new("vv_vec3 *")
        check(lib.vv_measure_mesh_distance(self._ptr, other._ptr, int(threads), d, pa, pb))
        return d[0], np.array([pa.x, pa.y, pa.z]), np.array([pb.x, pb.y, pb.z])

    def save(self, path):
        """Writes .ply, .obj, .stl, .glb (glTF 2.0 binary) or .vtp (VTK XML PolyData) by the extension, atomically."""
        check(lib.vv_mesh_save(self._ptr, cstr(path)))

    def __repr__(self):
        return "<volvis.Mesh %d vertices, %d triangles>" % (self._ptr.n_vertices,
                                                           self._ptr.n_triangles)


def load_mesh(path):
    """Loads a triangle mesh through Assimp (OBJ, PLY, STL, OFF, ...;
    vv_mesh_load). Errors: FileError, FormatError, LimitError."""
    out = ffi.new("vv_mesh **")
    check(lib.vv_mesh_load(out, cstr(path)))
    return Mesh._own(out[0])


class Grid:
    """An irregular grid (vv_grid): unstructured, curvilinear or spherical,
    with point and cell fields. Made by :func:`load_grid`."""

    @classmethod
    def _own(cls, ptr):
        self = cls.__new__(cls)
        self._ptr = ffi.gc(ptr, lib.vv_grid_free)
        return self

    @property
    def kind(self):
        """"unstructured", "curvilinear" or "spherical"."""
        return pystr(lib.vv_grid_kind_name(self._ptr.kind))

    @property
    def n_points(self):
        return self._ptr.n_points

    @property
    def n_cells(self):
        return self._ptr.n_cells

    @property
    def points(self):
        """(n, 3) float64 read-only view of the points, world units."""
        return _view(self, self._ptr.points, self._ptr.n_points, 3, np.float64)

    @property
    def fields(self):
        """Field names in order."""
        return [ffi.string(self._ptr.fields[i].name).decode() for i in range(self._ptr.n_fields)]

    def field(self, name, component=-1, time=0):
        """The scalars of a field as a float32 array (one per point or cell;
        NaN where missing); vectors give their magnitude unless a
        ``component`` is given. Errors: InvalidError (unknown field)."""
        idx = lib.vv_grid_find_field(self._ptr, cstr(name), int(time))
        if idx < 0:
            raise InvalidError("grid: no field %r (fields: %s)" % (name, ", ".join(self.fields)))
        out = ffi.new("float **")
        check(lib.vv_grid_field_scalars(self._ptr, idx, int(component), out))
        n = self._ptr.fields[idx].n_tuples
        try:
            return np.frombuffer(ffi.buffer(out[0], 4 * n), dtype=np.float32).copy()
        finally:
            lib.vvpy_free(out[0])

    def bounds(self):
        """(min, max) of the points."""
        b = lib.vv_grid_bounds(self._ptr)
        return (np.array([b.min.x, b.min.y, b.min.z]), np.array([b.max.x, b.max.y, b.max.z]))

    def __repr__(self):
        return "<volvis.Grid %s, %d points, %d cells, fields %s>" % (
            self.kind, self.n_points, self.n_cells, self.fields)


def load_grid(path):
    """Loads an irregular grid (VTK legacy and XML, OpenDX, PLOT3D, NetCDF;
    vv_grid_load). Errors: FileError, FormatError, LimitError,
    UnsupportedError."""
    out = ffi.new("vv_grid **")
    check(lib.vv_grid_load(out, cstr(path)))
    return Grid._own(out[0])
