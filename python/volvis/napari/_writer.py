"""The napari writer of the VolVis plug-in (napari.yaml, ``volvis.write``):
an image layer to a file in a format VolVis writes, through the library's
writers (vv_volume_save_with, include/volvis/io.h): .vvb (VolVis's bricked
format, with zstd bricks, coarse bricks and pyramid levels, as ``volvis
convert`` writes it), NRRD, MetaImage, VTK (legacy and XML image data),
SLC (8 bits), NIfTI and OME-Zarr (OME-NGFF 0.5 with its pyramid).

The layer's data (its level 0 when multiscale; a lazy array is read whole
here) must be 3-D of a voxel type the library holds (volvis.VOXEL_TYPES);
its scale becomes the voxel spacing and its translate the origin, from
napari's (z, y, x) order to the library's (x, y, z). Written atomically: on
failure an existing file is left as it was. Errors: volvis.Error
subclasses with the library's one-line message naming the file, or
volvis.InvalidError for data that is not one 3-D volume.
"""
import os

import numpy as np

from .._lib import check, cstr, ffi, lib
from ..errors import InvalidError
from ..volume import Volume

__all__ = ["write_image", "EXTENSIONS"]

EXTENSIONS = (".vvb", ".nrrd", ".nhdr", ".mha", ".mhd", ".vtk", ".vti", ".slc", ".nii",
              ".nii.gz", ".ome.zarr", ".zarr")


def write_image(path, data, meta):
    """npe2 single-layer writer: writes ``data`` (an array-like, or a list of
    levels: the first is written) with ``meta`` (the layer's attributes:
    scale, translate) to ``path``; returns [path]."""
    path = os.fspath(path)
    if not path.lower().endswith(EXTENSIONS):
        raise InvalidError("volvis napari writer: %s: the extension is none of %s"
                           % (path, ", ".join(EXTENSIONS)))
    if isinstance(data, (list, tuple)):
        data = data[0]
    arr = np.asarray(data)
    if arr.ndim != 3:
        raise InvalidError("volvis napari writer: %s: the layer's data has shape %s; VolVis "
                           "writes one 3-D volume" % (path, arr.shape))
    meta = meta or {}
    scale = tuple(meta.get("scale") or (1.0, 1.0, 1.0))[-3:]
    translate = tuple(meta.get("translate") or (0.0, 0.0, 0.0))[-3:]
    vol = Volume(np.ascontiguousarray(arr), spacing=scale[::-1], origin=translate[::-1])
    opt = ffi.new("vv_save_options *")
    lib.vv_save_options_init(opt)
    if path.lower().endswith(".vvb"):
        opt.vvb_flags = lib.VV_VVB_COARSE | lib.VV_VVB_ZSTD | lib.VV_VVB_LEVELS
    check(lib.vv_volume_save_with(vol._ptr, cstr(path), opt))
    return [path]
