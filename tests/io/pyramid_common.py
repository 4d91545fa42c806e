"""Helpers shared by the pyramid tests (zarr_pyramid_cli.py, hdf5_pyramid_cli.py,
tests/python/test_pyramid.py)."""
import re

import numpy as np
from PIL import Image


def levels_of(arr, n=3):
    """Level 0 and n - 1 levels of 2x2x2 means (rounded), each axis halved (floor)."""
    out = [arr]
    for _ in range(1, n):
        p = out[-1]
        z, y, x = [s // 2 * 2 for s in p.shape]
        q = p[:z, :y, :x].astype(np.float64).reshape(z // 2, 2, y // 2, 2, x // 2, 2)
        out.append(np.rint(q.mean(axis=(1, 3, 5))).astype(arr.dtype))
    return out


def write_ome_zarr(root, arr, spacing, chunks, compressor, sep, n=3, window=True):
    """An OME-Zarr 0.4 store at @root written by zarr-python: n levels of
    levels_of(arr), each with its scale and the translation of its voxel
    centres (spacing z, y, x), chunks, compressor (numcodecs) and dimension
    separator sep; with window, the omero window of the data's min and max.
    Returns the levels."""
    import zarr
    store = zarr.DirectoryStore(str(root), dimension_separator=sep)
    g = zarr.open_group(store, mode="w")
    lv = levels_of(arr, n)
    ds = []
    for k, a in enumerate(lv):
        g.create_dataset(str(k), data=a, chunks=chunks, compressor=compressor,
                         dimension_separator=sep)
        f = 2 ** k
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [s * f for s in spacing]},
            {"type": "translation", "translation": [s * (f - 1) / 2 for s in spacing]}]})
    g.attrs["multiscales"] = [{"version": "0.4", "axes": [
        {"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"], "datasets": ds}]
    if window:
        lo, hi = float(arr.min()), float(arr.max())
        g.attrs["omero"] = {"channels": [{"label": "v", "color": "FFFFFF", "window": {
            "min": lo, "max": hi, "start": lo, "end": hi}}]}
    return lv


def image(path):
    """A PNG as float64 RGB, or RGBA when its name ends in _a.png."""
    return np.asarray(Image.open(path).convert("RGBA" if path.endswith("_a.png") else "RGB"),
                      dtype=np.float64)


def psnr(a, b):
    """PSNR (dB) of two PNGs; 99 when identical."""
    m = ((image(a) - image(b)) ** 2).mean()
    return 99.0 if m == 0 else 10 * np.log10(255.0 ** 2 / m)


def stats(p):
    """(peak cache MiB, most reads of one chunk in a frame, nodes per level) from
    the line of an out-of-core `volvis render`."""
    m = re.search(r"peak cache ([0-9.]+) MiB, a chunk read at most (\d+) times", p.stdout)
    nodes = [int(x) for x in re.findall(r"(\d+) nodes \d+ chunks", p.stdout)]
    return (float(m.group(1)), int(m.group(2)), nodes) if m else (None, None, nodes)


def cracks(a_png, b_png):
    """Pixels opaque (alpha > 128) in one image and empty (< 8) in the other."""
    a, b = image(a_png), image(b_png)
    return int(np.sum((b[..., 3] > 128) & (a[..., 3] < 8)) + np.sum((a[..., 3] > 128) &
                                                                     (b[..., 3] < 8)))
