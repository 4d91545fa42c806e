#!/usr/bin/python3
"""MPI ranks never open an X display (docs/parallel.md, "No X display").

  mpi_display.py VOLVIS MPIEXEC MPI_COMPARE TESTUTIL_H OUTDIR

Open MPI's hwloc looks for GPUs on the X servers :0 to :9 (its "gl"
component), whatever DISPLAY says, in every process that discovers the
machine's topology itself; a server that dies during the probe (another
program's Xvfb) ends that process with "XIO: fatal IO error". This test
plays an X server on a free display :N of :0 to :9 (it takes the display's
lock file as an X server does, listens on the display's abstract and file
sockets, and records which process connects and closes at once), sets
DISPLAY=:N, and marks the processes it starts with a tag in their
environment, so a connection from anyone else's program is not counted:

- the launch line of the tests (VT_MPI_ENV of tests/testutil.h, read from
  that file, before mpiexec): `volvis render` on 2 ranks succeeds and
  nothing it starts (mpiexec, orted, the ranks) connects;
- mpiexec without that environment (DISPLAY=:N, no HWLOC_COMPONENTS): the
  ranks still succeed and no rank connects (nothing in a rank touches X:
  under mpiexec a rank adopts the launcher's topology, and the library
  uses no display); the launcher's own probe is reported, as the control
  that shows the fake server would see hwloc's (docs/parallel.md: the
  launcher's environment must turn it off);
- a singleton (vv_mpi_compare run without mpiexec, which calls
  vv_parallel_init: MPI_Init discovers the topology in the process and in
  the orted it starts) with DISPLAY=:N and no HWLOC_COMPONENTS: it
  succeeds and nothing connects (the library sets HWLOC_COMPONENTS=-gl
  before MPI_Init unless the user has set it).

Exits 0 when all pass, 1 on a failure, 77 (skipped) when no display of :0
to :9 is free.
"""
import os
import re
import secrets
import shlex
import socket
import struct
import subprocess
import sys
import threading

VOLVIS, MPIEXEC, COMPARE, TESTUTIL, OUT = sys.argv[1:6]
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared",
                    "data", "volumes", "neghip.slc")
TIMEOUT = 300
failures = []


def check(cond, what, detail=""):
    print(("ok   " if cond else "FAIL ") + what + ("" if cond or not detail else "\n" + detail),
          flush=True)
    if not cond:
        failures.append(what)


class FakeX:
    """An X server that accepts on :N and closes at once (XOpenDisplay then
    fails, with no error that ends the client), recording each client whose
    environment holds the tag."""

    def __init__(self, tag):
        self.tag = tag.encode()
        self.clients = []  # (pid, exe, cmdline) of tagged clients
        self.lock = threading.Lock()
        self.socks, self.paths = [], []
        for n in range(10):
            lock = f"/tmp/.X{n}-lock"
            try:
                fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o444)
            except FileExistsError:
                if not self.stale(lock):
                    continue
                try:  # a lock left by a server that is gone, as X servers do
                    os.unlink(lock)
                    fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o444)
                except OSError:
                    continue
            except OSError:
                continue
            os.write(fd, b"%10d\n" % os.getpid())
            os.close(fd)
            a = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                a.bind(f"\0/tmp/.X11-unix/X{n}")
            except OSError:
                a.close()
                os.unlink(lock)
                continue
            if os.path.exists(f"/tmp/.X11-unix/X{n}"):  # a server without its lock
                a.close()
                os.unlink(lock)
                continue
            self.n = n
            self.paths.append(lock)
            a.listen(64)
            self.socks.append(a)
            try:  # the file socket too (clients try the abstract one first)
                os.makedirs("/tmp/.X11-unix", exist_ok=True)
                f = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                f.bind(f"/tmp/.X11-unix/X{n}")
                f.listen(64)
                self.socks.append(f)
                self.paths.append(f"/tmp/.X11-unix/X{n}")
            except OSError:
                pass
            for s in self.socks:
                threading.Thread(target=self.serve, args=(s,), daemon=True).start()
            return
        print("skipped: no X display of :0 to :9 is free for the fake server")
        sys.exit(77)

    @staticmethod
    def stale(lock):
        """The lock file names a process that no longer runs."""
        try:
            with open(lock) as fh:
                pid = int(fh.read().strip())
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        except (OSError, ValueError):
            return False
        return False

    def serve(self, s):
        while True:
            try:
                c, _ = s.accept()
            except OSError:
                return
            # the client waits in XOpenDisplay until we close: /proc is still its
            pid = struct.unpack("3i", c.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, 12))[0]
            try:
                with open(f"/proc/{pid}/environ", "rb") as fh:
                    ours = self.tag in fh.read()
                exe = os.readlink(f"/proc/{pid}/exe")
                with open(f"/proc/{pid}/cmdline", "rb") as fh:
                    cmd = fh.read().replace(b"\0", b" ").decode(errors="replace").strip()
            except OSError:
                ours, exe, cmd = True, "?", "?"  # gone: count it, it may be ours
            if ours:  # recorded before the client can go on and its run end
                with self.lock:
                    self.clients.append((pid, exe, cmd))
            c.close()

    def take(self):
        with self.lock:
            got, self.clients = self.clients, []
        return got

    def close(self):
        for s in self.socks:
            s.close()
        for p in self.paths:
            try:
                os.unlink(p)
            except OSError:
                pass


