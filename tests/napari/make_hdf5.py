#!/usr/bin/env python3
"""Writes, with h5py (Debian's python3-h5py: the napari tests' .venv has
none), a BigDataViewer HDF5 file of two setups (channels) and an Imaris
5.5 file, each of 3 levels (2x2x2 means), for tests/napari; the levels are
saved beside them as .npy for the test to compare.

Usage: make_hdf5.py OUT_DIR"""
import os
import sys

import h5py
import numpy as np

out = sys.argv[1]
rng = np.random.default_rng(5)


def levels(a):
    lv = [a]
    for _ in range(2):
        z, y, x = (d // 2 for d in lv[-1].shape)
        lv.append(lv[-1][:2 * z, :2 * y, :2 * x].reshape(z, 2, y, 2, x, 2).mean(axis=(1, 3, 5))
                  .astype(a.dtype))
    return lv


def chars(s):
    return np.array(list(str(s)), dtype="S1")


setups = [levels(rng.integers(0, 3000, size=(40, 48, 56)).astype(np.uint16)) for _ in range(2)]
with h5py.File(os.path.join(out, "bdv.h5"), "w") as f:
    for s, lv in enumerate(setups):
        f["s%02d/resolutions" % s] = np.array([[2.0 ** k] * 3 for k in range(len(lv))])
        f["s%02d/subdivisions" % s] = np.array([[32, 32, 32]] * len(lv), dtype=np.int32)
        for k, a in enumerate(lv):
            f.create_dataset("t00000/s%02d/%d/cells" % (s, k), data=a,
                             chunks=tuple(min(32, d) for d in a.shape), compression="gzip")
            np.save(os.path.join(out, "bdv_s%d_l%d.npy" % (s, k)), a)

lv = levels(rng.integers(0, 250, size=(36, 44, 52)).astype(np.uint8))
spacing = (2.0, 0.5, 0.25)  # z, y, x
with h5py.File(os.path.join(out, "cells.ims"), "w") as f:
    z, y, x = lv[0].shape
    img = f.create_group("DataSetInfo/Image")
    img.attrs["Unit"] = chars("um")
    for k, (n, s) in enumerate(zip((x, y, z), spacing[::-1])):
        img.attrs["ExtMin%d" % k] = chars("0")
        img.attrs["ExtMax%d" % k] = chars("%.6f" % (n * s))
    for k, a in enumerate(lv):
        g = f.create_group("DataSet/ResolutionLevel %d/TimePoint 0/Channel 0" % k)
        pad = np.zeros([-(-d // 32) * 32 for d in a.shape], a.dtype)
        pad[:a.shape[0], :a.shape[1], :a.shape[2]] = a
        g.create_dataset("Data", data=pad, chunks=(32, 32, 32), compression="gzip")
        for name, n in zip(("ImageSizeX", "ImageSizeY", "ImageSizeZ"), a.shape[::-1]):
            g.attrs[name] = chars(n)
        g.attrs["HistogramMin"] = chars("%.3f" % a.min())
        g.attrs["HistogramMax"] = chars("%.3f" % a.max())
        np.save(os.path.join(out, "ims_l%d.npy" % k), a)
