#!/usr/bin/env python3
"""OME-Zarr stores served by nginx over HTTP and HTTPS, read by URL.

  http_nginx_cli.py VOLVIS OUTDIR

Run with the .venv of scripts/install-deps.sh test (vv_pypi_test). zarr-python 3
writes a sharded + zstd NGFF 0.5 pyramid (3 levels) and its Zarr v2 twin; nginx
(Debian's nginx-light, one process, a configuration of its own in OUTDIR, a free
loopback port; not the system's service) serves OUTDIR over HTTP and over HTTPS
with a test CA made here with openssl. Checked:

- `volvis info URL` is `volvis info DIR` but for the name, v3 and v2, HTTP and HTTPS
  (HTTP/2 there, as nginx's log says);
- `volvis render URL` (MIP, composite; whole and out of core; on 2 MPI ranks when
  mpirun is there) and `volvis slice URL` are the local PNGs byte for byte; `volvis convert URL --level 2 out.nrrd` the local one's voxels;
- nginx's access log: the shards are read by range (206 with a Range header), and
  reading level 2 fetches no shard of levels 0 and 1;
- level 0 (216 chunks) by URL with at least 16 requests in flight at once
  (VOLVIS_HTTP_STATS=1's count), the same voxels as the local read, v3 and v2;
- `--cache-dir`: a second read is answered 304 (If-None-Match) and read from the cache,
  the same voxels; VOLVIS_HTTP_CACHE_MAX bounds it;
- HTTPS without the test CA: one line naming the URL (the certificate refused);
  a store that is not there: one line naming the URL.
"""
import os
import re
import shutil
import signal
import subprocess
import time
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
try:
    import numpy as np  # noqa: F401
    import zarr  # noqa: F401
except ImportError as e:  # pragma: no cover
    print(f"skipped: {e} (bash scripts/install-deps.sh test makes .venv)")
    sys.exit(77)
from cli_common import read_nrrd  # noqa: E402
from http_common import make_ca, nginx_path, setup, start_nginx, stop_server  # noqa: E402

if not nginx_path():
    print("skipped: nginx is missing (apt-get install nginx-light)")
    sys.exit(77)

VOLVIS, OUT, check, www, v3, v2 = setup()
ca, crt, key = make_ca(OUT)
log = os.path.join(OUT, "access.log")
nginx, port, sport = start_nginx(OUT, www, "http_nginx_cli", tls=(crt, key), access_log=log)
env = {k: v for k, v in os.environ.items() if not k.lower().endswith("_proxy")}
env["SSL_CERT_FILE"] = env["CURL_CA_BUNDLE"] = ca


def volvis(*args, e=None):
    return subprocess.run([VOLVIS, *args], capture_output=True, text=True, env=e or env,
                          timeout=300)


def log_lines():
    with open(log) as f:
        return f.read().splitlines()


def one_line(p, needle, what):
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    check(p.returncode != 0 and len(lines) == 1 and needle in lines[0],
          f"{what}: one line naming {needle} ({lines[:3]}, exit {p.returncode})")


