"""Components through Python against analytic answers and independent methods."""
import math

import numpy as np
import pytest

import volvis



def sphere_volume(n=48, r=16.0, spacing=1.0):
    """Distance-to-centre field: the isosurface at r is a sphere of radius r."""
    c = (n - 1) / 2.0
    k, j, i = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    d = np.sqrt((i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2) * spacing
    return (r * spacing + 10 - d).astype(np.float32)  # inside (>= 10) within radius r


def test_isosurface_of_a_sphere():
    v = volvis.Volume(sphere_volume())
    mesh = volvis.isosurface(v, 10.0)
    verts, tris = mesh
    assert verts.shape[1] == 3 and tris.shape[1] == 3 and len(tris) > 1000
    assert mesh.topology().closed and mesh.topology().oriented
    assert mesh.area() == pytest.approx(4 * math.pi * 16 ** 2, rel=0.01)
    assert mesh.volume() == pytest.approx(4 / 3 * math.pi * 16 ** 3, rel=0.01)
    assert mesh.normals is not None and mesh.normals.shape == verts.shape
    # a cut plane through the centre halves the area
    half = volvis.isosurface(v, 10.0, cut_planes=[((23.5, 23.5, 23.5), (0, 0, 1))])
    assert half.area() == pytest.approx(mesh.area() / 2, rel=0.02)


def test_measure_agrees_with_analytic_and_histogram():
    a = sphere_volume()
    m = volvis.measure(a, isovalue=10.0, bins=64)
    assert m.volume == pytest.approx(4 / 3 * math.pi * 16 ** 3, rel=0.01)
    assert m.area == pytest.approx(4 * math.pi * 16 ** 2, rel=0.01)
    vox = volvis.measure(a, isovalue=10.0, method="voxel")
    assert vox.voxels == int((a >= 10).sum())
    assert vox.volume == pytest.approx(vox.voxels)
    counts, _ = np.histogram(a, bins=64, range=(a.min(), a.max()))
    np.testing.assert_array_equal(m.counts, counts)
    assert m.histogram.total == a.size


def test_colocalisation_matches_numpy():
    rng = np.random.default_rng(7)
    a = rng.integers(0, 1000, size=(9, 10, 11)).astype(np.uint16)
    b = (0.6 * a + rng.integers(0, 400, size=a.shape)).astype(np.float32)
    mask = (rng.random(a.shape) < 0.7).astype(np.uint8)
    c = volvis.colocalisation(a, b, mask=mask, thresholds=(300, 250))
    x, y = a[mask > 0].astype(float), b[mask > 0].astype(float)
    both = (x > 300) & (y > 250)
    assert c.voxels == int(mask.sum())
    assert c.pearson == pytest.approx(np.corrcoef(x, y)[0, 1], rel=1e-12)
    assert c.manders_m1 == pytest.approx(x[both].sum() / x[x > 300].sum(), rel=1e-12)
    assert c.manders_m2 == pytest.approx(y[both].sum() / y[y > 250].sum(), rel=1e-12)
    with pytest.raises(volvis.InvalidError, match="mask is 11 x 10 x 8"):
        volvis.colocalisation(a, b, mask=mask[:-1])


def test_filter_matches_scipy():
    ndimage = pytest.importorskip("scipy.ndimage")
    rng = np.random.default_rng(7)
    a = rng.normal(size=(20, 24, 28)).astype(np.float32)
    v = volvis.Volume(a, spacing=(1.0, 1.0, 2.0))
    g = volvis.filter(v, gaussian=2.0)
    assert g.dtype == np.float32 and g.spacing == v.spacing
    # sigma 2 world units = (2, 2, 1) voxels along (i, j, k); numpy order is (k, j, i)
    ref = ndimage.gaussian_filter(a.astype(np.float64), sigma=(1.0, 2.0, 2.0), mode="reflect",
                                  truncate=4.0)
    np.testing.assert_allclose(g.array, ref, atol=2e-5)
    m = volvis.filter(v, "--median 1")
    np.testing.assert_array_equal(m.array, ndimage.median_filter(a, size=3, mode="reflect"))
    chain = volvis.filter(v, [("gaussian", 2.0)], threshold="0:")
    np.testing.assert_array_equal(chain.array, (ref >= 0).astype(np.uint8))


def test_voxelize_sphere_and_csg():
    s = volvis.Shape.sphere(10.0)
    vol = volvis.voxelize(s, voxel_spacing=0.5)
    assert vol.dtype == np.uint8
    m = volvis.measure(vol, isovalue=127.5)
    assert m.volume == pytest.approx(4 / 3 * math.pi * 1000, rel=0.01)
    hollow = volvis.voxelize(s - volvis.Shape.sphere(5.0), voxel_spacing=0.5, dtype="f32")
    assert hollow.dtype == np.float32
    assert volvis.measure(hollow, isovalue=0.5).volume == pytest.approx(
        4 / 3 * math.pi * (1000 - 125), rel=0.02)
    lo, hi = (s | volvis.Shape.sphere(2.0).translate((20, 0, 0))).bounds()
    assert hi[0] == pytest.approx(22, abs=1e-6) and lo[0] == pytest.approx(-10, abs=1e-6)


def test_voxelize_mesh_round_trip():
    v = volvis.Volume(sphere_volume(n=40, r=12.0))
    mesh = volvis.isosurface(v, 10.0)
    vox = volvis.voxelize(mesh, voxel_spacing=0.5)
    assert volvis.measure(vox, isovalue=127.5).volume == pytest.approx(mesh.volume(), rel=0.02)


def test_compress_round_trip(tmp_path, ct_head):
    c = volvis.compress(ct_head, quality=100)
    info = c.info
    assert info["dims"] == ct_head.dims and info["dtype"] == "i16" and info["ratio"] > 1
    back = volvis.decompress(c)
    np.testing.assert_array_equal(back.array, ct_head.array)  # 16-bit integers decode exactly
    path = tmp_path / "head.vvc"
    c.save(path)
    np.testing.assert_array_equal(volvis.open(path).array, ct_head.array)
    lossy = volvis.compress(ct_head, rate=1.0)
    assert lossy.info["bits_per_voxel"] <= 1.0
    err = np.abs(volvis.decompress(lossy.bytes).array.astype(np.float64) - ct_head.array).max()
    assert 0 < err < 4000


def test_mesh_from_arrays_and_files(tmp_path):
    verts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    tris = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.uint32)
    m = volvis.Mesh(verts, tris)
    assert m.volume() == pytest.approx(1 / 6)
    m.save(tmp_path / "tet.ply")
    back = volvis.load_mesh(tmp_path / "tet.ply")
    assert back.volume() == pytest.approx(1 / 6)
    with pytest.raises(volvis.InvalidError):
        volvis.Mesh(verts, [[0, 1, 9]])


