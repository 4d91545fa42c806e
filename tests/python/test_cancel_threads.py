"""Ctrl+C cancels a long render through the library's progress callback;
renders from two Python threads run at once (the GIL is released)."""
import os
import signal
import threading
import time

import numpy as np
import pytest

import volvis
from conftest import SANITIZER


def long_world(ct_head):
    w = volvis.World.for_volume(ct_head, size=(1024, 1024))
    w.objects[0].step = 0.05  # many samples a ray: seconds of work on two cores
    return w


def test_keyboard_interrupt_cancels_within_half_a_second(ct_head):
    w = long_world(ct_head)
    seen = []
    sent = {}

    def interrupt():
        sent["t"] = time.perf_counter()
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.5, interrupt)
    t0 = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        volvis.render(w, renderer="raytrace", quality=2, progress=seen.append)
    latency = time.perf_counter() - sent["t"]
    print("render cancelled %.3f s after SIGINT (%.2f s into the render)"
          % (latency, sent["t"] - t0))
    assert latency < (1.5 if SANITIZER else 0.5), latency
    assert seen and seen[-1] < 1.0
    # the interpreter goes on, and the library renders again
    img = volvis.render(ct_head, size=(32, 32))
    assert img.shape == (32, 32, 4) and img.max() > 0


def test_progress_callable_can_cancel(ct_head):
    w = long_world(ct_head)
    calls = []

    def stop(f):
        calls.append(f)
        return f > 0.05
    with pytest.raises(volvis.CancelledError) as e:
        volvis.render(w, renderer="raycast", progress=stop)
    assert "cancel" in str(e.value).lower()
    assert calls


def test_tqdm_bar(ct_head):
    tqdm = pytest.importorskip("tqdm")
    import io
    buf = io.StringIO()
    bar = tqdm.tqdm(total=100, file=buf)
    volvis.render(ct_head, size=(256, 256), progress=bar)
    bar.close()
    assert bar.n == pytest.approx(100)


def test_two_threads_render_at_once(ct_head):
    """Each thread's render reports progress strictly between 0 and 1 while
    the other's does too: they overlap in time, so neither holds the GIL."""
    worlds = [volvis.World.for_volume(ct_head, size=(384, 384), azimuth=a) for a in (0, 90)]
    for w in worlds:
        w.objects[0].step = 0.1
    stamps = {0: [], 1: []}
    images = {}

    def run(n):
        def note(f):
            if 0 < f < 1:
                stamps[n].append(time.perf_counter())
        images[n] = volvis.render(worlds[n], threads=1, progress=note)

    threads = [threading.Thread(target=run, args=(n,)) for n in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert stamps[0] and stamps[1]
    a0, a1 = min(stamps[0]), max(stamps[0])
    b0, b1 = min(stamps[1]), max(stamps[1])
    assert a0 < b1 and b0 < a1, "the two renders did not overlap"
    for n in (0, 1):
        np.testing.assert_array_equal(images[n], volvis.render(worlds[n], threads=1))
