"""VolVis for Python: volumes from numpy, the World, rendering to numpy,
and the components (filtering, surfaces, measurement, modeling,
compression, animation), over the C library libvolvis (cffi, API mode).

    import numpy as np, volvis
    vol = volvis.open("head.nrrd")               # or volvis.Volume(array, spacing=...)
    img = volvis.render(vol, mode="mip")         # (h, w, 4) uint8 numpy array
    world = volvis.World.open("scan.ome.zarr", memory="out_of_core")  # file, folder, scene
    world = volvis.load_scene("examples/ct_head.json")
    img = volvis.render(world, renderer="raytrace", size=(512, 512))

Axis order: numpy [k, j, i] (C order), the library's i-fastest layout.
Angles are degrees, lengths world units. Errors raise volvis.Error
subclasses carrying the library's message. Reference: docs/python.md.
"""
from ._volvis import ffi as _ffi, lib as _lib_c
from .errors import (CancelledError, Error, FileError, FormatError, InvalidError, LimitError,
                     NoMemoryError, UnsupportedError)
from .volume import VOXEL_TYPES, Histogram, Volume, open
from .world import (Box, CutPlane, Cylinder, GridObject, Light, Material, MeshObject, Object,
                    Plane, Polygon, Sphere, TransferFunction, TransferFunction2D, View, VolumeObject,
                    World, load_scene, tf_presets)
from .render import Image, Renderer, RendererInfo, render, renderers
from .pyramid import Level, Pyramid, memory_limit, remote_stats
from .mesh import Grid, Mesh, load_grid, load_mesh
from .components import (Colocalisation, Compressed, Measurement, Shape, colocalisation,
                         compress, decompress, filter, filters, isosurface, measure, voxelize)
from .animation import Animation, orbit, render_movie
from . import notebook
from .notebook import read_png, save_png, show

__version__ = _ffi.string(_lib_c.vv_version()).decode()


def set_threads(n):
    """Default number of threads of the library's parallel loops (0: all cores)."""
    _lib_c.vv_threads_set(int(n))


def get_threads():
    """The number of threads a parallel loop uses now."""
    return _lib_c.vv_threads_get()


__all__ = [
    "Error", "NoMemoryError", "FileError", "FormatError", "InvalidError", "UnsupportedError",
    "LimitError", "CancelledError",
    "Volume", "open", "Histogram", "VOXEL_TYPES",
    "View", "Light", "CutPlane", "Material", "TransferFunction", "TransferFunction2D", "tf_presets",
    "Object", "VolumeObject", "GridObject", "Sphere", "Box", "Plane", "Cylinder", "Polygon",
    "MeshObject", "World", "load_scene",
    "Renderer", "RendererInfo", "renderers", "render", "Image", "Pyramid", "Level",
    "memory_limit", "remote_stats",
    "Mesh", "load_mesh", "Grid", "load_grid",
    "filter", "filters", "isosurface", "measure", "Measurement", "colocalisation",
    "Colocalisation", "voxelize", "Shape", "compress",
    "decompress", "Compressed",
    "Animation", "orbit", "render_movie", "show", "read_png", "save_png", "set_threads", "get_threads",
]
