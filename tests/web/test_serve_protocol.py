#!/usr/bin/env python3
"""`volvis serve` at the protocol level (docs/serve-protocol.md), without a
browser: a client that speaks the page's WebSocket protocol (python3-websockets).

Checks, each on the real binary:
  - a drag gives reduced frames, each showing a newer input; the stop gives the
    sharp frame showing the last input;
  - the PNG of the view equals `volvis render` of the saved session, byte for
    byte, in memory and out of core (an OME-Zarr pyramid under --memory-limit:
    its still frame arrives in progressive steps, the last one sharp; the CLI
    renders the session with the same --memory-limit and --lod 1);
  - `mpirun -n 2 volvis serve`: the PNG equals the one-process PNG within 2
    grey levels (the parallel module's compositing), and a drag still gives
    frames, after tabs that left while their frames were being drawn;
  - a session whose World names the gpu renderer (lavapipe here): the state
    says gpu, the PNG equals `volvis render` of the saved session (which keeps
    the renderer) byte for byte and is at least 40 dB from raycast's of the same
    view; under `mpirun -n 2` within 2 grey levels of one process, each rank
    with a Vulkan driver loaded (it drew its brick on its own device);
  - --shared: two clients see the same frames, and either steers the view;
  - one thumbnail a preset; a listing marks the Zarr store; a refused open
    or save answers an error and keeps the connection;
  - a 3-channel OME-Zarr pyramid (zarr-python) under --memory-limit: its 3 channels
    out of core, the PNG equals `volvis render` of the saved session with the same
    limit byte for byte, and hiding a channel changes the frame;
  - a 3-channel OME-TIFF (tifffile) shows its 3 channels, and hiding one or
    changing its colour changes the frame; a 4-D NIfTI of 3 time steps
    (nibabel) has the time slider's 3 steps, and a step changes the frame;
  - --cert/--key (a self-signed certificate made with openssl): HTTPS answers
    200 with the token and 403 without, and a frame arrives over WSS;
  - the frames' JPEG (encoded from the render's YUV 4:2:0 planes) at an odd
    size, 999 x 799, and the drag's reduced frames decode (PIL) to their
    header's size, and the still frame is within 48 dB of PIL's own JPEG of
    the view's PNG (RGB, 4:2:0, the same quality), as close to the PNG as it.

usage: test_serve_protocol.py VOLVIS_BINARY DATA_DIR [CHECK]
  CHECK: run only the checks whose title contains this text
Exits 77 (skipped) when python3-websockets or PIL is missing.
"""
import asyncio, functools, json, os, shutil, ssl, subprocess, sys, tempfile, time
import urllib.error, urllib.request

import serve_client  # exits 77 without python3-websockets

try:
    import numpy as np
    from PIL import Image
except ImportError as e:
    print(f"skipped: {e}")
    sys.exit(serve_client.SKIP)

BIN, DATA = sys.argv[1], sys.argv[2]
ONLY = sys.argv[3] if len(sys.argv) > 3 else ""
TIMEOUT = 180  # seconds for any one wait, on a loaded 2-core machine
Server = functools.partial(serve_client.Server, BIN)


async def until(ws, pred, what):
    """Reads messages until pred(kind, header, payload) is true; returns that message."""
    return await serve_client.until(ws, pred, what, TIMEOUT)


def sharp(k, h, p):
    return k == "FRME" and h["sharp"]


async def png_of(ws):
    await ws.send(json.dumps({"type": "png"}))
    return (await until(ws, lambda k, h, p: k == "PNG_", "PNG"))[2]


async def save(ws, path):
    await ws.send(json.dumps({"type": "save", "path": path}))
    k, h, _ = await until(ws, lambda k, h, p: k == "TEXT" and h["type"] in ("saved", "error"),
                          "saved")
    assert h["type"] == "saved", h


def cli_png(scene, out, extra=()):
    subprocess.run([BIN, "render", scene, "-o", out, "-q", *extra], check=True)
    return open(out, "rb").read()


def pixels(png_bytes, path):
    open(path, "wb").write(png_bytes)
    return np.asarray(Image.open(path)).astype(int)


