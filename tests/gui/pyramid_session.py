#!/usr/bin/python3
"""A multiresolution file out of core in the GUI (CTest test_gui_pyramid).

The CT head written as a 3-level OME-Zarr pyramid by zarr-python (32^3
Blosc-lz4 chunks) is opened with VOLVIS_MEMORY_LIMIT=16M, so that its
13.5 MiB level 0 is not read whole: the object shows the coarsest level,
and the scene view draws the pyramid by level of detail. The Navigator's
cache line names the chunks resident within the 16 MiB, the levels in use
and what is still coarser; it reaches "converged", and that full frame is
the one `volvis render STORE --memory-limit 16M` draws of the same view
(the session's camera) within rounding. A drag shows ray-cast previews
of the data (the frame log's representation column), never boxes, and the
image sharpens again when the drag stops. The slice views sample the
pyramid: the axial readout's value at a clicked point is level 0's, as
`volvis slice --probe` of the saved session reads it. The Measurement
page's histogram is level 0's, read box by box out of core (every voxel
of the 256 x 256 x 108 volume counted), not the proxy's, and so are its
isosurface measurements by Marching Cubes and voxel counting (the
triangles and voxels `volvis measure` finds in the whole file). A scene
of three objects side by side (composite and MIP; two of one store and
one of a copy, each object owning its source) is drawn out of core in one
frame (the cache line counts them) within the one 16 MiB budget of the
process's cache, and its converged frame is what `volvis render SCENE
--memory-limit` draws of the saved session. Then, in a GUI started with
nothing open, File > Open URL… as a person uses it (the menu, the dialog's URL entry, Open) opens
the store from a slow loopback HTTP server: while the loader waits for it
the views show "N chunks, X MB pending" (its accessible name; its description says what it is),
gone once every read is answered, and the converged frame is what `volvis
render` draws of the store by path in the saved session's view.

usage: pyramid_session.py GUI CLI OUTDIR [two | url]
"""
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "io"))
from atspi import Session, check, psnr, run, skip  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]  # and "two": the session of two pyramids alone
os.makedirs(OUT, exist_ok=True)
HEAD = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
NUM = r"(-?[0-9.]+(?:e[-+]?[0-9]+)?)"
READ = re.compile(rf"value {NUM} at voxel \({NUM}, {NUM}, {NUM}\), \({NUM}, {NUM}, {NUM}\)")


def make_store():
    try:
        import nibabel
        import numcodecs
        import numpy as np
        from pyramid_common import write_ome_zarr
    except ImportError as e:
        skip(f"zarr-python, numcodecs, nibabel or numpy missing: {e}")
    store = os.path.join(OUT, "head.ome.zarr")
    nii = os.path.join(OUT, "head.nii")
    subprocess.run([CLI, "convert", HEAD, nii, "--quiet"], check=True)
    arr = np.ascontiguousarray(np.asarray(nibabel.load(nii).dataobj).transpose(2, 1, 0))
    write_ome_zarr(store, arr, [1.5, 0.957, 0.957], (32, 32, 32),
                   numcodecs.Blosc("lz4", shuffle=numcodecs.Blosc.SHUFFLE), "/")
    return store


def cache_line(s):
    return s.text(s.find_label(lambda n: n.startswith("out of core:")))


def converged_frame(s, prefix, out, tag, at_convergence, label_timeout=20):
    """A session's converged view, kept: the View page's out-of-core line (the label
    whose text starts with PREFIX, there within LABEL_TIMEOUT s) until it says
    "converged" (within 120 s); AT_CONVERGENCE(its first text, its converged text), the
    session's checks of them; a second later the full frame copied to
    TAG + "converged.png", the window to TAG + "window.png" and the session saved as
    OUT/TAG + "session.json". Returns (the frame's PNG, the session's path)."""
    s.page("View")
    first = s.text(s.find_label(lambda n: n.startswith(prefix), timeout=label_timeout))
    line = lambda: s.text(s.find_label(lambda n: n.startswith(prefix)))  # noqa: E731
    s.wait_for(lambda: "converged" in line(), f"never converged: {line()!r}", timeout=120)
    at_convergence(first, line())
    time.sleep(1)
    shot = s.full_png(copy_to=f"{tag}converged.png")
    s.screenshot(f"{tag}window.png")
    session = os.path.join(out, f"{tag}session.json")
    s.save_as(session)
    return shot, session


