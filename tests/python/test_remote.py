"""World.open of a remote OME-Zarr store (docs/formats.md, "Remote data"): a store
`volvis convert` wrote (NGFF 0.5, sharded), served over HTTP on a free loopback port by
Python's own http.server -- which ignores Range and answers every read with the whole
object, so each shard index and inner chunk is cut here from a 200 -- opens through the
library's one door and draws the local store's image bit for bit, in memory and out of
core; a store that is not there raises naming the URL."""
import functools
import http.server
import subprocess
import threading

import numpy as np
import pytest

import volvis
from conftest import DATA, cli

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
