#!/usr/bin/python3
"""One test per numbered defect of issue 28, each failing on the GUI before
the fix (CTest test_gui_defect_NN). Widgets are found by accessible name and
role over AT-SPI; input is real (xdotool at the widgets' extents).

usage: defects.py GUI CLI OUTDIR N
  1  the wheel over the side bar's spin buttons leaves the World unchanged;
     scale pivots on the object's centre
  2  interaction (a drag, a transfer-function drag) shows ray casts, never boxes
  3  the 3-D view fills a 1600 x 1000 window (wider than 512 pixels)
  4  a mesh opened beside a volume is shown (framed, drawn, Y-up turned)
  5  a filter keeps the transfer function's points
  6  the transfer-function editor: axes readout, numeric entry, >= 20 presets
     with thumbnails, the active one shown
  7  the Rendering page lists the renderer's options by name (no "1:", "2:")
  8  measurement results under the button, in mm (never "unknown")
  9  cut planes: a list, on/off, removal, numbers that follow the handle
 10  a 3-D mouse present at start turns the view without the devices page
 11  discoverability: header bar, start page, quit dialog with Save, a fresh
     file is saved, the render window closes with Close, Esc and Ctrl+W
"""
import json
import os
import re
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Failure, Session, ae, check, run, skip  # noqa: E402

GUI, CLI, OUT, N = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
os.makedirs(OUT, exist_ok=True)
DATA = os.path.abspath("../shared/data")
HEAD_TF = {"opacity": [[-600, 0.0], [-300, 0.015], [-150, 0.0], [250, 0.0], [500, 0.3],
                       [1500, 0.8]],
           "color": [[-600, [0.9, 0.6, 0.5]], [250, [1, 0.93, 0.8]], [1500, [1, 1, 1]]],
           "opacity_unit_distance": 0.957}


def head_scene(name="session.json", **extra):
    scene = {
        "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
                 "width": 512, "height": 512, "background": [0, 0, 0]},
        "lights": [{"type": "directional", "direction": [0, -1, 0]}],
        "objects": [{"name": "head", "type": "volume", "file": f"{DATA}/volumes/ct_head.nrrd",
                     "origin": [-122.0, -122.0, -80.25], "mode": "composite", "step": 0.5,
                     "transfer_function": HEAD_TF}]}
    scene.update(extra)
    path = os.path.join(OUT, name)
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    return path


def saved(s, path):
    """Ctrl+S, then the session file as JSON."""
    s.key("ctrl+s")
    time.sleep(1.0)
    with open(path) as f:
        return json.load(f)


def spins_on_page(s, page):
    root = s.find(f"{page} page")
    return [o for o in s.find_all(role="spin button", root=root) if s.on_screen(o)]


# ---- 1 -----------------------------------------------------------------------------


def defect_1():
    # the default scene of a volume file: the head centred on the origin by
    # its position (-122 mm), so a scale about the centre doubles it
    with Session(GUI, [f"{DATA}/volumes/ct_head.nrrd"], OUT) as s:
        s.wait_full(0, "opening")
        time.sleep(1)
        # scale pivots on the centre: the CT head is centred on the origin, so
        # its position doubles with the scale
        s.page("Objects")
        px = s.find("position x", "spin button")
        x0 = s.value(px)
        s.set_spin(s.find("scale", "spin button"), 2)
        time.sleep(0.5)
        x1 = s.value(px)
        check(abs(x1 - 2 * x0) < 0.01, f"scale 2 about the centre: position x {x0} -> {x1}")
        print(f"scale 2 pivots on the centre: position x {x0:.3f} -> {x1:.3f}")
        for page in ("Objects", "Transfer function", "Lights", "View"):
            s.page(page)
            spins = spins_on_page(s, page)
            check(len(spins) >= 2, f"{page}: only {len(spins)} spin buttons on screen")
            before = [s.value(o) for o in spins]
            state = s.frames_log()[-1]["state"]
            title = s.title()
            for o in spins:
                if s.on_screen(o):
                    s.wheel(o, down=2, up=1)
            after = [s.value(o) for o in spins]
            changed = [o.name for o, a, b in zip(spins, before, after) if a != b]
            check(not changed, f"{page}: the wheel changed {changed}")
            check(s.frames_log()[-1]["state"] == state, f"{page}: the wheel changed the World")
            check(s.title() == title, f"{page}: the wheel changed the title: {s.title()!r}")
            print(f"{page}: the wheel over {len(spins)} spin buttons changed nothing")