def same_as_cli(shot, session, png, what, options=(), says=None):
    """`volvis render SESSION` (OPTIONS added) to PNG must succeed (its output saying
    SAYS, when given) and draw the GUI's frame SHOT within rounding (PSNR 30 dB or more);
    WHAT names the GUI's frame in the messages."""
    r = subprocess.run([CLI, "render", session, *options, "-o", png], capture_output=True,
                       text=True)
    print(f"volvis render {' '.join(options)} of {os.path.basename(session)}: "
          f"{r.stdout.strip()} {r.stderr.strip()}")
    check(r.returncode == 0 and (says is None or says in r.stdout),
          f"volvis render of the session of {what} failed: {r.stderr}")
    q = psnr(shot, png)
    print(f"{what} against volvis render of the session: {q:.1f} dB")
    check(q >= 30, f"{what} is not the CLI's ({q:.1f} dB)")


def main():
    store = make_store()
    env = {"VOLVIS_MEMORY_LIMIT": "16M"}
    with Session(GUI, [store], OUT, env=env, window=(1100, 720)) as s:
        s.wait_full(0, "opening the pyramid")

        def opened(first, line):
            print(f"first: {first!r}")
            check("of 16 MiB" in first, f"the cache line does not name the limit: {first!r}")
            print(f"converged: {line!r}")
            opening = [f for f in s.frames_log() if f["state"] == s.frames_log()[-1]["state"]]
            fulls = [f for f in opening if f["kind"] == "full"]
            print(f"opening: {[(f['kind'], f['render_ms']) for f in opening]}")
            check(len(fulls) >= 2, "the full frame did not sharpen (one full frame at opening)")
            m = re.search(r"\(([0-9.]+) of 16 MiB\)", line)
            check(m and float(m.group(1)) <= 16, f"the cache exceeds its limit: {line!r}")
            levels = [int(x) for x in re.findall(r" (\d+) \(\d+ nodes\)", line)]
            check(levels and min(levels) <= 1, f"no fine level in use: {line!r}")
        # the same view through the CLI: the session's camera, the store out of core
        shot, session = converged_frame(s, "out of core:", OUT, "", opened)
        # a drag: previews of the data, then the image sharpens again
        s.focus_main()
        n0 = len(s.frames_log())
        view = s.find("3-D view")
        s.drag(view, (0.5, 0.5), (0.65, 0.45), steps=20, delay=0.03)
        t = time.time()
        s.wait_for(lambda: "converged" in cache_line(s) and s.frames_log()[-1]["kind"] == "full",
                   f"not converged after the drag: {cache_line(s)!r}", timeout=120)
        print(f"after the drag ({time.time() - t:.1f} s): {cache_line(s)!r}")
        kinds = [f["kind"] for f in s.frames_log()[n0:]]
        print(f"frames during and after the drag: {kinds}")
        check(not any(k in ("bbox", "boxes", "coarse_mc") for k in kinds),
              f"the drag drew boxes or surfaces, not the data: {kinds}")
        check(any(k.startswith("raycast") for k in kinds), f"no ray-cast preview: {kinds}")
        s.screenshot("after_drag.png")
        # the slice views sample the pyramid (level 0 at the cursor), not the proxy
        s.click(s.find("4 views"))
        time.sleep(1.5)
        axial = s.find("axial view")
        s.click(axial, at=(0.45, 0.55))
        time.sleep(1.0)
        t = s.text(s.find_label(lambda n: n.startswith("axial:")))
        m = READ.search(t)
        check(m, f"axial readout {t!r}")
        v, i, j, k, x, y, z = (float(g) for g in m.groups())
        s.screenshot("four_up.png")
        # the histogram of level 0, read out of core (not the 64 x 64 x 27 proxy's)
        s.click(s.find("1 view"))
        s.page("Measurement")
        mpage = s.find("Measurement page")
        s.click(s.find("Histogram", "push button", root=mpage))
        hist = s.find_label(lambda n: n.startswith("histogram of"), root=mpage, timeout=60)
        ht = s.text(hist)
        print(f"histogram: {ht!r}")
        check("256 x 256 x 108, read out of core): 7077888 voxels" in ht,
              f"the histogram is not level 0's: {ht!r}")
        s.screenshot("histogram.png")
        # Marching Cubes reads level 0 box by box too
        s.click(s.find("Measure", "push button", root=mpage))
        iso = s.find_label(lambda n: n.startswith("head isovalue"), root=mpage, timeout=60)
        it = s.text(iso)
        print(f"isosurface: {it!r}")
        check("marching cubes" in it and "level 0 (256 x 256 x 108), read out of core" in it,
              f"Marching Cubes did not read level 0: {it!r}")
        # voxel counting reads level 0 box by box: volvis measure's count of the whole file
        s.choose(s.find("method", "combo box", root=mpage), ["marching cubes", "voxel counting"],
                 "voxel counting")
        s.click(s.find("Measure", "push button", root=mpage))
        vox = s.find_label(lambda n: n.startswith("head isovalue") and "voxel count" in n,
                           root=mpage, timeout=60)
        vt = s.text(vox)
        print(f"voxel counting: {vt!r}")
        check("level 0 (256 x 256 x 108), read out of core" in vt,
              f"voxel counting did not read level 0: {vt!r}")
        s.quit_discard()
    same_as_cli(shot, session, os.path.join(OUT, "cli.png"), "the GUI's converged frame",
                ["--quiet"])
    r = subprocess.run([CLI, "slice", session, "--probe", f"{x!r},{y!r},{z!r}"],
                       capture_output=True, text=True)
    check(r.returncode == 0, f"volvis slice --probe: {r.stderr}")
    probe = r.stdout.split()
    print(f"readout {t!r}; volvis slice --probe of the session: {r.stdout.strip()}")
    check(abs(float(probe[1]) - v) <= 1e-3 * (1 + abs(v)),
          f"the readout's value {v} is not level 0's {probe[1]}")
    r = subprocess.run([CLI, "measure", HEAD, "--iso", "0", "--method", "voxel"],
                       capture_output=True, text=True)
    print(f"volvis measure of the CT head: {r.stdout.strip()} {r.stderr.strip()}")
    m = re.search(r"(\d+) voxels", r.stdout)
    check(r.returncode == 0 and m and f"{m.group(1)} voxels" in vt,
          f"the GUI's level-0 voxel count is not volvis measure's: {vt!r}")
    r = subprocess.run([CLI, "measure", HEAD, "--iso", "0"], capture_output=True, text=True)
    m = re.search(r"Marching Cubes \((\d+) triangles\)", r.stdout)
    check(r.returncode == 0 and m and f" {m.group(1)} triangles" in it,
          f"the GUI's level-0 Marching Cubes is not volvis measure's: {it!r} / {r.stdout}")
    # a second GUI session runs in a process of its own (pyatspi keeps the
    # first session's bus), and so does a third
    r = subprocess.run([sys.executable, os.path.abspath(__file__), GUI, CLI, OUT, "two"])
    check(r.returncode == 0, f"the session of two pyramids failed ({r.returncode})")
    # the Open URL… session in the release preset alone: under the sanitizers
    # the chain of GUI sessions sets the suite's length, and the transport it
    # drives is under them in test_io_remote and the HTTP tests
    if os.environ.get("VV_SANITIZER"):
        print("the Open URL… session runs in the release preset alone")
        return
    r = subprocess.run([sys.executable, os.path.abspath(__file__), GUI, CLI, OUT, "url"])
    check(r.returncode == 0, f"the session of Open URL… failed ({r.returncode})")


