"""Reference results of SciPy's ndimage for tests/filter/test_scipy.c.

usage: scipy_ref.py OP IN NX NY NZ DTYPE OUT [PARAMS...]

Reads IN (raw voxels, x fastest, numpy DTYPE), writes OUT (raw): gaussian
SX SY SZ (sigmas in voxels) -> float32; median R -> DTYPE; erode|dilate|
open|close R (ball |d|^2 <= R^2, border 0) -> uint8; fill -> uint8;
label CONN (6, 18, 26) -> uint32. Exits 3 when SciPy is missing.
"""
import sys

try:
    import numpy as np
    from scipy import ndimage as ndi
except ImportError:
    sys.exit(3)

op, inp, nx, ny, nz, dtype, out = sys.argv[1:8]
par = sys.argv[8:]
a = np.fromfile(inp, dtype=dtype).reshape(int(nz), int(ny), int(nx))


def ball(r):
    z, y, x = np.mgrid[-r:r + 1, -r:r + 1, -r:r + 1]
    return (x * x + y * y + z * z) <= r * r


if op == "gaussian":
    sx, sy, sz = map(float, par)
    r = ndi.gaussian_filter(a.astype(np.float64), sigma=(sz, sy, sx), mode="reflect",
                            truncate=4.0).astype(np.float32)
elif op == "median":
    r = ndi.median_filter(a, size=2 * int(par[0]) + 1, mode="reflect")
elif op in ("erode", "dilate", "open", "close"):
    f = {"erode": ndi.binary_erosion, "dilate": ndi.binary_dilation,
         "open": ndi.binary_opening, "close": ndi.binary_closing}[op]
    r = f(a != 0, structure=ball(int(par[0]))).astype(np.uint8)
elif op == "fill":
    r = ndi.binary_fill_holes(a != 0).astype(np.uint8)
elif op == "label":
    conn = {"6": 1, "18": 2, "26": 3}[par[0]]
    r, n = ndi.label(a != 0, structure=ndi.generate_binary_structure(3, conn))
    r = r.astype(np.uint32)
else:
    sys.exit("unknown op " + op)
np.ascontiguousarray(r).tofile(out)
