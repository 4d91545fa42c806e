"""volvis.Pyramid: OME-Zarr pyramids written by zarr-python (an independent
writer) read by box and rendered out of core by level of detail.

- every level's voxels are zarr-python's, with the level's scale and
  translation;
- level 0 out of core within 256 KiB of chunks (the level is 279 KiB) against the in-memory render
  of level 0 (the same World, one ray a pixel): MIP, MinIP, X-ray and the
  isosurface bit for bit in float, composite >= 50 dB; the cache within
  the limit;
- by level of detail the nodes take coarser levels, and volvis.render(pyr)
  draws the store's default scene;
- progressive frames with the background loader converge on the
  converged image (PSNR non-decreasing, the last bit for bit);
- bad input: a missing store, a memory limit that is not a size, a box
  outside a level, a renderer without regions: the library's errors;
- a .vvb with pyramid levels (`volvis convert` of the phantom) opens as a
  Pyramid: level 0 is the phantom, each level numpy's 2x2x2 means (axes
  halved rounding up, means rounded half up), its spacing and origin the
  level's.
"""
import subprocess
import pathlib
import sys

import numpy as np
import pytest

import volvis

zarr = pytest.importorskip("zarr")
numcodecs = pytest.importorskip("numcodecs")
pytest.importorskip("PIL")
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "io"))
from pyramid_common import write_ome_zarr  # noqa: E402
from conftest import cli  # noqa: E402


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    """A 3-level OME-Zarr 0.4 store of an analytic u16 phantom (a shell, a
    ball and a ramp across odd-sized axes) in 16^3 Blosc-lz4 chunks."""
    z, y, x = np.mgrid[0:45, 0:52, 0:61].astype(np.float64)
    r = np.sqrt((x - 30.3) ** 2 + (y - 25.8) ** 2 + ((z - 22.1) * 1.2) ** 2)
    arr = (1500 * np.exp(-(r - 17) ** 2 / 6.0) + 3000 * (r < 7) + 20 * x).astype(np.uint16)
    spacing = [1.5, 0.8, 0.7]  # z, y, x
    root = tmp_path_factory.mktemp("pyr") / "ph.ome.zarr"
    # the omero window gives the value range (without it, the coarsest level's)
    lv = write_ome_zarr(root, arr, spacing, (16, 16, 16),
                        numcodecs.Blosc("lz4", shuffle=numcodecs.Blosc.SHUFFLE), "/")
    return str(root), lv, spacing


def test_levels_read_as_zarr_wrote_them(store):
    path, lv, spacing = store
    p = volvis.Pyramid(path, memory_limit="16M")
    assert len(p.levels) == 3
    for k, want in enumerate(lv):
        L = p.levels[k]
        assert L.shape == want.shape and L.dtype == np.uint16
        f = 2 ** k
        assert np.allclose(L.spacing, [s * f for s in spacing[::-1]])
        assert np.allclose(L.origin, [s * (f - 1) / 2 for s in spacing[::-1]])
        assert np.array_equal(p.read(k), want)
    # a box across chunks
    box = p.read(0, (5, 9, 13), (40, 30, 33))
    assert np.array_equal(box, lv[0][13:34, 9:31, 5:41])
    assert "3 levels" in repr(p)


def test_level0_out_of_core_equals_memory(store):
    path, lv, spacing = store
    p = volvis.Pyramid(path, memory_limit="256K")
    vol = volvis.Volume(lv[0], spacing=spacing[::-1], origin=(0, 0, 0))
    ray = volvis.Renderer("raycast", refinement="off")  # regions cast every pixel
    for mode in ["mip", "minip", "xray", "iso", "composite"]:
        w = volvis.World.for_volume(vol, mode=mode, isovalue=1200, size=(96, 80), azimuth=30,
                                    elevation=20)
        ref = volvis.render(w, renderer=ray, dtype=np.float32)
        img, info = p.render(world=w, level=0, dtype=np.float32, return_lod=True)
        assert info["nodes"][0] > 1 and info["nodes"][1:] == [0, 0]
        seen = int((ref[..., 3] > 0.02).sum())
        assert seen > 500, (mode, seen)
        if mode == "composite":
            mse = float(np.mean((ref.astype(np.float64) - img) ** 2))
            assert 10 * np.log10(1 / mse) >= 50, mode
        else:
            assert np.array_equal(ref, img), mode
    st = p.stats
    assert st["peak_bytes"] <= 256 << 10
    assert st["evictions"] > 0 and sum(st["chunk_reads"]) > 0


