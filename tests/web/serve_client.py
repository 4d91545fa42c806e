"""What the protocol-level tests of `volvis serve` share (test_serve_protocol.py,
test_serve_confine.py, test_serve_url.py): the server started on a free port
and stopped, a client connected as the page connects (python3-websockets),
the binary messages parsed, replies awaited, and the small NRRD volumes
they write. Importing it exits 77 (skipped, never passed) when
python3-websockets is missing."""
import asyncio, json, os, shutil, struct, subprocess, sys, tempfile, time

SKIP = 77
try:
    import websockets
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(SKIP)


class Server:
    """`BIN serve --port 0 ARGS` (under `mpirun -n MPI` when mpi > 0); its stderr is
    kept (text()); base and token come from the URL it prints."""

    def __init__(self, bin_path, args, mpi=0):
        cmd = [bin_path, "serve", "--port", "0"] + args
        env = None
        if mpi:
            cmd = [shutil.which("mpirun"), "--allow-run-as-root", "--oversubscribe", "-n",
                   str(mpi)] + cmd
            # no X display for mpirun or the ranks: Open MPI's hwloc probes the X
            # servers :0 to :9 for GPUs otherwise (docs/parallel.md)
            env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
            env["HWLOC_COMPONENTS"] = "-gl"
        self.mpi = mpi
        self.log = tempfile.TemporaryFile(mode="w+")
        self.p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=self.log, text=True,
                                  env=env)
        line = self.p.stdout.readline().strip()
        if not line.startswith("http"):
            raise SystemExit(f"server did not start: {cmd}\n{self.text()}")
        self.base, self.token = line.split("/?token=")

    def text(self):
        """What the server wrote to stderr so far."""
        self.log.seek(0)
        return self.log.read()

    def connect(self, context=None):
        """A WebSocket client as the page's (WSS with an ssl @context)."""
        host = self.base.split("//", 1)[1]
        scheme = "wss" if context else "ws"
        return websockets.connect(f"{scheme}://{host}/ws", subprotocols=["volvis"],
                                  origin=self.base, ssl=context,
                                  extra_headers={"Cookie": "volvis_token=" + self.token},
                                  max_size=1 << 27)

    def stop(self):
        """Stops the server; fails on a sanitizer's report or (one process) a status
        other than SIGTERM's clean exit. Returns its stderr."""
        self.p.terminate()
        try:
            self.p.wait(30)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
        # Ctrl-C and SIGTERM end the server with status 0; mpirun, which signals every
        # rank itself, reports the signal
        log = self.text()
        for bad in ("Sanitizer", "runtime error:"):  # ASan, LSan, UBSan, TSan reports
            assert bad not in log, log[-4000:]
        assert self.mpi or self.p.returncode in (0, -15), (self.p.returncode, log[-2000:])
        return log


def parse(m):
    """A binary message: (kind, header, payload)."""
    n = struct.unpack("<I", m[4:8])[0]
    return m[:4].decode(), json.loads(m[8:8 + n]), m[8 + n:]


async def until(ws, pred, what, timeout):
    """Reads messages until pred(kind, header, payload) is true (a text message is
    ("TEXT", its JSON, None)); returns that message. Fails after @timeout seconds."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        m = await asyncio.wait_for(ws.recv(), timeout)
        r = ("TEXT", json.loads(m), None) if isinstance(m, str) else parse(m)
        if pred(*r):
            return r
    raise AssertionError(f"no {what} within {timeout} s")


def nrrd(path, dims, data, content=None):
    """A raw uint8 NRRD of @dims (x, y, z) voxels: @data, bytes in x-fastest order."""
    hdr = (f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {dims[0]} {dims[1]} {dims[2]}\n"
           f"spacings: 1 1 1\n" + (f"content: {content}\n" if content else "") +
           "encoding: raw\n\n")
    assert len(data) == dims[0] * dims[1] * dims[2]
    with open(path, "wb") as f:
        f.write(hdr.encode() + data)