# ---- 2 -----------------------------------------------------------------------------


BOXES = {"bbox", "boxes", "coarse_mc"}


def defect_2():
    path = head_scene()
    with Session(GUI, [path], OUT) as s:
        s.wait_full(0, "opening")
        time.sleep(2)  # the reduced casts are learnt from the first frames
        view = s.find("3-D view")
        n0 = len(s.frames_log())
        s.drag(view, (0.7, 0.5), (0.3, 0.55), steps=60, delay=0.03)
        time.sleep(0.2)
        kinds = [f["kind"] for f in s.frames_log()[n0:]]
        s.wait_full(0)
        check(kinds, "the drag showed no frame")
        check(not BOXES & set(kinds), f"the drag showed boxes: {kinds}")
        print(f"drag: {len(kinds)} frames, {sorted(set(kinds))}")
        s.page("Transfer function")
        editor = s.find("transfer function editor")
        n0 = len(s.frames_log())
        s.drag(editor, (0.8, 0.8), (0.8, 0.3), steps=40, delay=0.03)
        time.sleep(0.2)
        kinds = [f["kind"] for f in s.frames_log()[n0:]]
        check(kinds, "the transfer-function drag showed no frame")
        check(not BOXES & set(kinds), f"the transfer-function drag showed boxes: {kinds}")
        print(f"transfer-function drag: {len(kinds)} frames, {sorted(set(kinds))}")


# ---- 3 -----------------------------------------------------------------------------


def defect_3():
    path = head_scene()
    with Session(GUI, [path], OUT, window=(1600, 1000)) as s:
        s.wait_full(0, "opening")
        n = s.n_full()
        time.sleep(1)
        s.wait_full(n - 1)
        last = [f for f in s.frames_log() if f["kind"] == "full"][-1]
        x, y, w, h = s.extents(s.find("3-D view"))
        check(last["w"] > 512 and last["w"] >= w - 1, f"the view renders {last['w']} wide in a "
              f"widget {w} wide")
        check(abs(last["h"] - h) <= 1, f"the view renders {last['h']} high in a widget {h} high")
        check(w > 800, f"the 3-D view is only {w} pixels wide in a 1600-pixel window")
        # the side bar's pages are not clipped at the right edge
        for o in s.find_all(role="spin button", root=s.find("Objects page")):
            if s.on_screen(o):
                ox, oy, ow, oh = s.extents(o)
                check(ox + ow <= 1600, f"{o.name} is clipped at the right ({ox}+{ow})")
        print(f"1600 x 1000: the 3-D view is {w} x {h}, rendered at {last['w']} x {last['h']}")


# ---- 4 -----------------------------------------------------------------------------