def test_two_pyramids_out_of_core(store):
    """Two objects from two pyramids side by side, drawn out of core in one
    frame (volvis.render of a World whose objects own their pyramids, one
    cache), against the World of their level-0 volumes in memory: MIP bit
    for bit, composite >= 50 dB; overlapping composite objects are refused."""
    path, lv, spacing = store
    a = volvis.Pyramid(path, memory_limit="1M")
    b = volvis.Pyramid(path, memory_limit="1M")
    vol = volvis.Volume(lv[0], spacing=spacing[::-1], origin=(0, 0, 0))
    ray = volvis.Renderer("raycast", refinement="off")  # regions cast every pixel
    for mode in ["mip", "composite"]:
        tf = volvis.TransferFunction.ramp(200, 3000, 0.6, unit_distance=1.0)
        ref_w = volvis.World.for_volume(vol, mode=mode, size=(120, 64), azimuth=20,
                                        elevation=25)
        ref_w.objects[0].tf = tf
        ref_w.add(volvis.VolumeObject(vol, "b", position=(50, 0, 0), mode=mode, tf=tf))
        v = ref_w.view
        ref_w.view = v.frame(*ref_w.bounds())
        w = a.world(mode=mode, size=(120, 64))
        w.objects[0].tf = tf
        w.add(b.object("b", position=(50, 0, 0), mode=mode, tf=tf))
        w.view = ref_w.view
        ref = volvis.render(ref_w, renderer=ray, dtype=np.float32)
        img, info = volvis.render(w, level=0, dtype=np.float32, return_lod=True)
        assert info["nodes"][0] > 2 and info["pending"] == 0
        # both objects on screen, apart: two runs of columns
        cols = np.nonzero((ref[..., 3] > 0.05).any(axis=0))[0]
        assert cols.size > 20 and int((np.diff(cols) > 3).sum()) == 1, (mode, cols)
        if mode == "composite":
            mse = float(np.mean((ref.astype(np.float64) - img) ** 2))
            print("two pyramids, composite: %.1f dB against memory" % (10 * np.log10(1 / mse)))
            assert 10 * np.log10(1 / mse) >= 50, mode
        else:
            assert np.array_equal(ref, img), mode
        # by level of detail the objects are drawn from their pyramids' nodes,
        # not from their proxies (the coarsest level)
        lod1, info = volvis.render(w, dtype=np.float32, return_lod=True)
        assert sum(info["nodes"]) >= 2 and info["pending"] == 0  # a node or more each
        assert np.array_equal(volvis.render(w, dtype=np.float32), lod1)
    # overlapping composite objects: refused, both named
    w = a.world(mode="composite", size=(48, 48))
    w.add(b.object("b", position=(10, 0, 0)))
    with pytest.raises(volvis.UnsupportedError, match="overlap"):
        volvis.render(w)
    with pytest.raises(volvis.InvalidError, match="unknown property"):
        b.object(colour=1)


def test_measure_level0_by_boxes(store):
    """Pyramid.measure: level 0's histogram and isosurface read box by box
    equal volvis.measure of the level-0 array in memory (the counts, voxels
    and triangles exactly, areas and volumes to 1e-7)."""
    path, lv, spacing = store
    p = volvis.Pyramid(path, memory_limit="8M")
    vol = volvis.Volume(lv[0], spacing=spacing[::-1], origin=(0, 0, 0))
    for method in ["mc", "voxel"]:
        a = p.measure(isovalue=1200, method=method, bins=64)
        b = volvis.measure(vol, isovalue=1200, method=method, bins=64)
        assert np.array_equal(a.counts, b.counts) and np.allclose(a.edges, b.edges)
        assert a.voxels == b.voxels > 0 and a.n_triangles == b.n_triangles
        for k in ("area", "volume", "cut_area"):
            assert abs(getattr(a, k) - getattr(b, k)) <= 1e-7 * abs(getattr(b, k)) + 1e-9, k
        assert a.method == method and a.area_bias == b.area_bias
    h = p.measure(bins=16)
    assert h.isovalue is None and int(h.counts.sum()) == lv[0].size
    with pytest.raises(volvis.InvalidError):
        p.measure(isovalue=1e9)
    with pytest.raises(volvis.InvalidError):
        p.measure(isovalue=1200, method="count")


def test_level_of_detail(store):
    path, lv, _ = store
    p = volvis.Pyramid(path, memory_limit="8M")
    img, info = p.render(mode="mip", size=(32, 32), lod=1.0, return_lod=True)
    assert info["nodes"][0] == 0 and sum(info["nodes"]) > 0  # minified: coarser levels
    assert img.shape == (32, 32, 4) and img[..., :3].max() > 0
    img = volvis.render(p, mode="iso", size=(64, 48))
    assert img.shape == (48, 64, 4) and int((img[..., 3] == 255).sum()) > 200
    w = p.world(mode="composite", size=(40, 40))
    assert w.objects[0].volume.dims == tuple(p.levels[-1].shape[::-1])


