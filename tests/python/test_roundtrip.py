"""Numpy round trips: projections of a volume made in numpy equal numpy's
reductions of the same array (mapped through the transfer function)."""
import numpy as np

import volvis


def plateau_volume(rng, nk=24, nj=20, ni=16):
    """Random integers inside a zero border; the maximum of each k column is
    doubled into its neighbour, so a MIP sampled anywhere between the two
    equal voxels sees the exact maximum."""
    a = np.zeros((nk, nj, ni), np.uint8)
    a[1:-1, 1:-1, 1:-1] = rng.integers(0, 256, size=(nk - 2, nj - 2, ni - 2))
    k = a.argmax(axis=0)
    for j in range(nj):
        for i in range(ni):
            kk = k[j, i]
            nb = kk + 1 if kk + 1 < nk - 1 else kk - 1
            if nb >= 1:
                a[nb, j, i] = a[kk, j, i]
    return a


def top_down(a, mode, spacing=(1.0, 1.0, 1.0)):
    """A World looking down -z at the volume, orthographic, one pixel per
    voxel with pixel centres on voxel centres; image row 0 is the largest j."""
    nk, nj, ni = a.shape
    vol = volvis.Volume(a, spacing=spacing)
    w = volvis.World()
    o = w.add(volvis.VolumeObject(vol, mode=mode, step=0.5))
    # a flat-ended grey ramp: grey = v / 255 exactly, opacity 1 everywhere
    o.tf = volvis.TransferFunction(opacity=[(0, 1), (255, 1)],
                                   color=[(0, (0, 0, 0)), (255, (1, 1, 1))])
    sx, sy, sz = spacing
    c = np.array([(ni - 1) * sx / 2, (nj - 1) * sy / 2, (nk - 1) * sz / 2])
    w.view = volvis.View(eye=c + (0, 0, 10 * nk * sz), at=c, up=(0, 1, 0),
                         projection="orthographic", ortho_height=nj * sy, size=(ni, nj))
    return w, o


def test_mip_equals_numpy_max(rng):
    a = plateau_volume(rng)
    w, _ = top_down(a, "mip")
    img = volvis.render(w)
    assert img.shape == (a.shape[1], a.shape[2], 4) and img.dtype == np.uint8
    expected = np.flipud(a.max(axis=0))
    np.testing.assert_array_equal(img[..., 0], expected)
    np.testing.assert_array_equal(img[..., 1], expected)
    np.testing.assert_array_equal(img[..., 3], 255)


def test_mip_fortran_ijk_array_is_the_same_volume(rng):
    a = plateau_volume(rng)
    f = np.asfortranarray(a.transpose(2, 1, 0))  # indexed [i, j, k], i fastest in memory
    vol = volvis.Volume(f, axes="ijk")
    assert vol.shares_memory and vol.dims == (a.shape[2], a.shape[1], a.shape[0])
    np.testing.assert_array_equal(vol.array, a)
    w, o = top_down(a, "mip")
    o2 = w.add(volvis.VolumeObject(vol, mode="mip"))
    o2.tf = o.tf
    w.remove(o)
    np.testing.assert_array_equal(volvis.render(w)[..., 0], np.flipud(a.max(axis=0)))


def test_minip_equals_numpy_min(rng):
    a = plateau_volume(rng)
    a[1:-1, 1:-1, 1:-1] = 255 - a[1:-1, 1:-1, 1:-1]  # plateaus now at the minima
    inner = a[1:-1]
    w, _ = top_down(inner.copy(), "minip")
    img = volvis.render(w)
    np.testing.assert_array_equal(img[1:-1, 1:-1, 0], np.flipud(inner.min(axis=0))[1:-1, 1:-1])


def test_xray_is_the_sum_along_the_axis_times_the_spacing(rng):
    """The ray caster's xray is the mean of its samples every half voxel over
    [0, n - 1] (docs/rendering.md), both ends included: with zero end slices
    that mean is 2 * sum / (2n - 1), i.e. the line integral sum * spacing
    over an effective chord of (n - 1/2) * spacing. Tolerance: one entry of
    the 4096-entry table over the value range."""
    a = plateau_volume(rng).astype(np.float32)
    a[:, :, 0] = 0
    a[-1, 0, 0] = 255  # the range, so the table covers [0, 255]
    dz = 1.5  # isotropic, so the step (half the smallest spacing) is half a voxel along k
    w, _ = top_down(a, "xray", spacing=(dz, dz, dz))
    f = volvis.render(w, dtype=np.float32)
    n = a.shape[0]
    integral = a.sum(axis=0) * dz
    expected = np.flipud(integral / ((n - 0.5) * dz))
    got = f[..., 0] * 255.0
    inner = (slice(1, -1), slice(1, -1))
    np.testing.assert_allclose(got[inner], expected[inner], atol=255.0 / 4095 + 1e-4)


