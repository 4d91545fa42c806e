#!/usr/bin/python3
"""SciPy ndimage peer of bench/bench_filter (run by it, in the same run).

usage: filter_scipy.py RAW NX NY NZ DTYPE OP RUNS [THRESHOLD]

Reads the raw volume bench_filter wrote (x fastest), times OP RUNS times
and prints the median as `anchor=scipy op=OP dataset=ct_head.nrrd value=MS
unit=ms`. OP: gaussian2 (sigma 2 voxels, float32 output), median1 (3x3x3),
cc6 / cc26 (ndimage.label of value >= THRESHOLD, the mask made beforehand).
SciPy's ndimage is single-threaded C.
"""
import statistics
import sys
import time

import numpy as np
from scipy import ndimage as ndi

raw, nx, ny, nz, dtype, op, runs = sys.argv[1:8]
thr = float(sys.argv[8]) if len(sys.argv) > 8 else 300.0
a = np.fromfile(raw, dtype=dtype).reshape(int(nz), int(ny), int(nx))
mask = a >= thr
times = []
for _ in range(int(runs)):
    t = time.perf_counter()
    if op == "gaussian2":
        ndi.gaussian_filter(a, sigma=2.0, output=np.float32, mode="reflect", truncate=4.0)
    elif op == "median1":
        ndi.median_filter(a, size=3, mode="reflect")
    elif op == "cc6":
        ndi.label(mask, structure=ndi.generate_binary_structure(3, 1))
    elif op == "cc26":
        ndi.label(mask, structure=ndi.generate_binary_structure(3, 3))
    else:
        sys.exit("unknown op " + op)
    times.append((time.perf_counter() - t) * 1000)
print("anchor=scipy op=filter_%s dataset=ct_head.nrrd value=%.6g unit=ms"
      % (op, statistics.median(times)))