def test_progressive_background_loading(store):
    """Progressive frames draw what is resident and leave the rest to the
    background loader: each frame is at least as close to the converged one,
    the last is it bit for bit, and no chunk is read twice."""
    path, lv, _ = store
    conv = volvis.Pyramid(path, memory_limit="8M")
    w = conv.world(mode="composite", size=(96, 96))
    ref = conv.render(w, lod=0.5, dtype=np.float32)
    p = volvis.Pyramid(path, memory_limit="8M")
    psnr, info = [], {"pending": 1}
    for _ in range(200):
        img, info = p.render(w, lod=0.5, dtype=np.float32, progressive=True, return_lod=True)
        err = float(np.mean((img - ref) ** 2))
        psnr.append(99.0 if err == 0 else 10 * np.log10(1.0 / err))
        if not info["pending"]:
            break
        p.wait(10.0)
    st = p.stats
    print("PSNR per frame", [round(q, 1) for q in psnr], st["loaded"], "chunks loaded")
    assert len(psnr) >= 2 and psnr[0] < 99.0  # the first frame came from coarser levels
    assert all(b >= a for a, b in zip(psnr, psnr[1:]))
    assert info["pending"] == 0 and np.array_equal(img, ref)
    assert st["loaded"] > 0 and st["load_errors"] == 0
    nchunks = sum(int(np.prod([-(-n // 16) for n in a.shape])) for a in lv)
    assert sum(st["chunk_reads"]) <= nchunks  # none read twice
    p.cancel()
    assert p.wait(5.0) == 0 and p.loading == 0


def test_bad_input(store, tmp_path):
    path, _, _ = store
    with pytest.raises(volvis.Error, match="nothing.zarr"):
        volvis.Pyramid(str(tmp_path / "nothing.zarr"))
    with pytest.raises(volvis.InvalidError, match="not a size"):
        volvis.Pyramid(path, memory_limit="lots")
    p = volvis.Pyramid(path, memory_limit="8M")
    with pytest.raises(volvis.InvalidError):
        p.read(1, (0, 0, 0), (999, 0, 0))
    with pytest.raises(volvis.InvalidError, match="level 5 of 3"):
        p.read(5)
    with pytest.raises(volvis.UnsupportedError, match="splat renders no regions"):
        p.render(renderer="splat", size=(16, 16))


def next_level(a):
    """The .vvb writer's next level, by numpy: every axis longer than one
    voxel halved rounding up, each voxel the mean of the voxels under it
    (fewer at an odd edge), rounded half up."""
    f = a.astype(np.float64)
    for ax in range(3):
        n = f.shape[ax]
        if n < 2:
            continue
        if n % 2:
            pad = [(0, 0)] * 3
            pad[ax] = (0, 1)
            f = np.pad(f, pad, constant_values=np.nan)
        shape = list(f.shape)
        shape[ax:ax + 1] = [shape[ax] // 2, 2]
        f = np.nanmean(f.reshape(shape), axis=ax + 1)
    return np.floor(f + 0.5).astype(a.dtype)


def test_vvb_levels(tmp_path):
    z, y, x = np.mgrid[0:67, 0:70, 0:131].astype(np.float64)
    arr = (1000 * np.sin(x / 9) * np.cos(y / 7) + 13 * z + 2000).astype(np.uint16)
    spacing = [1.5, 0.8, 0.7]  # z, y, x
    raw, vvb = tmp_path / "ph.raw", tmp_path / "ph.vvb"
    arr.tofile(raw)
    dims = f"{arr.shape[2]}x{arr.shape[1]}x{arr.shape[0]}"
    sp = f"{spacing[2]}x{spacing[1]}x{spacing[0]}"
    r = subprocess.run([cli(), "convert", "--raw", f"{dims}:u16:{sp}", str(raw), str(vvb)],
                       capture_output=True, text=True)
    assert r.returncode == 0 and "3 pyramid levels" in r.stdout, r.stdout + r.stderr
    p = volvis.Pyramid(str(vvb), memory_limit="16M")
    assert len(p.levels) == 3  # 131 x 70 x 67, 66 x 35 x 34, 33 x 18 x 17
    want = arr
    for k, L in enumerate(p.levels):
        f = 2 ** k
        assert L.shape == want.shape and L.dtype == np.uint16
        assert np.allclose(L.spacing, [s * f for s in spacing[::-1]])
        assert np.allclose(L.origin, [s * (f - 1) / 2 for s in spacing[::-1]])
        assert np.array_equal(p.read(k), want)
        want = next_level(want)
