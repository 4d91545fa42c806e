#!/usr/bin/env python3
"""`volvis serve` showing remote data: an OME-Zarr store served over HTTP by a
local server (Python's http.server in this process, loopback only).

Checks, on the real binary:
  - the URL given on the command line opens in a new session: its state has
    the local store's dims, and the page's PNG equals, byte for byte, the PNG
    of the same store opened by path from the root;
  - a URL under --allow-url opens by the client's "open" message;
  - the top listing shows the URL and the prefix;
  - every request the HTTP server got lies under the prefix.

Skipped (exit 77) while this build cannot open URLs: `volvis info URL` of the
store fails (the library's HTTP byte source is not there yet); the test runs
by itself once it is.

usage: test_serve_url.py VOLVIS_BINARY
"""
import asyncio, functools, http.server, json, os, shutil, subprocess, sys, tempfile
import threading

import serve_client  # exits 77 without python3-websockets

BIN = sys.argv[1]
WAIT = 40
SKIP = serve_client.SKIP


def nrrd(path, n):
    serve_client.nrrd(path, (n, n, n),
                      bytes(((i + 2 * j + 3 * k) % 251) for k in range(n) for j in range(n)
                            for i in range(n)))


class Quiet(http.server.SimpleHTTPRequestHandler):
    paths = []

    def log_message(self, fmt, *args):
        Quiet.paths.append(self.path)


def main():
    tmp = tempfile.mkdtemp(prefix="volvis-serve-url-")
    www, root = os.path.join(tmp, "www"), os.path.join(tmp, "root")
    os.makedirs(os.path.join(www, "data"))
    os.makedirs(root)
    src = os.path.join(tmp, "cube.nrrd")
    nrrd(src, 32)
    store = os.path.join(root, "img.ome.zarr")
    subprocess.run([BIN, "convert", src, store, "-q"], check=True)
    shutil.copytree(store, os.path.join(www, "data", "img.ome.zarr"))
    shutil.copytree(store, os.path.join(www, "data", "img2.ome.zarr"))
    httpd = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(Quiet, directory=www))
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    port = httpd.server_address[1]
    prefix = f"http://127.0.0.1:{port}/data/"
    url = prefix + "img.ome.zarr"
    info = subprocess.run([BIN, "info", url], capture_output=True, text=True, timeout=60)
    if info.returncode != 0:
        httpd.shutdown()
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"skipped: this build cannot open URLs yet (volvis info {url}: "
              f"{info.stderr.strip()})")
        return SKIP
    local = subprocess.run([BIN, "info", store], capture_output=True, text=True, check=True)
    print("volvis info by URL and by path:\n" + info.stdout + "\n" + local.stdout)

    srv = serve_client.Server(BIN, ["--root", root, "--allow-url", prefix, url])

    async def recv_until(ws, pred, what):
        """The payload (a text message's JSON) of the first message pred() holds for;
        an error reply fails."""
        def ok(k, h, p):
            assert not (k == "TEXT" and h["type"] == "error"), h
            return pred(k, h, p)
        k, h, p = await serve_client.until(ws, ok, what, WAIT)
        return h if k == "TEXT" else p

    async def png(ws):
        await recv_until(ws, lambda k, h, p: k == "FRME" and h["sharp"], "sharp frame")
        await ws.send(json.dumps({"type": "png"}))
        return await recv_until(ws, lambda k, h, p: k == "PNG_", "PNG")

    async def run():
        conn = srv.connect
        async with conn() as ws:
            await ws.send(json.dumps({"type": "hello", "width": 96, "height": 80}))
            st = await recv_until(ws, lambda k, h, p: k == "TEXT" and h["type"] == "state" and
                                  h["name"] == "img.ome.zarr", "the URL's state")
            assert st["dims"] == [32, 32, 32], st
            by_url = await png(ws)
            await ws.send(json.dumps({"type": "list", "path": ""}))
            r = await recv_until(ws, lambda k, h, p: k == "TEXT" and h["type"] == "listing",
                                 "listing")
            assert {"url": url, "prefix": False} in r["remote"], r
            assert {"url": prefix, "prefix": True} in r["remote"], r
            await ws.send(json.dumps({"type": "open", "url": prefix + "img2.ome.zarr"}))
            st = await recv_until(ws, lambda k, h, p: k == "TEXT" and h["type"] == "state" and
                                  h["name"] == "img2.ome.zarr", "the prefix URL's state")
            assert st["dims"] == [32, 32, 32], st
        async with conn() as ws:
            await ws.send(json.dumps({"type": "hello", "width": 96, "height": 80}))
            await recv_until(ws, lambda k, h, p: k == "TEXT" and h["type"] == "state" and
                             h["name"] == "img.ome.zarr", "the URL's state")
            await ws.send(json.dumps({"type": "open", "path": "img.ome.zarr"}))
            await recv_until(ws, lambda k, h, p: k == "TEXT" and h["type"] == "state" and
                             h["name"] == "img.ome.zarr" and h["renderer"], "the path's state")
            by_path = await png(ws)
        assert by_url == by_path, "the PNG by URL differs from the PNG by path"

    try:
        asyncio.run(run())
    finally:
        srv.stop()
        httpd.shutdown()
    bad = [q for q in Quiet.paths if not q.startswith("/data/")]
    assert not bad, bad
    print(f"ok: {len(Quiet.paths)} HTTP requests, all under /data/")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