def mpi_env_prefix():
    """VT_MPI_ENV of tests/testutil.h: the environment every mpiexec of the
    tests runs in, as a list of words."""
    with open(TESTUTIL) as fh:
        m = re.search(r'#define\s+VT_MPI_ENV\s+"([^"]*)"', fh.read())
    if not m:
        raise SystemExit(f"no VT_MPI_ENV in {TESTUTIL}")
    return shlex.split(m.group(1))


def run(cmd, env):
    try:
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return 124, f"timed out after {TIMEOUT} s"
    return p.returncode, p.stdout + p.stderr


def main():
    os.makedirs(OUT, exist_ok=True)
    if not os.path.exists(DATA):
        print(f"skipped: {DATA} is missing")
        sys.exit(77)
    tag = "VV_MPI_DISPLAY_TAG=" + secrets.token_hex(8)
    x = FakeX(tag)
    try:
        base = {k: v for k, v in os.environ.items() if k != "HWLOC_COMPONENTS"}
        base["DISPLAY"] = f":{x.n}"
        # under ASan, Open MPI's own allocations are not ours to report
        # (test_parallel_mpi_cli checks the ranks' leaks)
        base["ASAN_OPTIONS"] = "detect_leaks=0:abort_on_error=1"
        base[tag.split("=")[0]] = tag.split("=")[1]
        print(f"fake X server on :{x.n}", flush=True)
        mpi = [MPIEXEC, "--allow-run-as-root", "--oversubscribe", "-np", "2"]
        render = [VOLVIS, "render", DATA, "--size", "48x40", "-o"]
        rank_exes = {os.path.realpath(VOLVIS), os.path.realpath(COMPARE)}

        # 1. the tests' launch line: nothing connects
        png = os.path.join(OUT, "display_tests_env.png")
        rc, out = run(mpi_env_prefix() + mpi + render + [png], base)
        got = x.take()
        check(rc == 0 and "on 2 ranks)" in out,
              f"the tests' mpiexec line renders on 2 ranks (exit {rc})", out[-2000:])
        check(not got, f"under VT_MPI_ENV nothing connects to :{x.n} (connected: {got})")

        # 2. mpiexec in the fake display's environment: no rank connects
        png = os.path.join(OUT, "display_bare.png")
        rc, out = run(mpi + render + [png], base)
        got = x.take()
        check(rc == 0 and "on 2 ranks)" in out,
              f"mpiexec with DISPLAY=:{x.n} renders on 2 ranks (exit {rc})", out[-2000:])
        ranks = [c for c in got if os.path.realpath(c[1]) in rank_exes or c[1] == "?"]
        check(not ranks, f"with DISPLAY=:{x.n} no rank connects (ranks that did: {ranks})")
        launcher = sorted({os.path.basename(c[1]) for c in got if c not in ranks})
        print(f"note: the launcher probed :{x.n} ({', '.join(launcher)}): the control that "
              "the fake server sees hwloc's probe" if launcher else
              f"note: the launcher did not probe :{x.n} (hwloc without its gl component?): "
              "cases 1 and 3 cannot tell hwloc's probe here", flush=True)

        # 3. a singleton: the library turns the probe off before MPI_Init
        rc, out = run([COMPARE], base)
        got = x.take()
        check(rc == 0, f"vv_mpi_compare as a singleton (exit {rc})", out[-2000:])
        check(not got, f"a singleton and its orted do not connect to :{x.n} (connected: {got})")
    finally:
        x.close()
    if failures:
        print(f"{len(failures)} failed")
        sys.exit(1)
    print("all passed")


main()