def two_pyramids():
    """Three objects side by side (a scene): two of one store and one of a
    copy, each object owning its source, all drawn out of core by level of
    detail in one frame within the process's one budget, as volvis render
    of the scene out of core draws them."""
    import json
    import shutil
    store = os.path.abspath(os.path.join(OUT, "head.ome.zarr"))
    out = os.path.abspath(os.path.join(OUT, "two"))
    os.makedirs(out, exist_ok=True)
    # a second store: two files, each with sources of its own
    second = os.path.join(out, "copy.ome.zarr")
    shutil.rmtree(second, ignore_errors=True)
    shutil.copytree(store, second)
    tf = {"opacity": [[100, 0], [1500, 0.6]], "opacity_unit_distance": 1}
    scene = os.path.join(out, "two.json")
    json.dump({"view": {"width": 320, "height": 200, "eye": [392, -1300, 300],
                        "at": [392, 122, 80], "up": [0, 0, 1], "fov": 30},
               "objects": [{"name": "left", "file": store, "transfer_function": tf},
                           {"name": "right", "file": second, "position": [270, 0, 0],
                            "mode": "mip", "transfer_function": tf},
                           # a second object of the first file: a source of its own
                           {"name": "far", "file": store, "position": [540, 0, 0],
                            "mode": "mip", "transfer_function": tf}]},
              open(scene, "w"))
    with Session(GUI, [scene], out, env={"VOLVIS_MEMORY_LIMIT": "16M"},
                 window=(1100, 720)) as s:
        s.wait_full(0, "opening the scene")

        def within_budget(first, line):
            print(f"three objects of two pyramids: {line!r}")
            m = re.search(r"\(([0-9.]+) of 16 MiB\)", line)
            most = re.search(r"at most ([0-9.]+) MiB", line)
            check(m and float(m.group(1)) <= 16 and most and float(most.group(1)) <= 16,
                  f"the three objects' pieces are not within one budget of 16 MiB: {line!r}")
        shot, session = converged_frame(s, "3 objects out of core:", out, "two_", within_budget,
                                        label_timeout=30)
        s.quit()
    same_as_cli(shot, session, os.path.join(out, "two_cli.png"),
                "the GUI's frame of three objects", ["--memory-limit", "32M"],
                says="3 objects out of core")