def test_animation_frames_equal_turned_stills(tmp_path, ct_head):
    world = volvis.World.for_volume(ct_head, size=(64, 64))
    anim = volvis.orbit(degrees=90, frames=3, fps=3)
    assert anim.frames == 3
    frames = []
    stats = anim.render(str(tmp_path / "f_%02d.png"), world, on_frame=lambda k, a: frames.append(k))
    assert stats["frames"] == 3 and stats["rendered"] == 3 and frames == [0, 1, 2]
    for k in range(3):
        still = volvis.World.for_volume(ct_head, size=(64, 64), azimuth=30 * k)
        np.testing.assert_array_equal(volvis.read_png(tmp_path / ("f_%02d.png" % k))[..., :3],
                                      volvis.render(still, alpha=False))
        np.testing.assert_array_equal(volvis.render(anim.world_at(world, frame=k)),
                                      volvis.render(still))
    a2 = volvis.Animation(duration=1, fps=4)
    a2.add_track("view.fov", [(0, 30), (1, 10)], interp="linear")
    assert math.degrees(a2.world_at(world, time=0.5).view._c.fov) == pytest.approx(20)
    a2.save(tmp_path / "a.json")
    assert volvis.Animation.load(tmp_path / "a.json").tracks == ["view.fov"]
    if volvis._lib_c.vv_video_codec_available(volvis._lib_c.VV_VIDEO_H264):
        out = tmp_path / "orbit.mp4"
        volvis.render_movie(out, world, volvis.orbit(frames=4, fps=4))
        assert out.stat().st_size > 0