def test_float_output_and_depth(rng):
    a = plateau_volume(rng)
    w, _ = top_down(a, "mip")
    rgba, depth = volvis.render(w, dtype=np.float32, depth=True)
    assert rgba.dtype == np.float32 and rgba.shape == (a.shape[1], a.shape[2], 4)
    assert depth.shape == a.shape[1:] and depth.dtype == np.float32
    np.testing.assert_array_equal(np.round(rgba[..., 0] * 255).astype(np.uint8),
                                  volvis.render(w)[..., 0])
    assert np.isfinite(depth[5, 5]) and depth[5, 5] > 0


def test_volume_metadata_and_histogram(rng):
    a = rng.integers(-100, 100, size=(5, 6, 7)).astype(np.int16)
    v = volvis.Volume(a, spacing=(0.5, 0.25, 2), origin=(1, 2, 3), unit="mm")
    assert v.dims == (7, 6, 5) and v.shape == (5, 6, 7) and v.dtype == np.int16
    assert v.spacing == (0.5, 0.25, 2.0) and v.origin == (1.0, 2.0, 3.0) and v.unit == "mm"
    assert v.range == (a.min(), a.max())
    m = v.index_to_world()
    np.testing.assert_allclose(m @ [6, 5, 4, 1], [1 + 3, 2 + 1.25, 3 + 8, 1])
    h = v.histogram(bins=10, range=(-100, 100))
    expected, _ = np.histogram(a, bins=10, range=(-100, 100))
    np.testing.assert_array_equal(h.counts, expected)
    assert h.total == a.size and abs(h.mean - a.mean()) < 1e-9
    with np.testing.assert_raises(ValueError):
        v.array[0, 0, 0] = 1  # read-only view


def napari_attenuated_mip(a, lo, hi, attenuation, step):
    """napari's attenuated MIP (VisPy's volume shader, ATTENUATED_MIP
    snippet) reimplemented in numpy for rays down -z through the voxel
    columns of ``a`` (nk, nj, ni), samples every ``step`` voxels from the
    last slice (the front) to the first, linear between the voxels: the
    running sum S of clamp((v - lo) / (hi - lo), 0, 1), each value scaled by
    exp(-attenuation (S - 1) / step), the largest scaled value per column."""
    nk = a.shape[0]
    z = np.arange(nk - 1, -1e-9, -step)  # front to back
    k0 = np.floor(z).astype(int)
    k1 = np.minimum(k0 + 1, nk - 1)
    f = (z - k0)[:, None, None]
    v = (1 - f) * a[k0].astype(np.float64) + f * a[k1].astype(np.float64)
    s = np.cumsum(np.clip((v - lo) / (hi - lo), 0, 1), axis=0)
    return (v * np.exp(-attenuation * (s - 1) / step)).max(axis=0)


def test_attenuated_mip_equals_numpy_napari(rng):
    """attenuated-mip of a random float volume equals the numpy
    reimplementation of napari's shader, and differs from MIP."""
    a = rng.uniform(0, 255, size=(20, 12, 10)).astype(np.float32)
    a[:6] *= 0.5  # dimmer far slices
    a[0, 0, 0], a[-1, 0, 0] = 0, 255  # the range is [0, 255] exactly
    lo, hi = 30.0, 230.0
    for att in (0.0, 0.02, 0.05, 0.3):
        w, o = top_down(a, "attenuated-mip")
        o.attenuation = att
        o.tf = volvis.TransferFunction(opacity=[(lo, 1), (hi, 1)],
                                       color=[(0, (0, 0, 0)), (255, (1, 1, 1))])
        img = volvis.render(w)
        # the table spans the volume's range: a scaled value beyond it
        # takes the colour at its end
        want = np.flipud(np.clip(napari_attenuated_mip(a, lo, hi, att, 0.5), 0, 255))
        got = img[..., 0].astype(np.float64)
        worst = np.max(np.abs(got - want))
        assert worst <= 1.1, "attenuation %g: up to %.2f grey levels from napari's" % (att, worst)
        if att >= 0.05:
            assert np.mean(np.abs(want - np.flipud(a.max(axis=0)))) > 5  # not a MIP
