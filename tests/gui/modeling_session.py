#!/usr/bin/python3
"""The Modeling page with real input (CTest test_gui_modeling): a voxelized
sphere of size 100 at the origin, a box of size 100 at x = 50, then the CSG
difference sphere - box. The box covers the right half of the view; after
the difference (its operands hidden) only the left hemisphere is left, so
the right half of the final frame turns to background.

usage: modeling_session.py GUI CLI OUTDIR
"""
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)


def half_mean(png, right):
    r = subprocess.run(["convert", png, "-gravity", "east" if right else "west", "-crop",
                        "50%x100%+0+0", "+repage", "-format", "%[fx:mean]", "info:"],
                       capture_output=True, text=True)
    return float(r.stdout)


MODELS = ["sphere", "box", "torus", "cylinder", "cone", "mesh file"]
OPS = ["union", "intersection", "difference (A - B)"]


def main():
    with Session(GUI, [], OUT, window=(1100, 900)) as s:
        s.page("Modeling")
        page = s.find("Modeling page")
        add = s.find("Add", "push button", root=page)
        s.click(add)  # a sphere by default
        s.wait_full(0, "adding a sphere")
        n = s.n_full()
        s.set_spin(s.find("position x", "spin button", root=page), 50)
        s.choose(s.find("model", "combo box", root=page), MODELS, "box")
        s.click(add)
        s.wait_full(n, "adding a box")
        both = s.full_png("both.png")
        right_both = half_mean(both, True)
        n = s.n_full()
        s.choose(s.find("operation", "combo box", root=page), OPS, "difference (A - B)")
        s.click(s.find("Combine", "push button", root=page))
        s.wait_full(n, "the CSG difference")
        t0 = time.time()
        while half_mean(s.full_png(), True) >= 0.02 and time.time() - t0 < 20:
            time.sleep(0.3)  # the operands are hidden in a second change
        right_csg, left_csg = half_mean(s.full_png(), True), half_mean(s.full_png(), False)
        s.screenshot("csg.png")
        print(f"right half: {right_both} with the box, {right_csg} after sphere - box; "
              f"left half {left_csg}")
        check(right_both > 0.2, f"the box does not show ({right_both})")
        check(right_csg < 0.02, f"the difference left the right half ({right_csg})")
        check(left_csg > 0.1, f"the hemisphere is missing ({left_csg})")
        s.quit_discard()


run(main)
