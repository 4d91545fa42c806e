#!/usr/bin/python3
"""The slice views of the four-up layout (CTest test_gui_slices).

A click in the axial view moves the linked cursor: the readout of every view
names the same point, and its voxel value equals `volvis slice --probe` of
the saved session at that world position (the library's probe); the wheel
over the axial view steps one slice a notch (the voxel index k changes by
one, i and j stay); a right-button drag changes window and level (the axial
image changes, the World does not), and the Transfer function page's window
and level rows follow it; a window typed there changes the image again, not
the World; an oblique view follows the selected
cut plane; `volvis slice` of the saved session writes the axial slice.

usage: slices_session.py GUI CLI OUTDIR
"""
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Failure, Session, check, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
NUM = r"(-?[0-9.]+(?:e[-+]?[0-9]+)?)"
READ = re.compile(rf"value {NUM} at voxel \({NUM}, {NUM}, {NUM}\), \({NUM}, {NUM}, {NUM}\)")


def readout(s, axis):
    t = s.text(s.find_label(lambda n: n.startswith(f"{axis}:")))
    m = READ.search(t)
    check(m, f"{axis} readout {t!r}")
    return [float(x) for x in m.groups()], t


def main():
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
    with Session(GUI, [head], OUT, window=(1400, 900)) as s:
        s.wait_full(0, "opening")
        s.click(s.find("4 views"))
        time.sleep(1.5)
        axial = s.find("axial view")
        s.click(axial, at=(0.37, 0.58))
        time.sleep(0.5)
        (v, i, j, k, x, y, z), text = readout(s, "axial")
        for other in ("coronal", "sagittal"):
            o, _ = readout(s, other)
            check(all(abs(a - b) <= 1e-4 * (1 + abs(a)) for a, b in zip(o[4:], (x, y, z))),
                  f"the {other} view's cursor {o[4:]} is not the axial one's {(x, y, z)}")
        session = os.path.join(OUT, "session.json")
        s.save_as(session)
        r = subprocess.run([CLI, "slice", session, "--probe", f"{x!r},{y!r},{z!r}"],
                           capture_output=True, text=True)
        check(r.returncode == 0, f"volvis slice --probe: {r.stderr}")
        cli = float(r.stdout.split()[1])
        check(abs(cli - v) <= 1e-3 * (1 + abs(v)), f"GUI {v} != volvis slice --probe {cli}")
        print(f"cursor {text!r}; volvis slice --probe: {cli}")
        # the wheel: one slice a notch
        s.focus_main()
        s.click(axial, at=(0.37, 0.58))  # the pointer over the view again after the dialog
        time.sleep(0.5)
        (v, i, j, k, x, y, z), text = readout(s, "axial")
        for attempt in range(2):  # a wheel event X may lose is sent again
            s.wheel(axial, down=3)
            try:
                s.wait_for(lambda: abs(readout(s, "axial")[0][3] - k) > 0.5, "no scroll", 6)
                break
            except Failure:
                check(attempt == 0, "the wheel did not scroll the axial view")
        time.sleep(0.5)
        (v2, i2, j2, k2, *_), _ = readout(s, "axial")
        check(abs(abs(k2 - k) - 3) < 1e-6 and abs(i2 - i) < 1e-6 and abs(j2 - j) < 1e-6,
              f"three notches: voxel ({i}, {j}, {k}) -> ({i2}, {j2}, {k2})")
        print(f"wheel: slice k {k:g} -> {k2:g}")
        # window and level: the image changes, the World does not; the
        # Transfer function page's rows show them and take typed ones
        s.page("Transfer function")
        win0 = s.value(s.find("window", "spin button"))
        lev0 = s.value(s.find("level", "spin button"))
        before = s.screenshot("wl_before.png")
        state = s.frames_log()[-1]["state"]
        s.drag(axial, (0.5, 0.5), (0.8, 0.3), steps=8, button=3)
        time.sleep(0.5)
        after = s.screenshot("wl_after.png")
        ax, ay, aw, ah = s.extents(axial)
        crop = f"{aw}x{ah}+{ax}+{ay}"

        def changed(a, b):
            return float(subprocess.run(["compare", "-metric", "AE", "-extract", crop, a, b,
                                         "null:"], capture_output=True, text=True).stderr.split()[0])
        d = changed(before, after)
        check(d > 100, f"window/level drag changed {d} pixels of the axial view")
        check(s.frames_log()[-1]["state"] == state, "window/level changed the World")
        win1 = s.value(s.find("window", "spin button"))
        lev1 = s.value(s.find("level", "spin button"))
        check(win1 > win0 * 1.2 and lev1 != lev0,
              f"the page's window/level {win0:g}/{lev0:g} -> {win1:g}/{lev1:g} after the drag")
        s.set_spin(s.find("window", "spin button"), round(win0 / 4, 2))
        time.sleep(0.5)
        typed = s.screenshot("wl_typed.png")
        d = changed(after, typed)
        check(d > 100, f"a typed window changed {d} pixels of the axial view")
        check(s.frames_log()[-1]["state"] == state, "a typed window changed the World")
        print(f"window/level: automatic {win0:g}/{lev0:g}, dragged {win1:g}/{lev1:g}, "
              f"typed window {win0 / 4:g}")
        # an oblique view follows the selected cut plane
        s.page("Cut planes")
        s.click(s.find("Add cut plane", "push button"))
        time.sleep(0.5)
        s.click(s.find(lambda n: n.startswith("global plane 1:"), "label"))
        s.set_spin(s.find("normal y", "spin button"), 0.7)
        orient = s.find("orientation of the sagittal view", "combo box")
        s.choose(orient, ["axial", "coronal", "sagittal", "oblique (cut plane)"],
                 "oblique (cut plane)")
        time.sleep(1)
        t = s.text(s.find_label(lambda n: n.startswith("oblique:")))
        check(t.startswith("oblique: value"), f"oblique readout {t!r}")
        s.screenshot("four_up.png")
        # the CLI writes the axial slice of the saved session
        png = os.path.join(OUT, "cli_axial.png")
        subprocess.run([CLI, "slice", session, "--axis", "axial", "--at", f"{x},{y},{z}", "-q",
                        "-o", png], check=True)
        check(os.path.getsize(png) > 1000, "volvis slice wrote no image")
        print("window/level, oblique view, volvis slice: fine")
        s.key("ctrl+q")
        time.sleep(1)
        if s.app_proc.poll() is None:  # unsaved changes: close without saving
            s.click(s.find(lambda n: n.endswith("Close without saving"), "push button"))
        s.wait_exit(0)


run(main)
