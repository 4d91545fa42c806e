"""Helpers of the remote-store tests (http_nginx_cli.py, http_hostile_cli.py, s3_moto_cli.py)
and of bench/remote_read_pairs.py: a free loopback port, a test CA and server certificate
made with openssl, Debian's nginx serving a folder; the stores the tests serve come from
cli_common.write_stores."""
import os
import re
import shutil
import socket
import subprocess
import sys


def free_port():
    """A TCP port of 127.0.0.1 free now (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port(port, proc, timeout=15.0):
    """Waits until 127.0.0.1:PORT accepts (or PROC ended); 1 when it does."""
    import time
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if proc is not None and proc.poll() is not None:
            return 0
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return 1
        except OSError:
            time.sleep(0.05)
    return 0


def nginx_path():
    """Debian's nginx (nginx-light): its path, or None when it is not installed."""
    return shutil.which("nginx") or ("/usr/sbin/nginx" if os.path.exists("/usr/sbin/nginx")
                                     else None)


def start_nginx(out, root, who, tls=None, access_log=None):
    """nginx serving the files under ROOT on free loopback ports: one process, not a
    daemon, a configuration of its own written in OUT (nginx.conf; its pid, error log,
    stderr and temporary folders there too; not the system's service), 1024
    connections, 100000 requests a connection. HTTP on one port; with TLS = (server
    certificate, its key), HTTPS (HTTP/2 offered) on a second. ACCESS_LOG: a file where
    each request is logged as "$status $request_method "$uri" "$http_range"
    $body_bytes_sent $server_protocol" (None: no access log). Returns (process, port,
    TLS port or None) once every port accepts; stop it with stop_server(process). When it
    does not start, exits with one line "WHO: nginx did not start (...)"."""
    nginx = nginx_path()
    if not nginx:
        sys.exit(f"{who}: nginx is missing (apt-get install nginx-light)")
    port = free_port()
    sport = free_port() if tls else None
    log = (f"log_format ranges '$status $request_method \"$uri\" \"$http_range\" "
           f"$body_bytes_sent $server_protocol';\n  access_log {access_log} ranges;"
           if access_log else "access_log off;")
    ssl = (f"""
  server {{
    listen 127.0.0.1:{sport} ssl http2;
    ssl_certificate {tls[0]};
    ssl_certificate_key {tls[1]};
    root {root};
  }}""" if tls else "")
    conf = os.path.join(out, "nginx.conf")
    with open(conf, "w") as f:
        f.write(f"""daemon off;
master_process off;
worker_processes 1;
pid {out}/nginx.pid;
error_log {out}/error.log;
events {{ worker_connections 1024; }}
http {{
  {log}
  client_body_temp_path {out}/tmp_body;
  proxy_temp_path {out}/tmp_proxy;
  fastcgi_temp_path {out}/tmp_fcgi;
  uwsgi_temp_path {out}/tmp_uwsgi;
  scgi_temp_path {out}/tmp_scgi;
  default_type application/octet-stream;
  keepalive_requests 100000;
  server {{ listen 127.0.0.1:{port}; root {root}; }}{ssl}
}}
""")
    stderr = os.path.join(out, "nginx.stderr")
    with open(stderr, "wb") as err:
        p = subprocess.Popen([nginx, "-c", conf, "-p", out, "-e", f"{out}/error.log"],
                             stdout=subprocess.DEVNULL, stderr=err)
    if all(wait_port(q, p) for q in (port, sport) if q):
        return p, port, sport
    stop_server(p)
    with open(stderr, errors="replace") as f:
        why = " ".join(f.read().split())
    sys.exit(f"{who}: nginx did not start ({why or 'no port accepted within 15 s'})")


def access_bytes(log):
    """(bytes of every response body, bytes of the distinct chunk ranges) in the nginx
    access LOG of start_nginx (its "ranges" format): zarr.json and shard-index suffix
    ranges are not chunks."""
    total, distinct = 0, {}
    pat = re.compile(r'^(\d+) GET "([^"]*)" "([^"]*)" (\d+)')
    with open(log) as f:
        for line in f:
            m = pat.match(line)
            if not m:
                continue
            status, uri, rng, n = int(m.group(1)), m.group(2), m.group(3), int(m.group(4))
            total += n
            if status in (200, 206) and not uri.endswith("zarr.json") and \
                    not rng.startswith("bytes=-"):
                distinct[(uri, rng)] = n
    return total, sum(distinct.values())


def stop_server(p):
    """Stops a server's process P (an nginx of start_nginx, a moto server): SIGTERM,
    SIGKILL when it has not ended 10 s later; waits for it."""
    p.terminate()
    try:
        p.wait(timeout=10)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()


