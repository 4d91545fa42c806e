#!/usr/bin/python3
"""A GUI session for ThreadSanitizer (scripts/tsan.sh; not a CTest test).

The CT head opens; the 3-D view is dragged again and again, some drags
back to back (previews are cancelled and replaced while a refinement
renders), some waited out (the final frame is drawn); the wheel zooms; a
point of the transfer-function editor is dragged; the window is closed
(Ctrl+W, Close without saving) during a refinement: the render thread is
cancelled and joined, and prints its counts of frames. The
session only drives the GUI: scripts/tsan.sh counts ThreadSanitizer's
reports in the logs. Prints the frames shown, by kind.

usage: tsan_session.py GUI OUTDIR [short]
  short: one drag and quit (the injected-race check)
"""
import collections
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, run  # noqa: E402

GUI, OUT = sys.argv[1:3]
SHORT = len(sys.argv) > 3 and sys.argv[3] == "short"
os.makedirs(OUT, exist_ok=True)
DATA = os.path.abspath("../shared/data/volumes")
SLOW = 900  # seconds: everything is 5 to 15 times slower under TSan


def main():
    scene = os.path.join(OUT, "head.json")
    json.dump({
        "view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
                 "width": 400, "height": 400},
        "lights": [{"type": "directional", "direction": [0, -1, 0]}],
        "objects": [{"name": "head", "type": "volume", "file": f"{DATA}/ct_head.nrrd",
                     "origin": [-122.0, -122.0, -80.25], "mode": "composite", "step": 0.25,
                     "transfer_function": {
                         "opacity": [[-600, 0.0], [-300, 0.015], [-150, 0.0], [250, 0.0],
                                     [500, 0.3], [1500, 0.8]],
                         "color": [[-600, [0.9, 0.6, 0.5]], [250, [1, 0.93, 0.8]],
                                   [1500, [1, 1, 1]]]}}]}, open(scene, "w"))
    # G_SLICE: GLib 2.74 keeps freed GObjects in its own magazines, which
    # TSan would see as one object's memory reused by the next without a free
    env = {"G_SLICE": "always-malloc"}
    with Session(GUI, [scene], OUT, env=env) as s:
        t0 = time.time()
        while s.n_full() == 0:  # a file that does not open shows an error dialog
            check(not s.xdo("search", "--name", "VolVis: error").strip(),
                  "the volume did not open (an error dialog: see gui.log)")
            check(time.time() - t0 < SLOW, "no full frame after opening")
            check(s.app_proc.poll() is None, "the application died opening the volume")
            time.sleep(0.5)
        view = s.find("3-D view")
        n = s.n_full()
        s.drag(view, (0.6, 0.5), (0.4, 0.55), steps=16, delay=0.01)
        if SHORT:
            s.wait_full(n, "the drag", timeout=SLOW)
        else:
            s.wait_full(n, "the first drag", timeout=SLOW)
            # back to back: each drag's previews replace the last, whose
            # refinement is cancelled
            for i in range(6):
                a, b = (0.3, 0.7) if i % 2 == 0 else (0.7, 0.3)
                s.drag(view, (a, 0.4 + 0.05 * i), (b, 0.5), steps=12, delay=0.01,
                       button=1 if i < 4 else 3)
            n = s.n_full()
            s.wait_full(n - 1, "the drags", timeout=SLOW)
            s.wheel(view, down=2)
            s.wait_full(s.n_full() - 1, "the zoom", timeout=SLOW)
            # a refinement interrupted by a drag in the middle of it
            n = s.n_full()
            s.drag(view, (0.5, 0.5), (0.55, 0.45), steps=6, delay=0.01)
            time.sleep(1.0)
            s.drag(view, (0.55, 0.45), (0.5, 0.5), steps=6, delay=0.01)
            s.wait_full(n, "the interrupted refinement", timeout=SLOW)
            # the transfer function
            s.page("Transfer function")
            editor = s.find("transfer function editor")
            n = s.n_full()
            s.drag(editor, (0.75, 0.85), (0.75, 0.35), steps=16)
            s.wait_full(n, "the transfer-function drag", timeout=SLOW)
        # closed while a refinement renders (a full frame takes seconds at
        # this step under TSan)
        s.drag(view, (0.4, 0.5), (0.6, 0.5), steps=8, delay=0.01)
        time.sleep(0.3)
        # Ctrl+W, not Ctrl+Q: the closed window is destroyed, so the scene
        # view is disposed and joins its render thread (Ctrl+Q leaves the
        # thread to exit())
        # and quickly: "Close _without saving" by its mnemonic (a walk of the
        # accessible tree takes seconds under TSan)
        t0 = time.time()
        s.focus_main()
        s.key("ctrl+w")
        dialog = s.xdo("search", "--sync", "--name", "VolVis: unsaved changes").split()[0]
        s.xdo("windowfocus", dialog)
        time.sleep(0.2)
        s.key("alt+w")
        st = s.app_proc.wait(120)
        check(st in (0, 66), f"exit status {st} (0, or TSan's 66 after a report)")
        print(f"closed {time.time() - t0:.1f} s after the last drag's refinement was asked for")
        with open(os.path.join(OUT, "gui.log"), errors="replace") as f:
            check("volvis-gui: render thread:" in f.read(),
                  "the scene view's render thread was not stopped and joined")
        kinds = collections.Counter(f["kind"] for f in s.frames_log())
        states = len({f["state"] for f in s.frames_log()})
        check(kinds["full"] >= 1, "no full frame was shown")
        print(f"frames shown: {sum(kinds.values())} ({dict(kinds)}), {states} states of the World")


run(main)
