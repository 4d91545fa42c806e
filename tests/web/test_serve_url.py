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
    frame is drawn, also when the page read nothing while the reads ended and
    the server's queue for it was over half full (the last `remote` message,
    pending 0, is never dropped: browser_pending).

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
LISTS = 40  # listings the page asks for at once (the server queues at most 64 replies)
SKIP = serve_client.SKIP


def nrrd(path, n):
    serve_client.nrrd(path, (n, n, n),
                      bytes(((i + 2 * j + 3 * k) % 251) for k in range(n) for j in range(n)
                            for i in range(n)))


class Quiet(http.server.SimpleHTTPRequestHandler):
    paths = []
    drip = 0.0  # > 0: bodies written 512 bytes at a time, this many seconds apart
    hold = None  # a path prefix: requests under it wait here, unanswered, until go is set
    go = threading.Event()
    lock = threading.Lock()
    active = 0  # requests being answered now
    held = 0  # requests waiting under hold now
    last = 0.0  # time.monotonic() when the last answer ended

    def log_message(self, fmt, *args):
        Quiet.paths.append(self.path)

    def do_GET(self):
        with Quiet.lock:
            Quiet.active += 1
        try:
            if Quiet.hold and self.path.startswith(Quiet.hold) and not Quiet.go.is_set():
                with Quiet.lock:
                    Quiet.held += 1
                Quiet.go.wait()
                with Quiet.lock:
                    Quiet.held -= 1
            super().do_GET()
        finally:
            with Quiet.lock:
                Quiet.active -= 1
                Quiet.last = time.monotonic()

    @classmethod
    def idle_for(cls, seconds):
        """1 when no request is being answered and none ended SECONDS ago or later."""
        with cls.lock:
            return cls.active == 0 and time.monotonic() - cls.last >= seconds

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
    many = os.path.join(root, "many")  # 4000 names of 200 characters: a listing of ~1 MB
    os.makedirs(many, exist_ok=True)
    for i in range(4000):
        open(os.path.join(many, f"{i:04d}_" + "n" * 200), "w").close()
    shutil.copytree(os.path.join(www, "data", "slow.ome.zarr"),
                    os.path.join(www, "data", "b", "slow.ome.zarr"))
    Quiet.drip, Quiet.go = 0.02, threading.Event()
    p = subprocess.Popen([BIN, "serve", "--port", "0", "--root", root, "--memory-limit", "64M",
                          "--allow-url", prefix, url], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
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
        while time.time() < deadline and not seen:
            hidden, text, opened = d.execute_script(
                "const e = document.getElementById('status-remote'), v = window.volvis;"
                "return [e.hidden, e.textContent, !!(v && v.state && v.state.dims)];")
            if not hidden and opened:  # the store is open: a frame waits for its chunks
                if os.environ.get("VV_TEST_OUT"):
                    d.save_screenshot(os.path.join(os.environ["VV_TEST_OUT"],
                                                   "serve_url_pending.png"))
                seen.append(text)
            time.sleep(0.02)
        # the store loaded whole: the line gone, a sharp frame, every preset's thumbnail
        # (they render from level 0; their replies would share the queue below)
        def settled():
            return d.execute_script(
                "const e = document.getElementById('status-remote');"
                "const v = window.volvis, f = v && v.lastFrame;"
                "const p = document.getElementById('presets');"
                "return e.hidden && !!(f && f.sharp) && p.children.length > 0 &&"
                " !p.querySelector('.thumb-empty');")
        deadline = time.time() + WAIT
        while time.time() < deadline and not settled():
            time.sleep(0.05)
        assert settled(), "the first store never settled (sharp frame, thumbnails, no reads)"
        # The page falls behind while reads end. A copy of the store under the same
        # name (so that the page asks for no new thumbnails) is opened by the page's
        # "open" message; the HTTP server holds the reads of its level 0 unanswered, so
        # they stay pending. The page asks for LISTS listings of a folder of many long
        # names (about 1 MB each) and then reads nothing while an alert is open (its
        # main thread paused, the socket backs up): most of the replies wait in the
        # server's queue for this client, over half of it (SRV_QUEUE_MAX 64). Then the
        # server answers everything, fast, and once it has been idle for 2 s (every
        # read landed: pending 0), the page reads again. The last `remote` went out
        # while the queue was over half full: the page must still end at it (before the
        # latest-state slot, such a message was dropped, and the line kept "N chunks
        # pending" for good).
        Quiet.hold = "/data/b/slow.ome.zarr/0/c/"
        d.execute_script("window.volvis.send({type: 'open', url: arguments[0]})",
                         prefix + "b/slow.ome.zarr")
        # a read of level 0 held, and the page shows it pending (the server sent a
        # `remote` with pending > 0): only then does the page fall behind. (Waiting for
        # the line matters on a loaded machine: the server answers the listings below on
        # its service thread, and while it does, it sends no `remote`; had it sent none
        # before, the reads could all end unseen, and the page would rightly show none.)
        # (as many pending as are held at least: not a line left from the metadata's reads)
        deadline, text, shows = time.time() + WAIT, "", -1
        while time.time() < deadline:
            hidden, text, shows = d.execute_script(
                "const e = document.getElementById('status-remote'), v = window.volvis;"
                "return [e.hidden, e.textContent, v.remote ? v.remote.pending : -1];")
            held = Quiet.held
            if held and shows >= held and not hidden and re.match(PENDING, text):
                break
            time.sleep(0.05)
        held = Quiet.held
        print(f"the copy opened; {held} reads of its level 0 held, the page shows {text!r}")
        assert held > 0, "no read of level 0 held: the page cannot fall behind a pending read"
        assert re.match(PENDING, text), ("the page never showed the held reads pending", text)
        # (the file list is hidden meanwhile: laying out 4000 long names for each of the
        # LISTS listings takes the page about a second each, which is not what is tested)
        d.execute_script(
            "document.getElementById('files').style.display = 'none';"
            "for (let i = 0; i < arguments[0]; i++) window.volvis.send({type: 'list', "
            "path: 'many'});"
            "window.volvis.send({type: 'list', path: ''});"  # the last reply: the top
            "setTimeout(() => alert('the page reads nothing while this is open'), 0);", LISTS)
        from selenium.webdriver.support import expected_conditions as EC
        from selenium.webdriver.support.ui import WebDriverWait
        WebDriverWait(d, 20).until(EC.alert_is_present())
        time.sleep(2)  # the server takes the requests and queues the replies (see docstring)
        Quiet.drip = 0.0
        Quiet.go.set()
        t0 = time.time()
        while not Quiet.idle_for(2.0) and time.time() - t0 < WAIT:
            time.sleep(0.1)
        d.switch_to.alert.accept()
        print(f"the page paused with {held} reads held; the HTTP server idle after "
              f"{time.time() - t0:.1f} s")
        # the page has read every reply (the top's listing, the last, is shown), and then
        # its line must end at the final state: hidden, pending 0, the frame sharp
        deadline, top, hidden, text, sharp, pending = time.time() + WAIT, False, 0, "", 0, -1
        while time.time() < deadline:
            top, hidden, text, sharp, pending = d.execute_script(
                "const e = document.getElementById('status-remote');"
                "const v = window.volvis, f = v && v.lastFrame;"
                "const top = [...document.querySelectorAll('#files li')]"
                ".some((li) => li.textContent.startsWith('many/'));"
                "return [top, e.hidden, e.textContent, !!(f && f.sharp),"
                " v.remote ? v.remote.pending : -1];")
            if top and hidden and sharp and pending == 0:
                break
            time.sleep(0.05)
        shown = d.execute_script("return window.volvis.remoteShown")
        closed = d.execute_script("return window.volvis.closed")
        print(f"status line while a frame waited: {seen[:1]}; the client showed "
              f"{len(shown)} remote messages, the last {shown[-1:]!r}")
        assert closed is None, ("the server closed the page's socket", closed)
        # the line as the page showed it (every remote message it drew, in order):
        # while the store opened or a frame waited (polling every 20 ms catches the
        # second only on a quiet machine, so it is not required)
        assert any(re.match(PENDING, t) for t in seen + list(shown)), (seen, shown)
        assert top, ("the page never read the replies it asked for", hidden, text, pending,
                     shown[-3:])
        assert hidden and pending == 0, ("the pending line stays (stale)", text, pending,
                                         shown[-3:])
        assert sharp, "no sharp frame"
        if os.environ.get("VV_TEST_OUT"):
            d.execute_script("document.getElementById('files').style.display = '';")
            d.save_screenshot(os.path.join(os.environ["VV_TEST_OUT"], "serve_url_done.png"))
    finally:
        Quiet.drip, Quiet.hold = 0.0, None
        Quiet.go.set()
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