def defect_4():
    vol = f"{DATA}/volumes/neghip.slc"
    mesh = f"{DATA}/meshes/cow.obj"  # Y-up, about 10 units: the volume's 64 keep it visible
    with Session(GUI, [vol, mesh], OUT) as s:
        s.wait_full(0, "opening", timeout=300)
        time.sleep(2)
        session = os.path.join(OUT, "session.json")
        s.save_as(session)
        scene = json.load(open(session))
        objs = scene["objects"]
        check(len(objs) == 2, f"{len(objs)} objects")
        check(scene.get("render", {}).get("renderer") in ("raytrace",),
              f"a renderer that does not draw the mesh: {scene.get('render')}")
        # the last object (the mesh) is selected: its up axis is Y (cow.obj is Y-up)
        s.page("Objects")
        up = s.find("up axis", "combo box")
        shown = " ".join(s.text(o) for o in s.find_all(role="label", root=up))
        check("Y (OBJ" in shown, f"the mesh is not turned Y-up: up axis {shown!r}")
        withm = os.path.join(OUT, "with.png")
        subprocess.run([CLI, "render", session, "-q", "-o", withm], check=True, timeout=900)
        scene["objects"][1]["visible"] = False
        hidden = os.path.join(OUT, "hidden.json")
        json.dump(scene, open(hidden, "w"))
        without = os.path.join(OUT, "without.png")
        subprocess.run([CLI, "render", hidden, "-q", "-o", without], check=True, timeout=900)
        d = ae(withm, without)
        W, H = scene["view"]["width"], scene["view"]["height"]
        check(d > 0.001 * W * H, f"the mesh covers {d} pixels of {W * H}: not shown")
        print(f"volume and mesh: raytrace, the mesh covers {d:.0f} pixels, framed together")


# ---- 5 -----------------------------------------------------------------------------


def defect_5():
    path = head_scene()
    with Session(GUI, [path], OUT) as s:
        s.wait_full(0, "opening")
        s.page("Filtering")
        chain = s.find("filter chain", "text")
        s.click(chain)
        s.type("--threshold 300:")
        s.click(s.find("Apply", "push button", root=s.find("Filtering page")))
        t0 = time.time()
        while "filtered" not in open(os.path.join(OUT, "gui.log")).read():
            check(time.time() - t0 < 120, "the filter did not finish")
            time.sleep(0.3)
        scene = saved(s, path)
        tf = scene["objects"][0]["transfer_function"]
        check([p[0] for p in tf["opacity"]] == [p[0] for p in HEAD_TF["opacity"]],
              f"the filter replaced the transfer function: {tf['opacity']}")
        print("threshold filter applied: the transfer function's points are kept")


# ---- 6 -----------------------------------------------------------------------------


