#!/usr/bin/env python3
"""A hostile HTTP server in front of a real OME-Zarr store: every misbehaviour is one
line naming the URL (or a correct retry), never a hang, never memory beyond the budget.

  http_hostile_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test). zarr-python 3
writes a sharded + zstd NGFF 0.5 pyramid; a small http.server (a thread of this
script, a free loopback port) serves it under /MODE/..., the store's metadata always
as it is and its shards (keys with /c/) as MODE says:

  ok         byte ranges as nginx answers them
  drip       the right headers, then one byte a second (a low-speed timeout: the
             test sets VOLVIS_HTTP_LOW_SPEED_TIME=2, VOLVIS_HTTP_RETRIES=1)
  badrange   206 with a Content-Range one byte off the range asked
  trunc      a Content-Length of the range, half the bytes, the connection closed
  hugelen    Content-Length: 10^15 and a few bytes
  redirfile  302 to file:///etc/passwd
  redirftp   302 to ftp://127.0.0.1/...
  redirhost  302 to the same object at localhost (another host name): followed
  loop       302 to itself
  flaky      500 twice for each object, then right (retried: the render is the local one)
  gzipbomb   Content-Encoding: gzip, a body of 1 GiB of zeros gzip-compressed (1 MB)

`volvis convert URL --level 2` (and `render`) is run for each: the right voxels for
ok, flaky and redirhost; for the rest one line naming the URL and the reason, no
output file, a bounded time, and a peak RSS of every volvis run under 400 MB.
"""
import http.server
import os
import socketserver
import subprocess
import sys
import threading
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
try:
    import numpy as np
    import zarr  # noqa: F401
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)
from cli_common import read_nrrd  # noqa: E402
from http_common import free_port, setup  # noqa: E402

VOLVIS, OUT, check, www, v3, _ = setup(n=64)


def gzip_bomb(n=1 << 30):
    """N zero bytes gzip-compressed, made 1 MiB at a time (never N bytes held here)."""
    z = zlib.compressobj(9, zlib.DEFLATED, 31)
    block = b"\0" * (1 << 20)
    return b"".join(z.compress(block) for _ in range(n >> 20)) + z.flush()


BOMB = gzip_bomb()
port = free_port()
counts = {}
lock = threading.Lock()


