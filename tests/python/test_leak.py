"""No leak: 1000 create/render/free cycles leave the resident set stable."""
import gc

import numpy as np

import volvis
from conftest import SANITIZER


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


def cycle(k, rng):
    a = rng.integers(0, 255, size=(32, 32, 32), dtype=np.uint8)
    vol = volvis.Volume(a)  # shares the array
    w = volvis.World.for_volume(vol, size=(32, 32), azimuth=k % 360)
    w.add(volvis.Sphere(radius=5))
    img = volvis.render(w, renderer="raycast" if k % 2 else "raytrace", quality=0)
    mesh = volvis.isosurface(vol, 128)
    assert img.shape == (32, 32, 4) and len(mesh.vertices) > 0


# Under the sanitizers (VV_SANITIZER) RSS cannot show a leak: the
# quarantine holds up to 256 MiB of freed memory, more than 1000 leaking
# cycles would add. There the cycles check memory safety and the shared
# arrays' release only, and 100 of them do that as well as 1000 (the release
# suite measures the RSS).
CYCLES, WARM_UP = (100, 20) if SANITIZER else (1000, 200)


def test_rss_is_stable_over_1000_cycles():
    rng = np.random.default_rng(3)
    for k in range(WARM_UP):  # warm-up: caches, thread pools, allocator arenas
        cycle(k, rng)
    gc.collect()
    base = rss_bytes()
    for k in range(CYCLES):
        cycle(k, rng)
    gc.collect()
    grew = rss_bytes() - base
    print("RSS after %d cycles: %+.2f MiB" % (CYCLES, grew / 2**20))
    # every shared array was released by the library's last vv_volume_free
    assert len(volvis.volume._shared) == len(volvis.volume._shared_by_addr) <= 2
    # each cycle allocates about 0.2 MiB (volume, World, image, mesh); a leak of
    # any of them would add > 200 MiB. The sanitizer's quarantine holds up to
    # 256 MiB of freed memory by design.
    limit = (300 if SANITIZER else 8) * 2**20
    assert grew < limit, grew