REMOTE_WHAT = "reads of remote stores"
PENDING = re.compile(r"^\d+ chunks?(, [0-9.]+ MB|, [0-9]+ kB)? pending$")


def url_session():
    """A GUI started with nothing open; File > Open URL… of the store from a slow
    server (open_url); its converged frame is what volvis render draws of the saved
    session with the store's path in place of the URL (no network)."""
    import json
    store = os.path.abspath(os.path.join(OUT, "head.ome.zarr"))
    out = os.path.abspath(os.path.join(OUT, "url"))
    os.makedirs(out, exist_ok=True)
    with Session(GUI, [], out, env={"VOLVIS_MEMORY_LIMIT": "16M"}, window=(1100, 720)) as s:
        s.app()
        s.find("Open a file…", "push button", timeout=60)
        shot, session = open_url(s, store, out)
        s.quit()
    sc = json.load(open(session))
    check(len(sc["objects"]) == 1 and sc["objects"][0]["file"].startswith("http://127.0.0.1:"),
          f"the saved session does not name the URL: {sc['objects']}")
    sc["objects"][0]["file"] = store
    local = os.path.join(out, "url_local.json")
    json.dump(sc, open(local, "w"))
    same_as_cli(shot, local, os.path.join(out, "url_cli.png"),
                "the GUI's frame of the URL (the store by path)", ["--memory-limit", "16M"])


def open_url(s, store, out):
    """File > Open URL… as a person uses it (the menu shows it and its shortcut, Ctrl+Shift+O),
    the dialog's URL entry, Open.
    The store is served by a slow loopback server (http_common.drip_server): while the
    loader waits for it the views show "N chunks, X MB pending" (a label: its text is its
    accessible name, its description says what it is), gone once every read is
    answered; the frame then converges. Returns (the converged frame, the session saved of it)."""
    from http_common import drip_server
    srv, drip = drip_server(os.path.dirname(store), piece=1024, pause=0.004)
    url = f"http://127.0.0.1:{srv.server_address[1]}/{os.path.basename(store)}"
    try:
        s.focus_main()
        # the menu lists it with its shortcut; GTK 4.8 gives a popover's items
        # no usable extents, so the shortcut the menu shows opens it
        s.click(s.find("Menu"))
        s.find("Open URL…", timeout=20, visible=False)
        s.key("Escape")
        s.type_url(url)
        n0 = s.n_full()
        s.click(s.find("Open", "push button", timeout=20))
        line, t0 = None, time.time()
        while line is None and time.time() - t0 < 60:
            line = next((o for o in s.walk(prune_hidden_pages=True)
                         if (o.description or "").startswith(REMOTE_WHAT)), None)
        check(line is not None, "no remote-data line (its accessible description)")

        def shown():  # its text while on screen (a label's name is its text)
            try:
                return s.text(line) if s.extents(line)[2] > 0 else ""
            except Exception:
                return ""
        seen, t0 = [], time.time()
        while not seen and time.time() - t0 < 120:
            t = shown()
            if PENDING.match(t):
                seen.append(t)
                s.screenshot("url_pending.png")
            time.sleep(0.05)
        check(seen, "no \"N chunks, X MB pending\" over the views while the store loads")
        print(f"while loading: {seen[0]!r} (served {drip.sent} bytes so far)")
        s.wait_for(lambda: shown() == "", "the pending line stays after the reads ended",
                   timeout=120)
        s.wait_full(n0, "opening the URL")

        def pending_gone(first, line):
            check(shown() == "", f"the pending line is shown once converged: {shown()!r}")
            print(f"converged over HTTP: {line!r}; served {drip.requests} requests, "
                  f"{drip.sent} bytes")
        return converged_frame(s, "out of core:", out, "url_", pending_gone)
    finally:
        srv.shutdown()
        srv.server_close()


run({"two": two_pyramids, "url": url_session}.get((sys.argv[4:] or [""])[0], main))