class Handler(http.server.BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(self, *a):
        pass

    def send(self, code, headers, body=b""):
        self.send_response(code)
        for k, v in headers:
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD" and body:
            self.wfile.write(body)

    def do_HEAD(self):
        self.do_GET()

    def do_GET(self):
        parts = self.path.split("/", 2)
        mode, rel = (parts[1], parts[2]) if len(parts) == 3 else ("", "")
        f = os.path.join(www, rel)
        if not rel or ".." in rel or not os.path.isfile(f):
            return self.send(404, [("Content-Length", "0")])
        data = open(f, "rb").read()
        size = len(data)
        rng = self.headers.get("Range")
        a, b = 0, size - 1
        if rng and rng.startswith("bytes="):
            x, y = rng[6:].split("-")
            if x == "":
                a, b = max(0, size - int(y)), size - 1
            else:
                a, b = int(x), (int(y) if y else size - 1)
        chunk = "/c/" in rel
        here = f"http://127.0.0.1:{port}{self.path}"
        if chunk and mode == "redirfile":
            return self.send(302, [("Location", "file:///etc/passwd"), ("Content-Length", "0")])
        if chunk and mode == "redirftp":
            return self.send(302, [("Location", f"ftp://127.0.0.1/{rel}"),
                                   ("Content-Length", "0")])
        if chunk and mode == "redirhost":
            return self.send(302, [("Location", f"http://localhost:{port}/ok/{rel}"),
                                   ("Content-Length", "0")])
        if chunk and mode == "loop":
            return self.send(302, [("Location", here), ("Content-Length", "0")])
        if chunk and mode == "flaky":
            with lock:
                k = (self.path, rng)
                counts[k] = counts.get(k, 0) + 1
                n = counts[k]
            if n <= 2:
                return self.send(500, [("Content-Length", "0")])
        if chunk and mode == "gzipbomb":
            return self.send(206 if rng else 200,
                             [("Content-Encoding", "gzip"), ("Content-Length", str(len(BOMB)))] +
                             ([("Content-Range", f"bytes {a}-{b}/{size}")] if rng else []),
                             BOMB)
        if chunk and mode == "hugelen":
            self.send(206 if rng else 200, [("Content-Length", str(10 ** 15))] +
                      ([("Content-Range", f"bytes {a}-{b}/{size}")] if rng else []),
                      data[a:b + 1])
            self.close_connection = True
            return
        body = data[a:b + 1]
        hdrs = [("Content-Length", str(len(body)))]
        code = 206 if rng else 200
        if rng:
            if chunk and mode == "badrange":
                hdrs.append(("Content-Range", f"bytes {a + 1}-{b + 1}/{size + 1}"))
            else:
                hdrs.append(("Content-Range", f"bytes {a}-{b}/{size}"))
        if chunk and mode == "trunc":
            self.send(code, hdrs, body[:len(body) // 2])
            self.close_connection = True
            return
        if chunk and mode == "drip":
            self.send(code, hdrs)
            try:
                for i in range(len(body)):
                    self.wfile.write(body[i:i + 1])
                    self.wfile.flush()
                    time.sleep(1.0)
            except OSError:
                pass
            self.close_connection = True
            return
        self.send(code, hdrs, body)


class Server(socketserver.ThreadingMixIn, http.server.HTTPServer):
    daemon_threads = True
    allow_reuse_address = True

    def handle_error(self, request, client_address):
        pass  # a client that hung up on a hostile answer: expected


srv = Server(("127.0.0.1", port), Handler)
threading.Thread(target=srv.serve_forever, daemon=True).start()
env = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
env.update(VOLVIS_HTTP_LOW_SPEED_TIME="2", VOLVIS_HTTP_RETRIES="3")


peak_kb = [0]


def volvis(*args, extra=None):
    """volvis ARGS (its output, seconds); its own peak RSS (wait4) kept in peak_kb."""
    e = dict(env, **(extra or {}))
    t = time.monotonic()
    with open(os.path.join(OUT, "stdout"), "w+") as fo, \
            open(os.path.join(OUT, "stderr"), "w+") as fe:
        p = subprocess.Popen([VOLVIS, *args], stdout=fo, stderr=fe, env=e)
        deadline = time.monotonic() + 120
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > deadline:
                p.kill()
            time.sleep(0.02)
        p.returncode = os.waitstatus_to_exitcode(status)
        peak_kb[0] = max(peak_kb[0], ru.ru_maxrss)
        fo.seek(0)
        fe.seek(0)
        p.stdout, p.stderr = fo.read(), fe.read()
    return p, time.monotonic() - t


local = os.path.join(OUT, "local.nrrd")
p0, _ = volvis("convert", v3, local, "--level", "2", "--quiet")
want = read_nrrd(local)[0] if p0.returncode == 0 else None
check(want is not None, f"the local store reads ({p0.stderr.strip()})")
try:
    for mode in ("ok", "flaky", "redirhost"):
        url = f"http://127.0.0.1:{port}/{mode}/pyr3.ome.zarr"
        out = os.path.join(OUT, f"{mode}.nrrd")
        p, dt = volvis("convert", url, out, "--level", "2", "--quiet")
        ok = p.returncode == 0 and want is not None and np.array_equal(read_nrrd(out)[0], want)
        check(ok, f"{mode}: the voxels are the local store's ({p.stderr.strip()}, {dt:.1f} s)")
    a, b = os.path.join(OUT, "local.png"), os.path.join(OUT, "flaky.png")
    counts.clear()
    p1, _ = volvis("render", v3, "-o", a, "--size", "64x64", "--mode", "mip")
    p2, _ = volvis("render", f"http://127.0.0.1:{port}/flaky/pyr3.ome.zarr", "-o", b,
                   "--size", "64x64", "--mode", "mip")
    check(p1.returncode == 0 and p2.returncode == 0 and
          open(a, "rb").read() == open(b, "rb").read(),
          f"flaky (500 twice, then right): retried and rendered as the local ({p2.stderr.strip()})")
    for mode, needle, limit, extra in (
            ("drip", "too slow", 40, {"VOLVIS_HTTP_RETRIES": "1"}),
            ("badrange", "Content-Range", 30, None),
            ("trunc", "after 4 tries", 40, None),
            ("hugelen", "Content-Length", 30, None),
            ("redirfile", "file:///etc/passwd", 30, None),
            ("redirftp", "ftp://", 30, None),
            ("loop", "redirects", 30, None),
            ("gzipbomb", "Content-Encoding", 30, None)):
        url = f"http://127.0.0.1:{port}/{mode}/pyr3.ome.zarr"
        out = os.path.join(OUT, f"{mode}.nrrd")
        p, dt = volvis("convert", url, out, "--level", "2", "--quiet", extra=extra)
        lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
        check(p.returncode != 0 and len(lines) == 1 and url in lines[0] and
              needle.lower() in lines[0].lower() and not os.path.exists(out) and dt < limit,
              f"{mode}: one line naming the URL and '{needle}' in {dt:.1f} s < {limit} s "
              f"({lines[:2]}, exit {p.returncode})")
    peak = peak_kb[0] / 1024
    check(peak < 400, f"the peak RSS of every volvis run: {peak:.0f} MB < 400 MB")
finally:
    srv.shutdown()
check.finish("http_hostile_cli")
