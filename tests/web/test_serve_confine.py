#!/usr/bin/env python3
"""`volvis serve` confinement at the protocol level (python3-websockets, no
browser): what a browser may make the server read or fetch.

Checks, each on the real binary:
  - URLs (no request forgery): a test socket listens on a loopback port;
    --allow-url names a prefix on that port. Every open a client sends for a
    URL that is neither given nor under the prefix (another path, a prefix
    without its segment boundary, "..", percent-encoded "..", an encoded
    "/", user information, a query, another scheme, host or port, file://)
    is refused with one line to that client, the refusal is in the server's
    log, the connection stays open, and the socket never sees a connection.
    The top listing shows the given URL and the prefix. An allowed URL that
    the door cannot open (nothing listens on its port) answers one line.
  - Paths: "..", a link out (a file and a folder), a listing through a link
    out are refused; links out are not listed; a MetaImage header with its
    detached data beside it opens.
  - Scenes: a scene inside the root naming ../../outside, an absolute path
    outside, a link out or a URL not allowed is refused with one line naming
    the scene and the entry; a scene naming ../inside.nrrd opens.
  - A race: a thread swaps a name in the root between a regular file inside
    and a link to a file outside (and a folder between a real one and a link
    to an outside folder), with renameat2(RENAME_EXCHANGE), while the client
    opens it again and again: every open shows the inside file or fails;
    the outside file's size and the marker in its header never reach the
    client; a session saved into the swapped folder never lands outside.

usage: test_serve_confine.py VOLVIS_BINARY
Exits 77 (skipped) when python3-websockets is missing.
"""
import asyncio, ctypes, functools, json, os, socket, sys, tempfile, threading, time

import serve_client  # exits 77 without python3-websockets

BIN = sys.argv[1]
WAIT = 20  # seconds for any one reply, on a loaded 2-core machine
SECRET = "TOPSECRET-outside-the-root"
Server = functools.partial(serve_client.Server, BIN)


def nrrd(path, dims, value, content="inside"):
    serve_client.nrrd(path, dims, bytes([value]) * (dims[0] * dims[1] * dims[2]), content)


async def text_reply(ws, pred, what):
    """The next text message for which pred(message) holds (frames are skipped)."""
    deadline = time.time() + WAIT
    while time.time() < deadline:
        m = await asyncio.wait_for(ws.recv(), WAIT)
        if isinstance(m, str):
            j = json.loads(m)
            if pred(j):
                return j
    raise AssertionError(f"no {what} within {WAIT} s")


def one_line(msg):
    assert isinstance(msg, str) and msg and "\n" not in msg and len(msg) < 1100, msg
    return msg


class Trap:
    """A listening loopback socket that counts the connections it gets."""

    def __init__(self):
        self.s = socket.socket()
        self.s.bind(("127.0.0.1", 0))
        self.s.listen(16)
        self.s.settimeout(0.1)
        self.port = self.s.getsockname()[1]
        self.count = 0
        self.stop = False
        self.t = threading.Thread(target=self.run, daemon=True)
        self.t.start()

    def run(self):
        while not self.stop:
            try:
                c, _ = self.s.accept()
                self.count += 1
                c.close()
            except socket.timeout:
                pass

    def close(self):
        self.stop = True
        self.t.join()
        self.s.close()


def closed_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


libc = ctypes.CDLL(None, use_errno=True)
RENAME_EXCHANGE = 2


def exchange(a, b):
    if libc.renameat2(-100, a.encode(), -100, b.encode(), RENAME_EXCHANGE) != 0:
        e = ctypes.get_errno()
        raise OSError(e, os.strerror(e), a)


