#!/usr/bin/python3
"""The real volvis-gui, found by accessible names over AT-SPI, driven by real
X input (xdotool) at the widgets' extents (CTest test_gui_session).

A volume opens and its image is not blank; a file just opened is not
"unsaved"; a drag to the left turns the head left by exactly the drag's
angle (180 degrees a view height): the GUI's final frame equals `volvis
render --azimuth` of the saved session bit for bit; Ctrl+Z restores the
image bit for bit; dragging a point of the transfer-function editor changes
the image; Ctrl+S then `volvis render` gives the GUI's pixels; drags of the
light (Alt+3) and of the cut plane (Alt+4) change the image and still save
to the CLI's pixels; a final render window opens (Ctrl+R) and Ctrl+Q during
a render exits 0 at once; a bad file shows an error dialog that does not
send the user to the CLI's --raw, offers the raw import, and the
application keeps running.

usage: gui_session.py GUI CLI OUTDIR
"""
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, ae, check, psnr, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
DATA = os.path.abspath("../shared/data/volumes")


def head_scene(path, extra=None):
    scene = {
        "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
                 "width": 512, "height": 512, "background": [0, 0, 0]},
        "lights": [{"type": "directional", "direction": [0, -1, 0], "color": [1, 1, 1],
                    "intensity": 1.0}],
        "cut_planes": [{"point": [0, 0, 50], "normal": [0, 0, -1]}],
        "objects": [{
            "name": "head", "type": "volume", "file": f"{DATA}/ct_head.nrrd",
            "origin": [-122.0, -122.0, -80.25], "mode": "composite", "step": 0.5,
            "transfer_function": {
                "opacity": [[-600, 0.0], [-300, 0.015], [-150, 0.0], [250, 0.0], [500, 0.3],
                            [1500, 0.8]],
                "color": [[-600, [0.9, 0.6, 0.5]], [250, [1, 0.93, 0.8]], [1500, [1, 1, 1]]],
                "opacity_unit_distance": 0.957}}]}
    if extra:
        scene.update(extra)
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)


def cli_render(scene, out, *args):
    subprocess.run([CLI, "render", scene, "-q", "-o", out] + list(args), check=True)
    return out