async def drag(ws, width=320, height=256):
    """hello with a view of @width x @height, its first sharp frame, a drag of 10
    rotations, a zoom that stops (input 11); returns every frame after the first,
    (header, JPEG), to the sharp frame of input 11."""
    await ws.send(json.dumps({"type": "hello", "width": width, "height": height}))
    await until(ws, sharp, "first sharp frame")
    for i in range(1, 11):
        await ws.send(json.dumps({"type": "nav", "motion": "rotate", "dx": 6, "dy": 2,
                                  "seq": i, "moving": True}))
        await asyncio.sleep(0.02)
    await ws.send(json.dumps({"type": "nav", "motion": "zoom", "factor": 1.2, "seq": 11,
                              "moving": False}))
    frames = []
    while True:
        k, h, p = await until(ws, lambda k, h, p: k == "FRME", "frame")
        frames.append((h, p))
        if h["sharp"] and h["input_seq"] == 11:
            return frames


def descendants(pid, comm):
    """The processes below @pid (children, grandchildren...) named @comm."""
    parent = {}
    for d in os.listdir("/proc"):
        try:
            with open(f"/proc/{d}/stat") as f:
                st = f.read()
            parent[int(d)] = int(st[st.rindex(")") + 2:].split()[1])
        except (ValueError, OSError):
            continue
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        for c, pp in parent.items():
            if pp == p:
                todo.append(c)
                try:
                    with open(f"/proc/{c}/comm") as f:
                        if f.read().strip() == comm:
                            out.append(c)
                except OSError:
                    pass
    return out


def vulkan_driver_loaded(pid):
    """Whether process @pid has a Vulkan driver (an ICD: libvulkan_*.so) mapped."""
    with open(f"/proc/{pid}/maps") as f:
        return any("libvulkan_" in line for line in f)


def ranks_near(srv, one, path):
    """A drag on MPI server @srv, then its view's PNG (kept at @path): within 2
    grey levels of the one-process pixels @one (the parallel module's
    compositing)."""
    async def run():
        async with srv.connect() as ws:
            await drag(ws)
            return await png_of(ws)
    diff = np.abs(pixels(asyncio.run(run()), path) - one)
    assert diff.max() <= 2, f"2 ranks differ from one process by {diff.max()}"


async def drag_and_png(srv, root, name, cli_extra=(), steps_expected=False):
    async with srv.connect() as ws:
        frames = [h for h, _ in await drag(ws)]
        reduced = [f for f in frames if f["kind"] != "full"]
        seqs = [f["input_seq"] for f in frames]
        assert seqs == sorted(seqs), seqs  # never an older input after a newer one
        assert reduced or steps_expected, frames
        if steps_expected:  # progressive steps: full but not sharp before the sharp one
            assert any(f["kind"] == "full" and not f["sharp"] for f in frames) or \
                frames[-1]["sharp"], frames
        png = await png_of(ws)
        await save(ws, name + ".json")
    ours = pixels(png, os.path.join(root, name + "_page.png"))
    cli = cli_png(os.path.join(root, name + ".json"), os.path.join(root, name + "_cli.png"),
                  cli_extra)
    return png, cli, ours


