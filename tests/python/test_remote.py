"""World.open of a remote OME-Zarr store (docs/formats.md, "Remote data"): a store
`volvis convert` wrote (NGFF 0.5, sharded), served over HTTP on a free loopback port by
Python's own http.server -- which ignores Range and answers every read with the whole
object, so each shard index and inner chunk is cut here from a 200 -- opens through the
library's one door and draws the local store's image bit for bit, in memory and out of
core; a store that is not there raises naming the URL; while a slow server drips a
level, volvis.remote_stats shows reads and bytes pending, none after, and counts exactly
the bytes and requests the server answered."""
import functools
import http.server
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import volvis
from conftest import DATA, ROOT, cli

sys.path.insert(0, str(ROOT / "tests" / "io"))
from http_common import drip_server  # noqa: E402

CT = DATA / "volumes" / "ct_head.nrrd"


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    root = tmp_path_factory.mktemp("www")
    subprocess.run([cli(), "convert", str(CT), str(root / "ct.ome.zarr"), "-q", "--shard", "128"],
                   check=True, capture_output=True)
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(root))
    handler.log_message = lambda *a: None
    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    yield root / "ct.ome.zarr", f"http://127.0.0.1:{srv.server_address[1]}/ct.ome.zarr"
    srv.shutdown()


def test_url_equals_local(served):
    local, url = served
    a = volvis.render(volvis.World.open(local, mode="mip", size=(64, 64)), alpha=False)
    b = volvis.render(volvis.World.open(url, mode="mip", size=(64, 64)), alpha=False)
    assert a.max() > 0
    np.testing.assert_array_equal(a, b)


def test_url_out_of_core(served):
    local, url = served
    kw = dict(mode="mip", size=(64, 64), tf=(-1000, 1500), memory="out_of_core",
              memory_limit="64M", lod=True)
    a = volvis.render(volvis.World.open(local, **kw), alpha=False, level=1)
    w = volvis.World.open(url, **kw)
    assert w.opened["out_of_core"]
    np.testing.assert_array_equal(a, volvis.render(w, alpha=False, level=1))
    volvis.memory_limit(1 << 30)


def test_missing_store_names_the_url(served):
    _, url = served
    bad = url.replace("ct.ome.zarr", "none.ome.zarr")
    with pytest.raises(volvis.Error) as e:
        volvis.World.open(bad)
    assert bad in str(e.value) and "\n" not in str(e.value)


def _idle(timeout=30):
    """The remote counts once nothing is pending (a loader of an earlier test may be
    finishing its reads)."""
    end = time.monotonic() + timeout
    while True:
        st = volvis.remote_stats()
        if (st["pending"] == 0 and st["in_flight"] == 0) or time.monotonic() > end:
            return st
        time.sleep(0.01)


def test_remote_stats_pending_then_done(served):
    """vv_remote_stats while a slow server drips a level: reads and bytes pending
    during the read, none after; the bytes received are exactly the body bytes the
    server wrote, the requests the ones it answered; no read failed."""
    local, _ = served
    srv, Drip = drip_server(local.parent)
    url = f"http://127.0.0.1:{srv.server_address[1]}/{local.name}"
    try:
        before = _idle()
        got = {}

        def read():
            try:
                p = volvis.Pyramid(url)
                got["box"] = p.read(1)
            except Exception as e:  # noqa: BLE001: shown by the assertion below
                got["error"] = e

        t = threading.Thread(target=read)
        t.start()
        seen = []
        while t.is_alive():
            seen.append(volvis.remote_stats())
            time.sleep(0.002)
        t.join()
        Drip.wait_idle()
        after = volvis.remote_stats()
    finally:
        srv.shutdown()
        srv.server_close()
    print("remote_stats while dripping: %d polls, at most %d reads and %d bytes pending, "
          "%d in flight; after: %d reads answered, %d requests, %d bytes (the server: %d "
          "requests, %d bytes)" % (
              len(seen), max(s["pending"] for s in seen), max(s["pending_bytes"] for s in seen),
              max(s["in_flight"] for s in seen), after["completed"] - before["completed"],
              after["requests"] - before["requests"],
              after["bytes_received"] - before["bytes_received"], Drip.requests, Drip.sent))
    assert "error" not in got, got
    assert got["box"].size > 0
    assert max(s["pending"] for s in seen) > 0, seen[:3]
    assert max(s["pending_bytes"] for s in seen) > 0
    assert max(s["in_flight"] for s in seen) > 0
    assert after["pending"] == 0 and after["pending_bytes"] == 0 and after["in_flight"] == 0
    assert after["failed"] == before["failed"]
    assert after["bytes_received"] - before["bytes_received"] == Drip.sent > 0
    assert after["requests"] - before["requests"] == Drip.requests
    reads = after["completed"] - before["completed"]
    assert 0 < reads <= Drip.requests
    # bytes pending never exceed what is still to come: at most all the server sent
    assert max(s["pending_bytes"] for s in seen) <= Drip.sent


def test_scene_names_a_url(served, tmp_path):
    """A scene whose volume "file" is a URL (a GUI session of a store opened by URL)
    loads it as it is, never as a path beside the scene, and draws what the same scene
    naming the store's path draws."""
    import json
    local, url = served
    view = {"width": 64, "height": 64, "eye": [0, -900, 0], "at": [0, 0, 0], "up": [0, 0, 1]}
    imgs = []
    for name, f in (("url", url), ("path", str(local))):
        p = tmp_path / f"{name}.json"
        p.write_text(json.dumps({"view": view, "objects": [{"file": f, "mode": "mip"}]}))
        imgs.append(volvis.render(volvis.load_scene(str(p)), alpha=False))
    assert imgs[1].max() > 0
    np.testing.assert_array_equal(imgs[0], imgs[1])