def main():
    session = os.path.join(OUT, "session.json")
    head_scene(session)
    with Session(GUI, [session], OUT) as s:
        s.wait_full(0, "opening")
        s.screenshot("open.png")
        mean = float(subprocess.run(["convert", s.full_png(), "-format", "%[fx:mean]", "info:"],
                                    capture_output=True, text=True).stdout)
        check(mean > 0.02, f"the opened volume looks blank (mean {mean})")
        check(not s.title().endswith("*"), f"a file just opened is unsaved: {s.title()!r}")
        # save at the view's size: the CLI then renders what the GUI shows
        s.key("ctrl+s")
        time.sleep(1)
        full0 = s.full_png("full0.png")
        check(ae(full0, cli_render(session, os.path.join(OUT, "cli0.png"))) == 0,
              "the saved session does not render to the GUI's first image")
        view = s.find("3-D view")
        H = s.frames_log()[-1]["h"]
        # a drag to the left of D pixels: D * 180 / H degrees of azimuth
        x, y, w, h = s.extents(view)
        D = 96
        n = s.n_full()
        s.drag(view, (0.6, 0.5), (0.6 - D / w, 0.5), steps=12)
        s.wait_full(n, "the drag")
        drag = s.full_png("full_drag.png")
        az = D * 180.0 / H
        p = psnr(drag, cli_render(session, os.path.join(OUT, "cli_az.png"), "--azimuth", str(az)))
        pw = psnr(drag, cli_render(session, os.path.join(OUT, "cli_wrong.png"), "--azimuth",
                                   str(-az)))
        check(p > 40, f"drag left: PSNR {p} against --azimuth {az}")
        print(f"drag: PSNR {p} against the CLI at azimuth {az:.4g}, {pw} against {-az:.4g}")
        n = s.n_full()
        s.key("ctrl+z")
        s.wait_full(n, "undo")
        check(ae(s.full_png(), full0) == 0, "undo did not restore the image")
        print("undo: identical")

        # a point of the transfer-function editor, dragged up
        s.page("Transfer function")
        editor = s.find("transfer function editor")
        n = s.n_full()
        s.drag(editor, (0.75, 0.85), (0.75, 0.35), steps=16)
        s.wait_full(n, "the transfer-function drag")
        tf = s.full_png("full_tf.png")
        check(ae(tf, full0) > 0, "dragging a transfer-function point did not change the image")
        s.key("ctrl+s")
        time.sleep(1)
        check(ae(cli_render(session, os.path.join(OUT, "cli_saved.png")), tf) == 0,
              "the CLI render of the saved session differs from the GUI")
        print("transfer function edited, saved: the CLI gives the GUI's pixels")

        # the light (Alt+3) and the cut plane (Alt+4)
        n = s.n_full()
        s.key("alt+3")
        s.drag(view, (0.5, 0.5), (0.7, 0.5), steps=8, delay=0.03)
        s.wait_full(n, "the light drag")
        light = s.full_png("full_light.png")
        check(ae(light, tf) > 0, "dragging the light did not change the image")
        n = s.n_full()
        s.key("alt+4")
        s.drag(view, (0.5, 0.3), (0.5, 0.4), steps=8, delay=0.03)
        s.wait_full(n, "the cut-plane drag")
        cut = s.full_png("full_cut.png")
        check(ae(cut, light) > 0, "dragging the cut plane did not change the image")
        s.key("alt+1")
        s.key("ctrl+s")
        time.sleep(1)
        check(ae(cli_render(session, os.path.join(OUT, "cli_saved2.png")), cut) == 0,
              "after the light and cut-plane drags the CLI differs from the GUI")
        print("light and cut-plane drags: saved and rendered by the CLI to the GUI's pixels")

        # a final render window; Ctrl+Q while a second one renders
        s.key("ctrl+r")
        s.xdo("search", "--sync", "--name", "VolVis — render")
        time.sleep(1.5)
        s.screenshot("render_window.png")
        s.key("ctrl+r")
        time.sleep(0.05)
        t0 = time.time()
        s.quit()
        check(time.time() - t0 < 5, f"quitting during a render took {time.time() - t0:.1f} s")
        print("quit during a final render: exit 0")

        # a bad file: an error dialog without the CLI's --raw, offering the raw import
        bad = os.path.join(OUT, "bad.nrrd")
        with open(bad, "w") as f:
            f.write("NRRD0004\ntype: short\ndimension: 3\nsizes: 100000 100000 100000\n"
                    "encoding: raw\n\n")
        junk = os.path.join(OUT, "junk.bin")
        with open(junk, "wb") as f:
            f.write(bytes(range(256)) * 64)
        s.launch([bad])
        s.xdo("search", "--sync", "--name", "VolVis: error")
        time.sleep(0.5)
        s.screenshot("error.png")
        check(s.app_proc.poll() is None, "the application died on a bad file")
        s.key("Escape")
        time.sleep(0.3)
        check(s.title().startswith("VolVis — untitled"), "the main window is gone or not empty")
        s.find("Open a file…", "push button")  # the start page of an empty World
        # a file of no known format
        s.app_proc.kill()
        s.app_proc.wait()
        s.launch([junk])
        s.xdo("search", "--sync", "--name", "VolVis: error")
        time.sleep(0.5)
        texts = " ".join(s.text(o) for o in s.find_all(role="label"))
        check("--raw" not in texts, "the error dialog sends the user to the CLI's --raw")
        s.click(s.find(lambda n: n.endswith("Import as raw…"), "push button"))
        s.xdo("search", "--sync", "--name", "VolVis — import raw")
        time.sleep(0.5)
        s.screenshot("raw_dialog.png")
        s.key("Escape")
        time.sleep(0.3)
        s.quit()
        print("bad file: error dialog, raw import offered, still running, exit 0")

        # a NRRD reader that aborts in the sandbox (injected): the error
        # dialog names it, the GUI lives on, the World renders as before
        s.env = dict(s.env, VOLVIS_SANDBOX_INJECT="abort")
        n = s.n_full()
        s.launch([os.path.join(DATA, "nut.slc")])  # SLC: read in-process
        s.wait_full(n, "opening nut.slc")
        before = s.full_png("sandbox_before.png")
        s.focus_main()  # Open… (the shared file is only read: never _save_dialog here)
        s.key("ctrl+o")
        s.chooser_type("Open volume, mesh or scene", os.path.join(DATA, "ct_head.nrrd"),
                       location=True)
        s.xdo("search", "--sync", "--name", "VolVis: error")
        time.sleep(0.5)
        s.screenshot("sandbox_error.png")
        texts = " ".join(s.text(o) for o in s.find_all(role="label"))
        check("the NRRD reader crashed (SIGABRT)" in texts,
              f"the error dialog does not name the crash: {texts!r}")
        check(s.app_proc.poll() is None, "the application died with its reader")
        s.key("Escape")
        time.sleep(0.3)
        time.sleep(1)
        check(ae(s.full_png("sandbox_after.png"), before) == 0,
              "the view changed after the reader crashed")
        # the objects' names are the texts of their editable entries
        names = []
        for o in s.find_all(role="text"):
            try:
                names.append(s.text(o))
            except Exception:
                pass
        check("nut" in names, f"the World lost its volume: {names}")
        check(not [n for n in names if "ct_head" in n],
              f"an object of the file that failed is in the World: {names}")
        s.quit()
        print("a reader crash in the sandbox: the error dialog, the World unchanged, exit 0")


run(main)
