"""Helpers of the remote-store tests (http_nginx_cli.py, http_hostile_cli.py, s3_moto_cli.py):
a free loopback port, a test CA and server certificate made with openssl, the stores
zarr-python 3 writes (a sharded + zstd NGFF 0.5 pyramid and its Zarr v2 twin)."""
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


def write_stores(out, n=96):
    """The stores under OUT: pyr3.ome.zarr (NGFF 0.5, Zarr v3, 3 levels, shards of 32^3
    holding inner chunks of 16^3, zstd) and pyr2.ome.zarr (the same levels as Zarr v2,
    OME-Zarr 0.4, zlib chunks of 16^3). Returns (v3 path, v2 path)."""
    import numpy as np
    import zarr
    from zarr.codecs import ZstdCodec
    rng = np.random.default_rng(7)
    zz, yy, xx = np.mgrid[0:n, 0:n, 0:n].astype(np.float32)
    ball = (1000 * np.exp(-((zz - 40) ** 2 + (yy - 50) ** 2 + (xx - 45) ** 2) / 600))
    ball = ball.astype(np.uint16) + rng.integers(0, 50, size=ball.shape, dtype=np.uint16)
    v3 = os.path.join(out, "pyr3.ome.zarr")
    g = zarr.open_group(v3, mode="w")
    lv, ds = ball, []
    for k in range(3):
        a = g.create_array(str(k), shape=lv.shape, dtype=lv.dtype, chunks=(16, 16, 16),
                           shards=(32, 32, 32), compressors=ZstdCodec(level=3))
        a[:] = lv
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [2.0 ** k] * 3},
            {"type": "translation", "translation": [(2.0 ** k - 1) / 2] * 3}]})
        s = [d // 2 * 2 for d in lv.shape]
        lv = np.rint(lv[:s[0], :s[1], :s[2]].astype(np.float64).reshape(
            s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(1, 3, 5))).astype(np.uint16)
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{"axes": [
        {"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"], "datasets": ds}]}
    v2 = os.path.join(out, "pyr2.ome.zarr")
    g2 = zarr.open_group(v2, mode="w", zarr_format=2)
    for k in range(3):
        a = g[str(k)][:]
        g2.create_array(str(k), shape=a.shape, dtype=a.dtype, chunks=(16, 16, 16))[:] = a
    g2.attrs["multiscales"] = [{"version": "0.4", **g.attrs["ome"]["multiscales"][0]}]
    return v3, v2
