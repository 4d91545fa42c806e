#!/usr/bin/python3
"""The screenshots of docs/gui.md: the real volvis-gui on the CT head under
Xvfb, its pages found by accessible name over AT-SPI (tests/gui/atspi.py).

usage: scripts/gui_screenshots.py GUI OUT_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "gui"))
from atspi import Session  # noqa: E402

GUI, OUT = sys.argv[1], sys.argv[2]
W, H = 1400, 900


def shot(s, name):
    tmp = s.screenshot("root.png")
    dst = os.path.join(OUT, f"gui_{name}.png")
    subprocess.run(["convert", tmp, "-crop", f"{W}x{H}+0+0", "+repage", dst], check=True)
    print("wrote", dst)


def main():
    os.makedirs(OUT, exist_ok=True)
    work = tempfile.mkdtemp(prefix="gui_screenshots_")
    head = os.path.abspath(os.path.join(HERE, "..", "..", "shared", "data", "volumes",
                                        "ct_head.nrrd"))
    with Session(GUI, [], work, window=(W, H)) as s:
        time.sleep(2)
        shot(s, "start")
        s.app_proc.kill()
        s.app_proc.wait()
        s.launch([head])
        s.wait_full(0, "opening")
        time.sleep(1)
        s.wait_full(s.n_full() - 1)
        shot(s, "objects")
        s.page("Transfer function")
        s.click(s.find("ct-bone", "push button"))
        s.wait_full(s.n_full() - 1)
        time.sleep(8)  # the thumbnails
        editor = s.find("transfer function editor")
        x, y, w, h = s.extents(editor)
        s.xdo("mousemove", str(x + int(0.62 * w)), str(y + h // 3))
        time.sleep(0.5)
        shot(s, "transfer_function")
        s.click(s.find("4 views"))
        time.sleep(1)
        axial = s.find("axial view")
        s.click(axial, at=(0.45, 0.5))
        s.wait_full(s.n_full() - 1)
        time.sleep(1)
        shot(s, "four_up")
        s.click(s.find("1 view"))
        s.page("Cut planes")
        s.click(s.find("Add cut plane", "push button"))
        s.click(s.find(lambda n: n.startswith("global plane 1:"), "label"))
        s.set_spin(s.find("normal y", "spin button"), 0.6)
        s.key("alt+4")
        s.wait_full(s.n_full() - 1)
        time.sleep(1)
        shot(s, "cut_planes")
        s.key("alt+1")
        for page, name in (("View", "view"), ("Lights", "lights"), ("Rendering", "rendering"),
                           ("Modeling", "modeling"), ("Filtering", "filtering"),
                           ("Animator", "animator"), ("Input devices", "devices")):
            s.page(page)
            time.sleep(0.8)
            shot(s, name)
        s.page("Measurement")
        page = s.find("Measurement page")
        s.set_spin(s.find("isovalue", "spin button", root=page), 400)
        s.click(s.find("Measure", "push button", root=page))
        t0 = time.time()
        while not s.find_all(lambda n: "area" in n, "label", root=page, visible=True):
            if time.time() - t0 > 120:
                break
            time.sleep(0.5)
        shot(s, "measurement")
        s.key("ctrl+r")
        s.xdo("search", "--sync", "--name", "VolVis — render")
        time.sleep(6)
        shot(s, "render_window")
        s.key("Escape")
        s.app_proc.kill()
        s.app_proc.wait()
    shutil.rmtree(work, ignore_errors=True)


main()