def main():
    tmp = tempfile.mkdtemp(prefix="volvis-serve-confine-")
    root = os.path.join(tmp, "root")
    outside = os.path.join(tmp, "outside")
    for d in (root, outside, os.path.join(outside, "dir"), os.path.join(root, "scenes"),
              os.path.join(root, "racedir")):
        os.makedirs(d)
    inside_dims, secret_dims = [5, 6, 7], [9, 10, 11]
    nrrd(os.path.join(root, "inside.nrrd"), inside_dims, 10)
    secret = os.path.join(outside, "secret.nrrd")
    nrrd(secret, secret_dims, 200, SECRET)
    nrrd(os.path.join(outside, "dir", "x.nrrd"), secret_dims, 200, SECRET)
    nrrd(os.path.join(root, "racedir", "x.nrrd"), inside_dims, 10)
    # a file of two (MetaImage: the header, its detached data beside it)
    with open(os.path.join(root, "pair.mhd"), "w") as f:
        f.write("ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementType = MET_UCHAR\n"
                "ElementDataFile = pair.raw\n")
    with open(os.path.join(root, "pair.raw"), "wb") as f:
        f.write(bytes(range(24)))
    os.symlink(secret, os.path.join(root, "link.nrrd"))
    os.symlink(os.path.join(outside, "dir"), os.path.join(root, "linkdir"))
    scenes = {
        "up.json": "../../outside/secret.nrrd",
        "abs.json": secret,
        "link.json": "../link.nrrd",
        "linkdir.json": "../linkdir/x.nrrd",
    }
    trap = Trap()
    scenes["url.json"] = f"http://127.0.0.1:{trap.port}/secret.ome.zarr"
    for name, file in list(scenes.items()) + [("good.json", "../inside.nrrd")]:
        with open(os.path.join(root, "scenes", name), "w") as f:
            json.dump({"objects": [{"type": "volume", "file": file}]}, f)
    # the race's pairs: race.nrrd <-> .race_alt (a link out), racedir <-> .racedir_alt
    nrrd(os.path.join(root, "race.nrrd"), inside_dims, 10)
    os.symlink(secret, os.path.join(root, ".race_alt"))
    os.symlink(os.path.join(outside, "dir"), os.path.join(root, ".racedir_alt"))

    dead = closed_port()
    prefix = f"http://127.0.0.1:{trap.port}/data/"
    given = f"http://127.0.0.1:{dead}/given.ome.zarr"
    srv = Server(["--root", root, "--allow-url", prefix, given,
                  os.path.join(root, "inside.nrrd")])
    failures = []
    seen = []  # every text message the client got

    def check(name, fn):
        t0 = time.time()
        try:
            asyncio.run(fn())
            print(f"ok   {name} ({time.time() - t0:.1f} s)")
        except Exception as e:  # noqa: BLE001 - report every check
            import traceback
            traceback.print_exc()
            failures.append(name)
            print(f"FAIL {name}: {e}")

    async def hello(ws):
        """Hello, then the state of the file every new session opens."""
        await ws.send(json.dumps({"type": "hello", "width": 64, "height": 48}))
        r = await text_reply(ws, lambda j: j["type"] == "state" and j["name"] == "inside.nrrd",
                             "the first file's state")
        assert r["dims"] == inside_dims, r

    async def refused(ws, msg, needle):
        await ws.send(json.dumps(msg))
        r = await text_reply(ws, lambda j: j["type"] == "error" or
                             (j["type"] == "state" and j["name"] != "inside.nrrd"), "reply")
        seen.append(r)
        assert r["type"] == "error", (msg, r)
        one_line(r["message"])
        assert needle in r["message"], (needle, r["message"])
        return r["message"]

    async def urls():
        bad = [
            f"http://127.0.0.1:{trap.port}/secret",
            f"http://127.0.0.1:{trap.port}/database/x.zarr",
            f"http://127.0.0.1:{trap.port}/data",  # the prefix "/data/" needs its "/"
            f"http://127.0.0.1:{trap.port}/data/../secret",
            f"http://127.0.0.1:{trap.port}/data/%2e%2E/secret",
            f"http://127.0.0.1:{trap.port}/data%2f..%2fsecret",
            f"http://127.0.0.1:{trap.port}/data/a//b",
            f"http://user:pw@127.0.0.1:{trap.port}/data/x.zarr",
            f"http://127.0.0.1:{trap.port}@127.0.0.1:{trap.port}/data/x",
            f"http://127.0.0.1:{trap.port}/data/x.zarr?redirect=1",
            f"https://127.0.0.1:{trap.port}/data/x.zarr",
            f"http://localhost:{trap.port}/data/x.zarr",
            f"http://[::ffff:127.0.0.1]:{trap.port}/data/x.zarr",
            f"http://2130706433:{trap.port}/data/x.zarr",
            f"http://127.0.0.1:{trap.port + 1 if trap.port < 65535 else 1}/data/x.zarr",
            f"http://127.0.0.1/data/x.zarr",
            f"file:///etc/passwd",
            f"gopher://127.0.0.1:{trap.port}/data/x",
            f"s3://data/x.zarr",
            f"http://127.0.0.1:{trap.port}/data/x\\..\\..\\secret",
        ]
        async with srv.connect() as ws:
            await hello(ws)
            lines = []
            for u in bad:
                lines.append(await refused(ws, {"type": "open", "url": u}, ""))
            # a URL as a path, a path and a URL together
            await refused(ws, {"type": "open", "path": f"http://127.0.0.1:{trap.port}/data/x"},
                          "")
            # the connection is still open: the listing answers, with the URLs
            await ws.send(json.dumps({"type": "list", "path": ""}))
            r = await text_reply(ws, lambda j: j["type"] == "listing", "listing")
            assert {"url": given, "prefix": False} in r["remote"], r
            assert {"url": prefix, "prefix": True} in r["remote"], r
            names = [e["name"] for e in r["entries"]]
            assert "inside.nrrd" in names and "scenes" in names, names
            assert "link.nrrd" not in names and "linkdir" not in names, names  # links out
            # an allowed URL that the door cannot open (nothing listens there): one line
            await ws.send(json.dumps({"type": "open", "url": given}))
            r = await text_reply(ws, lambda j: j["type"] in ("error", "state") and
                                 j.get("name") != "inside.nrrd", "the door's answer")
            assert r["type"] == "error", r
            one_line(r["message"])
        time.sleep(0.5)
        assert trap.count == 0, f"the trap socket got {trap.count} connections"
        log = srv.text()
        for u in bad[:3]:
            assert u in log, (u, log[-3000:])  # each refusal is logged

    async def paths():
        async with srv.connect() as ws:
            await hello(ws)
            await refused(ws, {"type": "open", "path": "../outside/secret.nrrd"}, "'..'")
            await refused(ws, {"type": "open", "path": "link.nrrd"}, "leaves the root")
            await refused(ws, {"type": "open", "path": "linkdir/x.nrrd"}, "leaves the root")
            await refused(ws, {"type": "list", "path": "linkdir"}, "leaves the root")
            await refused(ws, {"type": "save", "path": "linkdir/s.json"}, "leaves the root")
            await refused(ws, {"type": "open", "path": secret}, "absolute")
            # a header and its detached data, both inside: opens
            await ws.send(json.dumps({"type": "open", "path": "pair.mhd"}))
            r = await text_reply(ws, lambda j: j["type"] == "error" or
                                 j.get("name") == "pair.mhd", "the MetaImage's state")
            assert r["type"] == "state" and r["dims"] == [4, 3, 2], r

    async def scene_files():
        async with srv.connect() as ws:
            await hello(ws)
            for name, file in scenes.items():
                msg = await refused(ws, {"type": "open", "path": f"scenes/{name}"}, "scene")
                assert f"scenes/{name}" in msg and file in msg, msg
                assert "outside" in msg or "leaves" in msg or "not a URL" in msg, msg
            await ws.send(json.dumps({"type": "open", "path": "scenes/good.json"}))
            r = await text_reply(ws, lambda j: j["type"] in ("error", "state") and
                                 j.get("name") == "good.json" or j["type"] == "error", "state")
            assert r["type"] == "state" and r["dims"] == inside_dims, r
        time.sleep(0.3)
        assert trap.count == 0, f"the trap socket got {trap.count} connections"

    async def race():
        stop = threading.Event()
        swaps = [0]

        def swapper():
            a, b = os.path.join(root, "race.nrrd"), os.path.join(root, ".race_alt")
            c, d = os.path.join(root, "racedir"), os.path.join(root, ".racedir_alt")
            while not stop.is_set():
                exchange(a, b)
                exchange(c, d)
                swaps[0] += 1
                time.sleep(0.0002)

        t = threading.Thread(target=swapper, daemon=True)
        t.start()
        opened = refusals = by_reader = saved = 0
        try:
            async with srv.connect() as ws:
                await hello(ws)
                t_end = time.time() + 12
                k = 0
                while time.time() < t_end and k < 80:
                    path = "race.nrrd" if k % 2 == 0 else "racedir/x.nrrd"
                    k += 1
                    await ws.send(json.dumps({"type": "open", "path": path}))
                    r = await text_reply(
                        ws, lambda j: j["type"] == "error" or
                        (j["type"] == "state" and j.get("name") in ("race.nrrd", "x.nrrd")),
                        "an answer to the open")
                    seen.append(r)
                    if r["type"] == "state":
                        assert r["dims"] == inside_dims, f"the outside file was served: {r}"
                        opened += 1
                        # a session saved into the folder being swapped: never outside
                        await ws.send(json.dumps({"type": "save", "path": "racedir/saved.json"}))
                        r = await text_reply(ws, lambda j: j["type"] in ("saved", "error"),
                                             "an answer to the save")
                        saved += r["type"] == "saved"
                        # the next open must not be answered by this file's state again
                        await ws.send(json.dumps({"type": "open", "path": "inside.nrrd"}))
                        await text_reply(ws, lambda j: j["type"] == "error" or
                                         j.get("name") == "inside.nrrd", "inside")
                    else:
                        one_line(r["message"])
                        refusals += 1
                        # past the server's check, refused by the reader's layer beneath the root
                        by_reader += "Permission denied" in r["message"]
        finally:
            stop.set()
            t.join()
        assert not os.path.exists(os.path.join(outside, "dir", "saved.json")), \
            "a session was saved outside the root"
        print(f"     race: {saved} sessions saved, none outside the root")
        print(f"     race: {k} opens, {opened} showed the inside file, {refusals} refused "
              f"({by_reader} of them by a reader, after the server's check passed); "
              f"{swaps[0]} swaps")
        assert swaps[0] > 100 and opened + refusals == k, (swaps[0], opened, refusals, k)

    check("URLs: refused, logged, no connection; the listing's URLs", urls)
    check("paths: '..', links out, a listing through a link", paths)
    check("a scene's files", scene_files)
    check("a link swapped in while opening", race)
    log = srv.stop()
    for m in seen:
        assert SECRET not in json.dumps(m), m
    assert SECRET not in log, "the outside file's header reached the log"
    assert str(secret_dims) not in json.dumps(seen)
    trap.close()
    if failures:
        print("failed:", ", ".join(failures))
        print(log[-3000:])
        return 1
    import shutil
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
