"""Helpers of the remote-store tests (http_nginx_cli.py, http_hostile_cli.py, s3_moto_cli.py):
a free loopback port, a test CA and server certificate made with openssl; the stores they
serve come from cli_common.write_stores."""
import os
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
