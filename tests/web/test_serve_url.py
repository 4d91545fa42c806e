#!/usr/bin/env python3
"""`volvis serve` showing remote data: an OME-Zarr store served over HTTP by a
local server (Python's http.server in this process, loopback only).

Checks, on the real binary:
  - the URL given on the command line opens in a new session: its state has
    the local store's dims, and the page's PNG equals, byte for byte, the PNG
    of the same store opened by path from the root;
  - a URL under --allow-url opens by the client's "open" message;
  - the top listing shows the URL and the prefix;
  - every request the HTTP server got lies under the prefix;
  - the page in headless Chromium (selenium), a server of its own showing a
    96^3 store served slowly, out of core: once it is open, while a frame
    waits for its remote chunks, the status line shows "N chunks, X kB
    pending" (the server's `remote` messages), and it is gone once the sharp
    frame is drawn.

Skipped (exit 77) while this build cannot open URLs: `volvis info URL` of the
store fails (the library's HTTP byte source is not there yet); the test runs
by itself once it is.

usage: test_serve_url.py VOLVIS_BINARY
"""
import asyncio, functools, http.server, json, os, re, shutil, subprocess, sys, tempfile
import threading, time

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
    drip = 0.0  # > 0: bodies written 512 bytes at a time, this many seconds apart

    def log_message(self, fmt, *args):
        Quiet.paths.append(self.path)

    def copyfile(self, source, outputfile):
        if not Quiet.drip:
            return super().copyfile(source, outputfile)
        while True:
            b = source.read(512)
            if not b:
                return
            outputfile.write(b)
            outputfile.flush()
            time.sleep(Quiet.drip)


PENDING = r"^\d+ chunks?(, [0-9.]+ MB|, [0-9]+ kB)? pending$"


def browser_pending(root, store, www, prefix):
    """The page shows the remote reads pending while a slow server feeds the first
    frame, and drops the line once the sharp frame is drawn. Returns None, or why it
    cannot run (selenium or Chromium missing)."""
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError as e:
        return f"{e} (apt install python3-selenium)"
    chromium = os.environ.get("CHROMIUM", "/usr/bin/chromium")
    driver = os.environ.get("CHROMEDRIVER", "/usr/bin/chromedriver")
    for exe in (chromium, driver):
        if not os.access(exe, os.X_OK):
            return f"{exe} is missing (apt install chromium chromium-driver)"
    if os.environ.get("VV_TEST_OUT"):  # where the page's screenshots go
        os.makedirs(os.environ["VV_TEST_OUT"], exist_ok=True)
    # 96^3: two levels, level 0 in 8 chunks, read out of core (--memory-limit) by the
    # frames after the open read level 1
    src = os.path.join(root, "..", "slow.nrrd")
    nrrd(src, 96)
    subprocess.run([BIN, "convert", src, os.path.join(www, "data", "slow.ome.zarr"), "-q"],
                   check=True)
    url = prefix + "slow.ome.zarr"
    Quiet.drip = 0.02
    p = subprocess.Popen([BIN, "serve", "--port", "0", "--root", root, "--memory-limit", "64M",
                          url], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    opts = webdriver.ChromeOptions()
    opts.binary_location = chromium
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
              "--window-size=1000,700"):
        opts.add_argument(a)
    d = None
    try:
        line = p.stdout.readline().strip()
        assert line.startswith("http"), p.stderr.read()
        d = webdriver.Chrome(service=Service(driver), options=opts)
        d.get(line)
        seen, deadline = [], time.time() + WAIT
        while time.time() < deadline:
            hidden, text, sharp, opened = d.execute_script(
                "const e = document.getElementById('status-remote');"
                "const v = window.volvis, f = v && v.lastFrame;"
                "return [e.hidden, e.textContent, !!(f && f.sharp), !!(v && v.state && "
                "v.state.dims)];")
            if not hidden and opened:  # the store is open: a frame waits for its chunks
                if not seen and os.environ.get("VV_TEST_OUT"):
                    d.save_screenshot(os.path.join(os.environ["VV_TEST_OUT"],
                                                   "serve_url_pending.png"))
                seen.append(text)
            if hidden and sharp and opened:  # the remote reads of the sharp frame done
                break
            time.sleep(0.02)
        shown = d.execute_script("return window.volvis.remoteShown")
        print(f"status line while a frame waited: {sorted(set(seen))[:4]}; "
              f"the client showed {len(shown)} remote messages")
        # the line as the page showed it (every remote message it drew, in order):
        # while the store opened or a frame waited (polling every 20 ms catches the
        # second only on a quiet machine, so it is not required)
        assert any(re.match(PENDING, t) for t in seen + list(shown)), (seen, shown)
        assert hidden and sharp, ("the pending line stays, or no sharp frame", text, shown)
        assert d.execute_script("return window.volvis.remote.pending") == 0
        if os.environ.get("VV_TEST_OUT"):
            d.save_screenshot(os.path.join(os.environ["VV_TEST_OUT"], "serve_url_done.png"))
    finally:
        Quiet.drip = 0.0
        if d:
            d.quit()
        p.terminate()
        p.wait(20)
    return None


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

    why = None
    try:
        asyncio.run(run())
        srv.stop()
        why = browser_pending(root, store, www, prefix)
    finally:
        srv.stop()
        httpd.shutdown()
    bad = [q for q in Quiet.paths if not q.startswith("/data/")]
    assert not bad, bad
    print(f"ok: {len(Quiet.paths)} HTTP requests, all under /data/")
    shutil.rmtree(tmp, ignore_errors=True)
    if why:
        print(f"skipped: the page's pending line: {why}")
        return SKIP
    return 0


if __name__ == "__main__":
    sys.exit(main())