try:
    http = f"http://127.0.0.1:{port}"
    https = f"https://127.0.0.1:{sport}"
    for name, local in (("v3", v3), ("v2", v2)):
        base = os.path.basename(local)
        pl = volvis("info", local)
        for scheme, root in (("http", http), ("https", https)):
            url = f"{root}/{base}"
            pu = volvis("info", url)
            check(pl.returncode == 0 and pu.returncode == 0 and
                  pu.stdout.replace(url, local) == pl.stdout and "levels" in pl.stdout.lower(),
                  f"info {name} over {scheme} equals the local info but for the name "
                  f"({pu.stderr.strip()})")
        url = f"{http}/{base}"
        for mode, extra in (("mip", ["--mode", "mip", "--tf", "50:1000"]),
                            ("composite", ["--mode", "composite", "--tf", "50:1000"]),
                            ("mip-ooc", ["--mode", "mip", "--tf", "50:1000", "--memory-limit",
                                         "64M", "--level", "0"])):
            a, b = (os.path.join(OUT, f"{name}_{mode}_{w}.png") for w in ("local", "url"))
            p1 = volvis("render", local, "-o", a, "--size", "96x96", *extra)
            p2 = volvis("render", url, "-o", b, "--size", "96x96", *extra)
            same = p1.returncode == 0 and p2.returncode == 0 and \
                open(a, "rb").read() == open(b, "rb").read()
            check(same, f"render {name} {mode} by URL is the local PNG byte for byte "
                  f"({p1.stderr.strip()} {p2.stderr.strip()})")
    # the same over HTTPS (HTTP/2 where nginx offers it)
    a, b = (os.path.join(OUT, f"tls_{w}.png") for w in ("local", "url"))
    p1 = volvis("render", v3, "-o", a, "--size", "96x96", "--mode", "mip")
    p2 = volvis("render", f"{https}/pyr3.ome.zarr", "-o", b, "--size", "96x96", "--mode", "mip")
    check(p1.returncode == 0 and p2.returncode == 0 and
          open(a, "rb").read() == open(b, "rb").read(),
          f"render over HTTPS with the test CA is the local PNG ({p2.stderr.strip()})")
    protos = {ln.split()[-1] for ln in log_lines()}
    check("HTTP/2.0" in protos and "HTTP/1.1" in protos,
          f"HTTP/2 over TLS, HTTP/1.1 in the clear ({sorted(protos)})")
    # slice, and MPI ranks (each opens the URL through the same door)
    a, b = (os.path.join(OUT, f"slice_{w}.png") for w in ("local", "url"))
    p1 = volvis("slice", v3, "-o", a)
    p2 = volvis("slice", f"{http}/pyr3.ome.zarr", "-o", b)
    check(p1.returncode == 0 and p2.returncode == 0 and
          open(a, "rb").read() == open(b, "rb").read(),
          f"slice by URL is the local PNG ({p2.stderr.strip()})")
    mpirun = shutil.which("mpirun")
    if mpirun:
        a, b = (os.path.join(OUT, f"mpi_{w}.png") for w in ("local", "url"))
        how = ["--size", "96x96", "--mode", "mip"]
        # Open MPI's own allocations are not freed at exit: under ASan the
        # ranks skip the leak check, as tests/parallel/test_mpi.c's MPIRUN
        run = [mpirun, "--oversubscribe", "-n", "2",
               "-x", "ASAN_OPTIONS=detect_leaks=0:abort_on_error=1"] + (
                   ["--allow-run-as-root"] if os.geteuid() == 0 else [])
        p1 = subprocess.run(run + [VOLVIS, "render", v3, "-o", a, *how], capture_output=True,
                            text=True, env=env, timeout=120)
        p2 = subprocess.run(run + [VOLVIS, "render", f"{http}/pyr3.ome.zarr", "-o", b, *how],
                            capture_output=True, text=True, env=env, timeout=120)
        check(p1.returncode == 0 and p2.returncode == 0 and "2 ranks" in p2.stdout and
              open(a, "rb").read() == open(b, "rb").read(),
              f"render by URL on 2 MPI ranks is the local PNG ({p2.stderr.strip()[-300:]})")
    # shards by range; level 2 alone reads no shard of levels 0 and 1
    open(log, "w").close()
    os.kill(nginx.pid, signal.SIGUSR1)  # reopen the log
    import time
    time.sleep(0.3)
    for lvl in ("2",):
        o1, o2 = (os.path.join(OUT, f"l{lvl}_{w}.nrrd") for w in ("local", "url"))
        p1 = volvis("convert", v3, o1, "--level", lvl, "--quiet")
        p2 = volvis("convert", f"{http}/pyr3.ome.zarr", o2, "--level", lvl, "--quiet")
        ok = p1.returncode == 0 and p2.returncode == 0
        if ok:
            x1, s1, g1 = read_nrrd(o1)
            x2, s2, g2 = read_nrrd(o2)
            ok = np.array_equal(x1, x2) and s1 == s2 and g1 == g2
        check(ok, f"convert --level {lvl} by URL equals the local read ({p2.stderr.strip()})")
    lines = log_lines()
    shard = re.compile(r'^(\d+) GET "/pyr3\.ome\.zarr/(\d)/c/[0-9/]+" "([^"]*)"')
    reads = [shard.match(ln) for ln in lines]
    reads = [m for m in reads if m]
    check(len(reads) > 0 and all(m.group(1) == "206" and m.group(3).startswith("bytes=")
                                 for m in reads),
          f"every shard read is a range answered 206 ({len(reads)} reads; "
          f"{[m.group(0) for m in reads if m.group(1) != '206'][:3]})")
    finer = [m.group(0) for m in reads if m.group(2) in ("0", "1")]
    check(not finer and any(m.group(2) == "2" for m in reads),
          f"reading level 2 fetches no shard of levels 0 and 1 ({finer[:3]})")
    # a level of many chunks read in batches: level 0 (96^3, 216 chunks of 16^3; v3 in
    # 27 shards, v2 one object each) with at least 16 requests in flight at once (the
    # transport's count, VOLVIS_HTTP_STATS=1), the local read's voxels bit for bit
    for name, local in (("v3", v3), ("v2", v2)):
        o1, o2 = (os.path.join(OUT, f"l0_{name}_{w}.nrrd") for w in ("local", "url"))
        p1 = volvis("convert", local, o1, "--level", "0", "--quiet", "--no-compress")
        p2 = volvis("convert", f"{http}/{os.path.basename(local)}", o2, "--level", "0",
                    "--quiet", "--no-compress", e=dict(env, VOLVIS_HTTP_STATS="1"))
        m = re.search(r"(\d+) requests, at most (\d+) in flight", p2.stderr)
        most = int(m.group(2)) if m else 0
        ok = p1.returncode == 0 and p2.returncode == 0 and most >= 16
        if ok:
            x1, s1, g1 = read_nrrd(o1)
            x2, s2, g2 = read_nrrd(o2)
            ok = np.array_equal(x1, x2) and s1 == s2 and g1 == g2
        check(ok, f"level 0 of {name} by URL: at least 16 requests in flight ({most}) and "
              f"the local voxels ({p2.stderr.strip()})")
    # opening a pyramid by URL fetches each metadata document once (the root's is
    # not read again for every level; the levels' are asked together): an
    # out-of-core render of each store, every zarr.json, .zattrs and .zarray in the
    # access log at most once
    for name, local in (("v3", v3), ("v2", v2)):
        open(log, "w").close()
        p = volvis("render", f"{http}/{os.path.basename(local)}", "-o",
                   os.path.join(OUT, f"meta_{name}.png"), "--memory-limit", "64M", "--size",
                   "64x64", "-q")
        time.sleep(0.2)
        meta = re.compile(r'^\d+ (?:GET|HEAD) "([^"]*(?:zarr\.json|\.zattrs|\.zarray|\.zgroup))"')
        docs = [m.group(1) for m in map(meta.match, log_lines()) if m]
        twice = sorted({d for d in docs if docs.count(d) > 1})
        check(p.returncode == 0 and docs and not twice,
              f"render {name} by URL fetches each metadata document once ({len(docs)} "
              f"fetches; twice: {twice[:3]}; {p.stderr.strip()})")
    # --cache-dir: a second read sends If-None-Match and takes the bytes from the
    # cache on 304; a small bound is kept
    cache = os.path.join(OUT, "cache")
    o1, o2, o3 = (os.path.join(OUT, f"cache{i}.nrrd") for i in (1, 2, 3))
    p1 = volvis("convert", f"{http}/pyr3.ome.zarr", o1, "--level", "2", "--quiet",
                "--cache-dir", cache)
    open(log, "w").close()
    os.kill(nginx.pid, signal.SIGUSR1)
    time.sleep(0.3)
    p2 = volvis("--cache-dir", cache, "convert", f"{http}/pyr3.ome.zarr", o2, "--level", "2",
                "--quiet")
    reads = [m for m in (shard.match(ln) for ln in log_lines()) if m]
    ok = p1.returncode == 0 and p2.returncode == 0 and \
        np.array_equal(read_nrrd(o1)[0], read_nrrd(o2)[0]) and \
        np.array_equal(read_nrrd(o2)[0], read_nrrd(os.path.join(OUT, "l2_local.nrrd"))[0])
    check(ok and reads and all(m.group(1) == "304" for m in reads),
          f"--cache-dir: the second read's shard requests are all answered 304 from the cache "
          f"({len(reads)} reads, {sorted(set(m.group(1) for m in reads))}; "
          f"{p2.stderr.strip()})")
    small = os.path.join(OUT, "cache_small")
    e = dict(env, VOLVIS_HTTP_CACHE_MAX="40K")
    p3 = subprocess.run([VOLVIS, "--cache-dir", small, "convert", f"{http}/pyr3.ome.zarr", o3,
                         "--level", "0", "--quiet"], capture_output=True, text=True, env=e,
                        timeout=300)
    held = sum(os.path.getsize(os.path.join(small, f)) for f in os.listdir(small))
    check(p3.returncode == 0 and 0 < held <= 40 * 1024,
          f"--cache-dir within VOLVIS_HTTP_CACHE_MAX=40K: {held} bytes held ({p3.stderr.strip()})")
    # refusals: one line naming the URL
    noca = {k: v for k, v in env.items() if k not in ("SSL_CERT_FILE", "CURL_CA_BUNDLE")}
    noca["SSL_CERT_FILE"] = noca["CURL_CA_BUNDLE"] = "/etc/ssl/certs/ca-certificates.crt"
    one_line(volvis("info", f"{https}/pyr3.ome.zarr", e=noca), f"{https}/pyr3.ome.zarr",
             "HTTPS with a certificate no CA of the system's signed")
    one_line(volvis("info", f"{http}/nothing.ome.zarr"), f"{http}/nothing.ome.zarr",
             "a store that is not there")
finally:
    stop_server(nginx)
check.finish("http_nginx_cli")