def defect_6():
    path = head_scene()
    with Session(GUI, [path], OUT, window=(1300, 900)) as s:
        s.wait_full(0, "opening")
        s.page("Transfer function")
        gallery = s.find("transfer-function presets", visible=False)
        presets = s.find_all(role="push button", root=gallery)
        names = [o.name for o in presets]
        check(len(presets) >= 20, f"{len(presets)} presets: {names}")
        for want in ("ct-bone", "ct-lung", "ct-vessels", "mr-t1-brain", "mr-t2-brain", "mip",
                     "fire", "microscopy-green", "microscopy-magenta"):
            check(want in names, f"no preset {want}")
        active = s.find_label(lambda n: n.startswith("Active preset:"))
        check("none" in s.text(active), f"active before a preset: {s.text(active)!r}")
        s.click(s.find("ct-bone", "push button"))
        # the label follows the preset once the main loop has run (slow under ASan)
        s.wait_for(lambda: "ct-bone" in s.text(active),
                   "after ct-bone: the active-preset label does not name it", timeout=20)
        # the thumbnails come from the volume: not black
        bone = s.find("ct-bone", "push button")
        t0 = time.time()
        while True:
            shot = s.screenshot("presets.png")
            x, y, w, h = s.extents(bone)
            mean = float(subprocess.run(["convert", shot, "-crop", f"{w}x{h - 20}+{x}+{y}",
                                         "-format", "%[fx:mean]", "info:"],
                                        capture_output=True, text=True).stdout or 0)
            if mean > 0.15 or time.time() - t0 > 60:
                break
            time.sleep(1)
        print(f"ct-bone's thumbnail: mean {mean:.3f}")
        # the editor's readout under the pointer
        editor = s.find("transfer function editor")
        readout = s.find_label(lambda n: n.startswith("point at the editor") or
                               n.startswith("value "))
        ex, ey, ew, eh = s.extents(editor)
        s.xdo("mousemove", str(ex + ew // 2), str(ey + eh // 3))
        time.sleep(0.4)
        r = s.text(readout)
        check(r.startswith("value ") and "opacity" in r and "colour #" in r, f"readout {r!r}")
        # a point added by a click, typed by number: value 700, opacity 0.4
        s.click(editor, at=(0.6, 0.5))
        value = s.find("point value", "spin button")
        check(-1024 <= s.value(value) <= 2986, f"selected point at {s.value(value)}")
        s.set_spin(value, 700)
        s.set_spin(s.find("point opacity", "spin button"), 0.4)
        time.sleep(0.5)
        check("none" in s.text(active), "the edited function still shows a preset as active")
        tf = saved(s, path)["objects"][0]["transfer_function"]
        check(any(abs(p[0] - 700) < 1e-6 and abs(p[1] - 0.4) < 1e-6 for p in tf["opacity"]),
              f"typed point (700, 0.4) not in {tf['opacity']}")
        print(f"readout {r!r}; point typed (700, 0.4); {len(presets)} presets, ct-bone active")


# ---- 7 -----------------------------------------------------------------------------


def defect_7():
    # a session rendered by the ray tracer: its options on the page
    path = head_scene(render={"renderer": "raytrace", "quality": 0})
    with Session(GUI, [path], OUT) as s:
        s.wait_full(0, "opening", timeout=300)
        s.page("Rendering")
        page = s.find("Rendering page")
        # on the page (some below the window: the page scrolls), not on other pages
        entries = [o.name for o in s.find_all(role="text", root=page) if s.extents(o)[2] > 0]
        check(entries, "no options shown for raytrace")
        bad = [e for e in entries if not re.fullmatch(r"[a-z][a-z0-9_]*", e)]
        check(not bad, f"option names that are no options: {bad}")
        r = subprocess.run([CLI, "renderers", "--json"], capture_output=True, text=True)
        if r.returncode != 0:
            print(f"raytrace options shown: {entries}")
            skip("'volvis renderers --json' (the typed option tables) is not built yet")
        table = [r for r in json.loads(r.stdout)["renderers"] if r["name"] == "raytrace"][0]
        keys = [o["key"] for o in table["options"]]
        check(sorted(entries) == sorted(keys), f"page {entries} != table {keys}")
        print(f"raytrace options: {entries}")


# ---- 8 -----------------------------------------------------------------------------


def write_mm_nrrd(path):
    n = 32
    data = bytearray()
    for k in range(n):
        for j in range(n):
            for i in range(n):
                r = ((i - 15.5) ** 2 + (j - 15.5) ** 2 + (k - 15.5) ** 2) ** 0.5
                data.append(200 if r < 10 else 0)
    hdr = ("NRRD0004\ntype: uchar\ndimension: 3\nspace: right-anterior-superior\n"
           f"sizes: {n} {n} {n}\nspace directions: (0.5,0,0) (0,0.5,0) (0,0,0.5)\n"
           "space units: \"mm\" \"mm\" \"mm\"\nspace origin: (0,0,0)\nencoding: raw\n\n")
    with open(path, "wb") as f:
        f.write(hdr.encode() + bytes(data))


def defect_8():
    ball = os.path.join(OUT, "ball_mm.nrrd")
    write_mm_nrrd(ball)
    with Session(GUI, [ball], OUT, window=(1300, 1000)) as s:
        s.wait_full(0, "opening")
        s.page("Measurement")
        page = s.find("Measurement page")
        s.set_spin(s.find("isovalue", "spin button", root=page), 100)
        s.click(s.find("Measure", "push button", root=page))
        t0 = time.time()
        while True:
            res = s.find_all(lambda n: "isovalue" in n and "area" in n, "label", root=page,
                             visible=True)
            if res:
                break
            check(time.time() - t0 < 60, "no result at the Measure button")
            time.sleep(0.3)
        result = res[0]
        t = s.text(result)
        check("mm²" in t and "mm³" in t and "unknown" not in t, f"result {t!r}")
        # the result is under the button: just below it, on screen
        bx, by, bw, bh = s.extents(s.find("Measure", "push button", root=page))
        rx, ry, rw, rh = s.extents(result)
        check(s.on_screen(result) and 0 <= ry - (by + bh) < 40, "the result is not at the button")
        # a sphere of radius 5 mm: 4/3 pi 125 = 523.6 mm^3
        vol = float(re.search(r"volume ([0-9.e+]+) mm³", t).group(1))
        check(abs(vol - 523.6) / 523.6 < 0.05, f"volume {vol} mm³ of a 5 mm ball")
        print(f"result at the button: {t!r}")


# ---- 9 -----------------------------------------------------------------------------


def defect_9():
    path = head_scene()
    with Session(GUI, [path], OUT) as s:
        s.wait_full(0, "opening")
        s.page("Cut planes")
        page = s.find("Cut planes page")
        s.click(s.find("Add cut plane", "push button", root=page))
        time.sleep(0.5)
        row = s.find(lambda n: n.startswith("global plane 1:"), "label", root=page)
        s.click(row)
        pz = s.find("point z", "spin button", root=page)
        z0 = s.value(pz)
        n = s.n_full()
        s.key("alt+4")
        view = s.find("3-D view")
        s.drag(view, (0.5, 0.5), (0.5, 0.35), steps=10, delay=0.03)
        s.wait_full(n, "the cut-plane drag")
        time.sleep(0.4)
        z1 = s.value(pz)
        check(abs(z1 - z0) > 1, f"the numbers did not follow the handle: z {z0} -> {z1}")
        print(f"handle drag: point z {z0:.2f} -> {z1:.2f} on the page")
        cuts = saved(s, path).get("cut_planes", [])
        check(len(cuts) == 1 and abs(cuts[0]["point"][2] - z1) < 1e-3, f"saved planes {cuts}")
        # below and right of its centre: GTK 4.8 reports a list row's check box a few
        # pixels above and left of where it draws it (the centre of its extents fell on
        # the indicator's corner once the page's title wrapped, issue 66)
        s.click(s.find("global plane 1 on", "check box", root=page), at=(0.7, 0.65))
        time.sleep(0.5)
        check(not saved(s, path).get("cut_planes"), "a plane switched off is still in the World")
        s.click(s.find("global plane 1 on", "check box", root=page), at=(0.7, 0.65))
        time.sleep(0.5)
        check(len(saved(s, path).get("cut_planes", [])) == 1, "switched on: no plane")
        s.click(s.find("remove global plane 1", "push button", root=page))
        time.sleep(0.5)
        check(not saved(s, path).get("cut_planes"), "Remove left the plane")
        check(not s.find_all(lambda n: n.startswith("global plane 1"), "label", root=page,
                             visible=True), "the removed plane is still listed")
        print("cut plane: listed, moved by its handle, off and on, removed")


# ---- 10 ----------------------------------------------------------------------------


class FakeSpacenavd(threading.Thread):
    """spacenavd's protocol v0: eight 32-bit integers an event (type 0: motion
    x y z rx ry rz period); libspnav's protocol request goes unanswered."""

    def __init__(self, path):
        super().__init__(daemon=True)
        self.path = path
        self.srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.srv.bind(path)
        self.srv.listen(1)
        self.conn = None
        self.go = threading.Event()

    def run(self):
        self.srv.settimeout(60)
        try:
            self.conn, _ = self.srv.accept()
        except OSError:
            return
        self.go.wait(120)
        for _ in range(30):  # half a second of a full twist of the cap
            self.conn.sendall(struct.pack("8i", 0, 0, 0, 0, 0, 350, 0, 16))
            time.sleep(1 / 60)
        self.conn.sendall(struct.pack("8i", 0, 0, 0, 0, 0, 0, 0, 16))


def defect_10():
    path = head_scene()
    # $TMPDIR unless it is too long for a socket's path (sun_path: 108 bytes)
    tmp = tempfile.gettempdir()
    sockdir = tempfile.mkdtemp(prefix="vvspnav-", dir=tmp if len(tmp) <= 64 else "/tmp")
    sock = os.path.join(sockdir, "spnav.sock")
    daemon = FakeSpacenavd(sock)
    daemon.start()
    env = {"SPNAV_SOCKET": sock, "VOLVIS_NO_AUTO_DEVICES": "",
           "VOLVIS_DEVICE_DIR": os.path.abspath("share/devices")}
    try:
        with Session(GUI, [path], OUT, env=env) as s:
            s.wait_full(0, "opening")
            t0 = time.time()
            while daemon.conn is None:
                check(time.time() - t0 < 20, "the GUI did not connect to spacenavd at start")
                time.sleep(0.1)
            time.sleep(1)
            first = s.full_png("first.png")
            n = s.n_full()
            daemon.go.set()
            s.wait_full(n, "the 3-D mouse's motion")
            time.sleep(1.5)
            d = ae(s.full_png(), first)
            check(d > 1000, f"the 3-D mouse did not turn the view ({d} pixels differ)")
            print(f"a 3-D mouse present at start turned the view ({d:.0f} pixels differ)")
    finally:
        daemon.srv.close()
        if os.path.exists(sock):
            os.remove(sock)
        os.rmdir(sockdir)


# ---- 11 ----------------------------------------------------------------------------


def defect_11():
    path = head_scene()
    with Session(GUI, [], OUT) as s:
        for name in ("Open…", "Save", "Undo", "Redo", "Menu", "1 view", "4 views"):
            roles = {o.getRoleName() for o in s.find_all(name, visible=True)}
            check(roles & {"push button", "toggle button"}, f"no {name} in the header bar")
        s.find("Open a file…", "push button")  # the start page
        s.app_proc.kill()
        s.app_proc.wait()
        s.launch([path])
        s.wait_full(0, "opening")
        check(not s.title().endswith("*"), f"a file just opened is unsaved: {s.title()!r}")
        # the render window: Close, Escape and Ctrl+W
        for how in ("Close", "Escape", "ctrl+w"):
            s.focus_main()
            s.key("ctrl+r")
            s.xdo("search", "--sync", "--name", "VolVis — render")
            time.sleep(1)
            if how == "Close":
                win = s.find("VolVis — render", "frame", visible=False)
                s.click(s.find("Close", "push button", root=win, visible=False))
            else:
                s.key(how)
            time.sleep(1)
            left = s.xdo("search", "--name", "VolVis — render").split()
            check(not left, f"{how} did not close the render window")
        check(s.app_proc.poll() is None, "closing the render window ended the application")
        # an edit, then Ctrl+Q: the dialog offers Save, which saves and quits
        s.focus_main()
        s.page("Objects")
        s.set_spin(s.find("position x", "spin button"), 10)
        time.sleep(0.3)
        check(s.title().endswith("*"), "an edit did not mark the session unsaved")
        s.key("ctrl+q")
        s.xdo("search", "--sync", "--name", "VolVis: unsaved changes")
        time.sleep(0.5)
        dialog = s.find("VolVis: unsaved changes", visible=False)
        save = s.find(lambda n: n.endswith("Save"), "push button", root=dialog, visible=False)
        s.click(save)
        s.wait_exit(0)
        check(abs(json.load(open(path))["objects"][0]["position"][0] - 10) < 1e-9,
              "Save in the quit dialog did not save")
        print("header bar, start page, a fresh file saved, render window closes three ways, "
              "quit dialog saves")


run(globals()[f"defect_{N}"])
