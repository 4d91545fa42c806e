"""Zero copy: a Volume shares the numpy array's memory."""
import gc
import resource

import numpy as np

import volvis
from conftest import SANITIZER


def peak_rss_bytes():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def test_one_gib_volume_raises_peak_memory_by_far_less_than_one_gib():
    n = 1024  # 1024 x 1024 x 512 u16 = 1 GiB
    a = np.empty((512, n, n), np.uint16)
    a[...] = 7  # touch every page: the array is resident before the Volume exists
    a[100, 200, 300] = 4000
    before = peak_rss_bytes()
    v = volvis.Volume(a, spacing=(0.5, 0.5, 1.0))
    after = peak_rss_bytes()
    assert v.shares_memory
    assert v.range == (7.0, 4000.0)
    grew = after - before
    print("peak RSS grew by %.1f MiB for a 1 GiB Volume" % (grew / 2**20))
    # AddressSanitizer checks each load against its shadow, one byte per
    # eight bytes of memory: reading the array for its range touches
    # a.nbytes / 8 of shadow, which is the sanitizer's, not a copy
    limit = 64 * 2**20 + (a.nbytes // 8 if SANITIZER else 0)
    assert grew < limit, grew
    # the voxels are the array's own memory
    assert np.shares_memory(v.array, a)
    del v, a
    gc.collect()


def test_writes_to_the_array_are_seen_by_the_next_render():
    a = np.zeros((16, 16, 16), np.uint8)
    a[4:12, 4:12, 4:12] = 100
    vol = volvis.Volume(a)
    w = volvis.World.for_volume(vol, mode="mip", size=(48, 48), tf_range=(0, 255))
    r = volvis.Renderer("raycast")  # keeps its caches between renders
    first = volvis.render(w, renderer=r)
    a[6:10, 6:10, 6:10] = 250  # written in place
    second = volvis.render(w, renderer=r)
    assert vol.range == (0.0, 250.0)
    assert second[..., 0].max() > first[..., 0].max()
    fresh = volvis.render(volvis.World.for_volume(volvis.Volume(a.copy()), mode="mip",
                                                  size=(48, 48), tf_range=(0, 255)))
    np.testing.assert_array_equal(second, fresh)


def test_the_volume_keeps_the_array_alive():
    a = np.arange(24 * 20 * 16, dtype=np.float32).reshape(24, 20, 16)
    w = volvis.World.for_volume(volvis.Volume(a), size=(32, 32))
    expected = volvis.render(w)
    ref = a.copy()
    del a
    gc.collect()
    # only the World's object holds the volume now, and through it the array
    np.testing.assert_array_equal(volvis.render(w), expected)
    np.testing.assert_array_equal(w.objects[0].volume.array, ref)


def test_layouts_that_cannot_be_shared_are_copied_or_refused():
    c = np.arange(60, dtype=np.int16).reshape(3, 4, 5)
    f = np.asfortranarray(c)  # [k, j, i] but k fastest: copied
    v = volvis.Volume(f)
    assert not v.shares_memory
    np.testing.assert_array_equal(v.array, c)
    try:
        volvis.Volume(f, copy=False)
    except volvis.InvalidError as e:
        assert "copy=False" in str(e)
    else:
        raise AssertionError("copy=False accepted a Fortran array for axes 'kji'")
    be = c.astype(">i2")
    v = volvis.Volume(be)
    assert not v.shares_memory
    np.testing.assert_array_equal(v.array, c)