def make_ca(d):
    """A test CA and a server certificate for 127.0.0.1 and localhost it signs, in D:
    (ca.pem, server.pem, server.key)."""
    if not shutil.which("openssl"):
        print("skipped: openssl is missing")
        sys.exit(77)
    ca_key, ca, key, csr, crt = (os.path.join(d, n) for n in
                                 ("ca.key", "ca.pem", "server.key", "server.csr", "server.pem"))
    ext = os.path.join(d, "ext.cnf")
    with open(ext, "w") as f:
        f.write("subjectAltName=IP:127.0.0.1,DNS:localhost\nbasicConstraints=CA:FALSE\n")

    def ossl(*a):
        subprocess.run(["openssl", *a], check=True, capture_output=True)
    ossl("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", ca_key, "-out", ca,
         "-days", "2", "-subj", "/CN=volvis test CA")
    ossl("req", "-newkey", "rsa:2048", "-nodes", "-keyout", key, "-out", csr,
         "-subj", "/CN=127.0.0.1")
    ossl("x509", "-req", "-in", csr, "-CA", ca, "-CAkey", ca_key, "-CAcreateserial",
         "-out", crt, "-days", "2", "-extfile", ext)
    return ca, crt, key


def setup(n=96):
    """A remote-store test's start: (volvis, OUT made empty, its Checks, OUT/www holding
    the stores of cli_common.write_stores at N^3, the v3 store's path, the v2 store's)
    from the command line VOLVIS OUT."""
    from cli_common import Checks, write_stores
    volvis, out = sys.argv[1], os.path.abspath(sys.argv[2])
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    www = os.path.join(out, "www")
    os.makedirs(www)
    v3, v2 = write_stores(www, n=n)
    return volvis, out, Checks(), www, v3, v2


def drip_server(root, piece=1024, pause=0.003, delay=0.0, gate=None):
    """A slow HTTP server of the files under ROOT on a free loopback port, in threads of
    this process: byte ranges (206 with Content-Range; a suffix range too), HEAD, 404
    without a body, and every body written PIECE bytes at a time PAUSE seconds apart;
    each request answered DELAY seconds after it came, and while GATE (a
    threading.Event, or None) is not set, not at all (a server that does not answer,
    until the test sets it; handler.held counts the requests waiting there). It
    counts what it answered, as an access log would: (server, handler class) with
    handler.requests (requests answered), handler.sent (body bytes written) and
    handler.wait_idle(). Stop it with server.shutdown(); server.server_close()."""
    import http.server
    import pathlib
    import threading
    import time
    base = pathlib.Path(root).resolve()

    class Drip(http.server.BaseHTTPRequestHandler):
        lock = threading.Lock()
        requests = 0
        sent = 0
        active = 0  # requests being answered now
        held = 0  # requests that waited for the gate

        def log_message(self, *a):
            pass

        def _add(self, requests=0, sent=0, active=0):
            with Drip.lock:
                Drip.requests += requests
                Drip.sent += sent
                Drip.active += active

        def _answer(self, body):
            if gate is not None and not gate.is_set():
                with Drip.lock:
                    Drip.held += 1
                gate.wait()
            if delay:
                time.sleep(delay)
            self._add(requests=1, active=1)
            try:
                self._send(body)
            finally:
                self._add(active=-1)

        def _send(self, body):
            path = (base / self.path.split("?")[0].lstrip("/")).resolve()
            if base not in path.parents or not path.is_file():
                self.send_response(404)
                self.send_header("Content-Length", "0")
                self.end_headers()
                return
            data = path.read_bytes()
            rng = self.headers.get("Range")
            if rng and rng.startswith("bytes="):
                a, b = rng[6:].split("-")
                lo, hi = ((max(0, len(data) - int(b)), len(data) - 1) if a == "" else
                          (int(a), min(len(data) - 1, int(b)) if b else len(data) - 1))
                self.send_response(206)
                self.send_header("Content-Range", "bytes %d-%d/%d" % (lo, hi, len(data)))
                data = data[lo:hi + 1]
            else:
                self.send_response(200)
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            for i in range(0, len(data) if body else 0, piece):
                if i:
                    time.sleep(pause)
                self.wfile.write(data[i:i + piece])
                self.wfile.flush()
                self._add(sent=len(data[i:i + piece]))

        def do_GET(self):
            self._answer(True)

        def do_HEAD(self):
            self._answer(False)

        @classmethod
        def wait_idle(cls, timeout=30):
            """Waits until no request is being answered (its counts final)."""
            end = time.monotonic() + timeout
            while cls.active and time.monotonic() < end:
                time.sleep(0.01)

    srv = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Drip)
    srv.daemon_threads = True
    threading.Thread(target=srv.serve_forever, daemon=True).start()
    return srv, Drip