def main():
    tmp = tempfile.mkdtemp(prefix="volvis-serve-test-")
    root = os.path.join(tmp, "root")
    os.makedirs(root)
    shutil.copy(os.path.join(DATA, "volumes", "ct_head.nrrd"), root)
    head = os.path.join(root, "ct_head.nrrd")
    # an OME-Zarr pyramid of the head, written by our converter
    subprocess.run([BIN, "convert", head, os.path.join(root, "head.ome.zarr"), "-q"], check=True)
    failures = 0

    def check(name, fn):
        nonlocal failures
        if ONLY not in name:
            return
        t0 = time.time()
        try:
            fn()
            print(f"ok   {name} ({time.time() - t0:.1f} s)", flush=True)
        except Exception as e:  # report every check, then fail
            failures += 1
            print(f"FAIL {name}: {e!r}", flush=True)

    def in_memory():
        srv = Server([head])
        try:
            png, cli, _ = asyncio.run(drag_and_png(srv, root, "mem"))
            assert png == cli, "the page's PNG differs from volvis render of the session"
        finally:
            srv.stop()

    def out_of_core():
        srv = Server(["--memory-limit", "16M", os.path.join(root, "head.ome.zarr")])
        try:
            png, cli, _ = asyncio.run(drag_and_png(srv, root, "ooc", ("--memory-limit", "16M",
                                                                      "--lod", "1"), True))
            assert png == cli, "out of core: the PNG differs from volvis render of the session"
        finally:
            srv.stop()

    def mpi():
        if not shutil.which("mpirun"):
            raise AssertionError("mpirun is missing (openmpi-bin)")
        one = pixels(open(os.path.join(root, "mem_page.png"), "rb").read(),
                     os.path.join(root, "x.png"))
        srv = Server([head], mpi=2)
        try:
            async def leave():
                # a tab that leaves while its frames are drawn by all ranks: its
                # session ends without holding up the server (its render thread
                # may wait on the service thread for a frame of all ranks)
                for _ in range(3):
                    async with srv.connect() as gone:
                        await gone.send(json.dumps({"type": "hello", "width": 320,
                                                    "height": 256}))
                        for i in range(1, 4):
                            await gone.send(json.dumps({"type": "nav", "motion": "rotate",
                                                        "dx": 9, "dy": 0, "seq": i,
                                                        "moving": True}))
                        await gone.send(json.dumps({"type": "png"}))
            asyncio.run(leave())
            ranks_near(srv, one, os.path.join(root, "mpi_page.png"))
        finally:
            srv.stop()

    def gpu():
        # a session whose World names the gpu renderer (Vulkan: lavapipe here)
        scene = os.path.join(root, "head_gpu.json")
        with open(scene, "w") as f:
            json.dump({"lights": [{"type": "directional", "color": [1, 1, 1],
                                   "intensity": 1.0}],
                       "objects": [{"name": "head", "type": "volume", "file": "ct_head.nrrd",
                                    "origin": [-122.0, -122.0, -80.25], "mode": "composite",
                                    "transfer_function": {
                                        "opacity": [[100, 0.0], [1500, 0.8]],
                                        "color": [[100, [1, 0.9, 0.8]], [1500, [1, 1, 1]]]}}],
                       "render": {"renderer": "gpu"}}, f)
        srv = Server([scene])
        try:
            async def state_renderer():
                async with srv.connect() as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 64, "height": 48}))
                    return (await until(ws, lambda k, h, p: k == "TEXT" and
                                        h["type"] == "state" and h["dims"],
                                        "state"))[1]["renderer"]
            named = asyncio.run(state_renderer())
            assert named == "gpu", named
            png, cli, one = asyncio.run(drag_and_png(srv, root, "gpu"))
            with open(os.path.join(root, "gpu.json")) as f:
                saved = json.load(f)
            assert saved["render"]["renderer"] == "gpu", saved.get("render")
            assert png == cli, "gpu: the page's PNG differs from volvis render of the session"
            # the same view drawn by raycast: the gpu renderer's image, not another's
            saved["render"]["renderer"] = "raycast"
            with open(os.path.join(root, "gpu_as_raycast.json"), "w") as f:
                json.dump(saved, f)
            ray = pixels(cli_png(os.path.join(root, "gpu_as_raycast.json"),
                                 os.path.join(root, "gpu_raycast.png")),
                         os.path.join(root, "gpu_raycast.png"))
            mse = float(np.mean((one - ray) ** 2))
            psnr = 10 * np.log10(255.0 ** 2 / mse) if mse > 0 else float("inf")
            assert psnr >= 40, f"gpu against raycast {psnr:.1f} dB"
            assert one.max() > 50, "the gpu frame is empty"
        finally:
            srv.stop()
        if not shutil.which("mpirun"):
            raise AssertionError("mpirun is missing (openmpi-bin)")
        srv = Server([scene], mpi=2)
        try:
            ranks_near(srv, one, os.path.join(root, "gpu_mpi_page.png"))
            # each rank drew on a Vulkan device: the driver is loaded in both (the
            # ranks drew with raycast, whatever the World named, before)
            drivers = [vulkan_driver_loaded(pid) for pid in descendants(srv.p.pid, "volvis")]
            assert len(drivers) == 2 and all(drivers), f"ranks with a Vulkan driver: {drivers}"
        finally:
            srv.stop()

    def shared_session():
        srv = Server(["--shared", head])
        try:
            async def run():
                async with srv.connect() as a, srv.connect() as b:
                    for ws in (a, b):
                        await ws.send(json.dumps({"type": "hello", "width": 320,
                                                  "height": 256}))
                        await until(ws, sharp, "first sharp frame")
                    await b.send(json.dumps({"type": "nav", "motion": "rotate", "dx": 30,
                                             "dy": 0, "seq": 7, "moving": False}))
                    ka = await until(a, lambda k, h, p: sharp(k, h, p) and h["input_seq"] == 7,
                                     "the other client's steering seen")
                    kb = await until(b, lambda k, h, p: sharp(k, h, p) and h["input_seq"] == 7,
                                     "own steering")
                    assert ka[1]["seq"] == kb[1]["seq"] and ka[2] == kb[2]
            asyncio.run(run())
        finally:
            srv.stop()

    def thumbnails_listing_errors():
        srv = Server([head])
        try:
            async def run():
                async with srv.connect() as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 320, "height": 256}))
                    k, state, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                              h["type"] == "state" and h["dims"], "state")
                    await ws.send(json.dumps({"type": "thumbnails", "size": 48}))
                    names = set()
                    while len(names) < len(state["presets"]):
                        k, h, p = await until(ws, lambda k, h, p: k == "THMB", "thumbnail")
                        assert p[:2] == b"\xff\xd8" and h["width"] == 48
                        names.add(h["name"])
                    assert names == set(state["presets"])
                    await ws.send(json.dumps({"type": "list", "path": ""}))
                    k, h, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                          h["type"] == "listing", "listing")
                    entries = {e["name"]: e for e in h["entries"]}
                    assert entries["head.ome.zarr"]["store"] and not entries["head.ome.zarr"]["dir"]
                    for bad in ({"type": "open", "path": "../etc/passwd"},
                                {"type": "open", "path": "/etc/passwd"},
                                {"type": "save", "path": "x.png"},
                                {"type": "list", "path": "nowhere"}):
                        await ws.send(json.dumps(bad))
                        k, h, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                              h["type"] == "error", "error")
                        assert "\n" not in h["message"]
                    # still served: a slice and a probe with the value's unit
                    await ws.send(json.dumps({"type": "probe", "axis": "axial", "index": 60,
                                              "width": 128, "height": 128, "x": 64, "y": 64}))
                    k, h, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                          h["type"] == "probe", "probe")
                    assert h["value"] is not None and h["value_unit"] == "HU"
                    assert h["indices"]["axial"] == 60
            asyncio.run(run())
        finally:
            srv.stop()

    def channels_and_time():
        try:
            import tifffile
            import nibabel as nib
        except ImportError as e:
            raise AssertionError(f"{e} (python3-tifffile, python3-nibabel)")
        z, y, x = np.mgrid[0:24, 0:32, 0:72]
        balls = [(((x - cx) ** 2 + (y - 16) ** 2 + (z - 12) ** 2 <= 64) * 900 + 40)
                 .astype(np.uint16) for cx in (14, 36, 58)]
        tifffile.imwrite(os.path.join(root, "cells.ome.tif"), np.stack(balls), ome=True,
                         metadata={"axes": "CZYX", "Channel": {"Name": ["a", "b", "c"]}})
        steps = np.stack([(((x - 20 - 12 * t) ** 2 + (y - 16) ** 2 + (z - 12) ** 2 <= 64) *
                           200.0).astype(np.float32) for t in range(3)], axis=-1)
        nib.save(nib.Nifti1Image(steps.transpose(2, 1, 0, 3), np.eye(4)),
                 os.path.join(root, "moving.nii.gz"))

        async def frame_after(ws, msg):
            """The sharp frame after @msg, and the last state sent before it."""
            await ws.send(json.dumps(msg))
            seen = {}

            def keep(k, h, p):
                if k == "TEXT" and h["type"] == "state":
                    seen["state"] = h
                return sharp(k, h, p)
            k, h, p = await until(ws, keep, f"the sharp frame after {msg['type']}")
            return p, seen.get("state")

        srv = Server(["--root", root, os.path.join(root, "cells.ome.tif")])
        try:
            async def run():
                async with srv.connect() as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 128, "height": 96}))
                    # the state of the file opened (hello may come before the open ends)
                    k, st, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                           h["type"] == "state" and h["dims"], "state")
                    assert [c["name"] for c in st["channels"]] == ["a", "b", "c"], st["channels"]
                    first = (await until(ws, sharp, "first frame"))[2]
                    hidden, st = await frame_after(ws, {"type": "channel", "index": 1,
                                                        "visible": False})
                    assert hidden != first, "hiding a channel changed nothing"
                    assert st and st["channels"][1]["visible"] is False, st
                    recolored, st = await frame_after(ws, {"type": "channel", "index": 0,
                                                           "color": "#00ff00"})
                    assert recolored != hidden and st["channels"][0]["color"] == "#00ff00", st
                    # the whole time series: open it in the same session
                    t0, st = await frame_after(ws, {"type": "open", "path": "moving.nii.gz"})
                    assert st and st["time_steps"] == 3 and st["name"] == "moving.nii.gz", st
                    t2, st = await frame_after(ws, {"type": "time", "step": 2})
                    assert t2 != t0, "time step 2 looks like step 0"
                    assert st and st["time"] == 2, st
            asyncio.run(run())
        finally:
            srv.stop()

    def channels_out_of_core():
        """A 3-channel OME-Zarr pyramid (zarr-python's; Zarr v2, OME-Zarr 0.4) under
        --memory-limit: one object of its 3 channels out of core (every channel of a node
        read at once), the PNG equal to volvis render of the saved session with the same
        limit, and a channel hidden reads no chunk again (the out-of-core counts)."""
        import zarr
        z, y, x = np.mgrid[0:48, 0:64, 0:96]
        lv = np.stack([(((x - cx) ** 2 + (y - 32) ** 2 + (z - 24) ** 2 <= 200) * 900 + 40 +
                        (x + y + z) % 7).astype(np.uint16) for cx in (24, 48, 72)])
        path = os.path.join(root, "cells.ome.zarr")
        g = zarr.open_group(zarr.DirectoryStore(path, dimension_separator="/"), mode="w")
        ds = []
        for k in range(3):
            g.create_dataset(str(k), data=lv, chunks=(1, 16, 16, 16), dimension_separator="/")
            ds.append({"path": str(k), "coordinateTransformations": [
                {"type": "scale", "scale": [1.0] + [2.0 ** k] * 3}]})
            lv = lv[:, ::2, ::2, ::2]
        g.attrs["multiscales"] = [{"version": "0.4", "axes": [
            {"name": "c", "type": "channel"}] + [{"name": a, "type": "space"} for a in "zyx"],
            "datasets": ds}]
        g.attrs["omero"] = {"channels": [{"label": n, "color": c} for n, c in
                                         (("a", "FF0000"), ("b", "00FF00"), ("c", "0000FF"))]}
        srv = Server(["--root", root, "--memory-limit", "4M", path])
        try:
            async def run():
                async with srv.connect() as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 128, "height": 96}))
                    k, st, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                           h["type"] == "state" and h["dims"], "state")
                    assert [c["name"] for c in st["channels"]] == ["a", "b", "c"], st["channels"]
                    first = (await until(ws, sharp, "first frame"))[2]
                    png = await png_of(ws)
                    await save(ws, "chooc.json")
                    await ws.send(json.dumps({"type": "channel", "index": 1, "visible": False}))
                    hidden = (await until(ws, sharp, "the frame without channel b"))[2]
                    assert hidden != first, "hiding a channel changed nothing"
                    return png
            png = asyncio.run(run())
            cli = cli_png(os.path.join(root, "chooc.json"), os.path.join(root, "chooc_cli.png"),
                          ("--memory-limit", "4M", "--lod", "1"))
            assert png == cli, "the page's PNG of the channels out of core differs from volvis " \
                               "render of the session"
        finally:
            srv.stop()

    def foreground_window():
        """The slice views' window of mricron's MNI template (63 % of its voxels a
        background at 0, the brain between 62 and 119) spans the brain: its lower
        end at 50 or above, as the GUI's (vv_slice_auto_window through the door)."""
        ch2 = "/usr/share/mricron/templates/ch2better.nii.gz"
        if not os.path.exists(ch2):
            raise AssertionError(f"{ch2} is missing (Debian's mricron-data)")
        shutil.copy(ch2, root)
        srv = Server(["--root", root, os.path.join(root, "ch2better.nii.gz")])
        try:
            async def run():
                async with srv.connect() as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 64, "height": 64}))
                    k, st, _ = await until(ws, lambda k, h, p: k == "TEXT" and
                                           h["type"] == "state" and h["dims"], "state")
                    lo, hi = st["level"] - st["window"] / 2, st["level"] + st["window"] / 2
                    print(f"  ch2better: the browser's window {lo:.1f} .. {hi:.1f}")
                    assert lo >= 50 and hi <= 131, (lo, hi)
            asyncio.run(run())
        finally:
            srv.stop()

    def tls():
        if not shutil.which("openssl"):
            raise AssertionError("openssl is missing")
        key, cert = os.path.join(tmp, "key.pem"), os.path.join(tmp, "cert.pem")
        subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout",
                        key, "-out", cert, "-days", "2", "-subj", "/CN=localhost"], check=True,
                       capture_output=True)
        srv = Server(["--cert", cert, "--key", key, head])
        try:
            assert srv.base.startswith("https://"), srv.base
            ctx = ssl.create_default_context()
            ctx.check_hostname = False
            ctx.verify_mode = ssl.CERT_NONE
            r = urllib.request.urlopen(srv.base + "/?token=" + srv.token, context=ctx)
            assert r.status == 200 and "HttpOnly" in r.headers["Set-Cookie"]
            try:
                urllib.request.urlopen(srv.base + "/", context=ctx)
                raise AssertionError("no 403 without the token over HTTPS")
            except urllib.error.HTTPError as e:
                assert e.code == 403, e.code

            async def run():
                async with srv.connect(ctx) as ws:
                    await ws.send(json.dumps({"type": "hello", "width": 64, "height": 64}))
                    await until(ws, sharp, "a frame over WSS")
            asyncio.run(run())
        finally:
            srv.stop()

    def yuv_frames():
        import io

        def decode(jpeg):
            return np.asarray(Image.open(io.BytesIO(jpeg)).convert("RGB")).astype(float)

        def psnr(a, b):
            mse = np.mean((a - b) ** 2)
            return float("inf") if mse == 0 else 10 * np.log10(255.0 ** 2 / mse)

        srv = Server([head])
        try:
            async def run():
                async with srv.connect() as ws:
                    frames = await drag(ws, 999, 799)
                    return frames, await png_of(ws)
            frames, png = asyncio.run(run())
        finally:
            srv.stop()
        for h, p in frames:  # every frame, reduced ones of odd sides included
            img = decode(p)
            assert img.shape == (h["height"], h["width"], 3), (img.shape, h)
        h, frame = frames[-1]
        assert (h["width"], h["height"]) == (999, 799), h
        view = Image.open(io.BytesIO(png)).convert("RGB")
        ref = io.BytesIO()  # libjpeg's encoder from RGB, as tjCompress2 of RGBX was
        view.save(ref, "JPEG", quality=h["quality"], subsampling=2)
        ours, theirs, exact = decode(frame), decode(ref.getvalue()), np.asarray(view).astype(float)
        between, to_ours, to_theirs = psnr(ours, theirs), psnr(ours, exact), psnr(theirs, exact)
        print(f"  999 x 799 at quality {h['quality']}: {between:.1f} dB between the two "
              f"JPEGs; to the PNG {to_ours:.1f} dB (YUV planes), {to_theirs:.1f} dB (PIL)")
        assert between >= 48, between
        assert to_ours >= to_theirs - 0.5, (to_ours, to_theirs)

    check("drag and PNG in memory equal volvis render of the saved session", in_memory)
    check("out of core: progressive still frames, PNG equals volvis render", out_of_core)
    check("mpirun -n 2: the PNG within 2 levels of one process", mpi)
    check("gpu: PNG equals volvis render, near raycast; mpirun -n 2 within 2 levels", gpu)
    check("--shared: two clients, one view", shared_session)
    check("thumbnails, the listing's store, refusals keep the connection", thumbnails_listing_errors)
    check("channels (OME-TIFF) and time steps (4-D NIfTI)", channels_and_time)
    check("channels of a store out of core: PNG equals volvis render", channels_out_of_core)
    check("--cert/--key: HTTPS, 403 without the token, frames over WSS", tls)
    check("the slice window of ch2better.nii.gz spans its brain", foreground_window)
    check("JPEG from YUV 4:2:0 planes at 999 x 799: decodes, within 48 dB of RGB's", yuv_frames)
    if failures == 0:
        shutil.rmtree(tmp, ignore_errors=True)
    else:
        print(f"outputs kept in {tmp}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
