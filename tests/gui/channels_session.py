#!/usr/bin/python3
"""Channels and time steps in the GUI (CTest test_gui_channels).

An OME-TIFF written by tifffile (3 channels named and coloured in its OME
metadata, 3 time steps, a ball per channel at its own place, moving from
step to step) opens as one object of three channels:

- the Channels and time page lists them by name with the file's colours;
  the saved session names them, and `volvis render` of it gives the GUI's
  full-quality frame bit for bit;
- hiding a channel takes its colour out of the image and the slice view
  (counted on screen), Ctrl+Z brings it back; the blend rule and a contrast
  slider change the saved session ("blend", the channel's transfer
  function);
- the time-step slider shows step 2: the session says "time": 2 and
  `volvis render` of it (reading step 2 of the file itself) gives the GUI's
  frame bit for bit; Play advances the step shown and Pause stops it;
- the Animator's "Add time-step key" at step 0 (0 s) and step 2 (1 s) makes
  a linear objects[0].time track of 2 keys; rendered at one frame a
  second, its frame 1 is `volvis render` of the session at step 2, bit for
  bit;
- "edit TF" of a channel makes the Transfer function page edit that
  channel's function (it says which).

usage: channels_session.py GUI CLI OUTDIR
"""
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, ae, check  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
SKIP = 77

try:
    import numpy as np
    import tifffile
except ImportError as e:
    print(f"skipped: {e} (python3-numpy, python3-tifffile)")
    sys.exit(SKIP)

NAMES = ["nuclei", "membrane", "protein"]
RGB = [(255, 0, 0), (0, 255, 0), (0, 0, 255)]  # OME Color: RGBA as a signed 32-bit integer


def ome_color(rgb):
    v = (rgb[0] << 24) | (rgb[1] << 16) | (rgb[2] << 8) | 255
    return v - (1 << 32) if v >= 1 << 31 else v


def write_stack(path):
    T, C, Z, Y, X = 3, 3, 24, 24, 24
    z, y, x = np.mgrid[0:Z, 0:Y, 0:X]
    data = np.zeros((T, C, Z, Y, X), np.uint16)
    for t in range(T):
        for c in range(C):
            cx, cy, cz = 5 + 7 * c, 8 + 4 * t, 12
            data[t, c][(x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2 <= 16] = 3000 + 500 * c
    tifffile.imwrite(path, data, metadata={
        "axes": "TCZYX", "Channel": {"Name": NAMES, "Color": [ome_color(c) for c in RGB]}})


def saved(s, name):
    path = os.path.join(OUT, name)
    s.save_as(path)
    s.focus_main()
    with open(path) as f:
        return path, json.load(f)


def cli_render(scene, out):
    subprocess.run([CLI, "render", scene, "-q", "-o", out], check=True)
    return out


def volume_entry(scene):
    objs = [o for o in scene["objects"] if o.get("type") == "volume"]
    check(len(objs) == 1, f"{len(objs)} volume objects in the session")
    return objs[0]


def main():
    stack = os.path.join(OUT, "cells.ome.tif")
    write_stack(stack)
    with Session(GUI, [stack], OUT, window=(1400, 900)) as s:
        s.wait_full(0, "opening")
        s.page("Channels and time")
        for n in NAMES:
            s.find(f"show {n}")
            s.find(f"colour of {n}")
        path, scene = saved(s, "session0.json")
        vol = volume_entry(scene)
        check([c.get("name") for c in vol.get("channels", [])] == NAMES,
              f"channels {vol.get('channels')}")
        check(ae(s.full_png("full0.png"), cli_render(path, os.path.join(OUT, "cli0.png"))) == 0,
              "the saved session does not render to the GUI's image")

        # hide "nuclei" (red): the red ball goes, Ctrl+Z brings it back
        n = s.n_full()
        s.click(s.find("show nuclei"))
        s.wait_full(n, "hiding a channel")
        path, scene = saved(s, "session_hidden.json")
        check(volume_entry(scene)["channels"][0].get("visible") is False, "nuclei still visible")
        hidden = s.full_png("full_hidden.png")
        check(ae(hidden, cli_render(path, os.path.join(OUT, "cli_hidden.png"))) == 0,
              "the session with a hidden channel does not render to the GUI's image")
        check(ae(hidden, os.path.join(OUT, "full0.png")) > 0, "hiding nuclei changed nothing")
        n = s.n_full()
        s.key("ctrl+z")
        s.wait_full(n, "undo")
        check(ae(s.full_png("full_undone.png"), os.path.join(OUT, "full0.png")) == 0,
              "Ctrl+Z did not show nuclei again (the first image)")

        # blend rule and a contrast limit
        n = s.n_full()
        s.choose(s.find("channel blend", "combo box"), ["composite", "additive", "maximum"], "maximum")
        s.wait_full(n, "the blend rule")
        lo = s.find("lower contrast limit of protein")
        before = s.value(lo)
        s.click(lo)
        s.key("Home")
        s.key("Page_Up")
        time.sleep(0.5)
        after = s.value(lo)
        check(after != before, f"the lower limit of protein stayed {before}")
        path, scene = saved(s, "session_blend.json")
        vol = volume_entry(scene)
        check(vol.get("blend") == "maximum", f"blend {vol.get('blend')}")
        pts = vol["channels"][2]["transfer_function"]["opacity"]
        check(abs(pts[0][0] - after) < 1e-6, f"protein's opacity starts at {pts[0]}, not {after}")
        print(f"blend maximum; protein's lower limit {before} -> {after}")

        # time: step 2 by the slider's keys, as `volvis render` reads it
        s.page("Channels and time")
        ts = s.find("time step", role="slider")
        s.click(ts)
        s.key("Home")
        s.key("Right")
        s.key("Right")
        s.wait_for(lambda: s.value(ts) == 2, "the time slider at 2")
        shown = s.find_label(lambda n: n.startswith("step ") and " of " in n)
        s.wait_for(lambda: s.text(shown) == "step 3 of 3", "step 2 shown")
        time.sleep(1.0)
        n = s.n_full()
        s.wait_full(n - 1, "step 2")
        path, scene = saved(s, "session_t2.json")
        check(volume_entry(scene).get("time") == 2, f"time {volume_entry(scene).get('time')}")
        time.sleep(1.0)
        check(ae(s.full_png("full_t2.png"), cli_render(path, os.path.join(OUT, "cli_t2.png")))
              == 0, "the session at step 2 does not render to the GUI's image")
        label = s.find_label(lambda n: n.startswith("step ") and " of " in n)
        check("step 3 of 3" in s.text(label), f"label {s.text(label)!r}")
        play = s.find("Play time steps")
        s.click(play)
        s.wait_for(lambda: "step 3 of 3" not in s.text(label), "Play did not advance", 10)
        s.click(play)  # Pause
        time.sleep(0.5)
        stopped = s.text(label)
        time.sleep(0.8)
        check(s.text(label) == stopped, "Pause did not stop the time steps")
        print(f"time: step 2 saved and rendered alike; play then pause at {stopped!r}")

        # the Animator's time-step keys: step 0 at 0 s, step 2 at 1 s
        def to_step(key, step):
            s.page("Channels and time")
            slider = s.find("time step", role="slider")
            s.click(slider)
            s.key(key)
            s.wait_for(lambda: s.value(slider) == step, f"the time slider at {step}")
            # the step is read off the interface's thread: shown when the label says so
            lab = s.find_label(lambda n: n.startswith("step ") and " of " in n)
            s.wait_for(lambda: s.text(lab) == f"step {step + 1} of 3", f"step {step} shown")

        to_step("Home", 0)
        s.page("Animator")
        apage = s.find("Animator page")
        s.click(s.find("Add time-step key", root=apage))
        to_step("End", 2)  # as session_t2.json was saved
        s.page("Animator")
        s.click(s.find("Add time-step key", root=apage))
        track = s.find_label(lambda n: n.startswith("objects[0].time"))
        check(s.text(track) == "objects[0].time (linear): 2 keys at 0, 1 s",
              f"the Animator's track reads {s.text(track)!r}")
        s.set_spin(s.find("frames per second", "spin button", root=apage), 1)
        frames = os.path.join(OUT, "anim_time")
        os.makedirs(frames, exist_ok=True)
        s.click(s.find("output", "text", root=apage))
        s.key("ctrl+a")
        s.type(os.path.join(frames, "f_%03d.png"))
        s.click(s.find("Render", "push button", root=apage))
        f1 = os.path.join(frames, "f_001.png")
        s.wait_for(lambda: os.path.exists(f1) and os.path.getsize(f1) > 0, "frame 1", 180)
        time.sleep(1.0)
        check(ae(f1, os.path.join(OUT, "cli_t2.png")) == 0,
              "the Animator's frame 1 (step 2) does not render as the session at step 2")
        check(ae(os.path.join(frames, "f_000.png"), f1) > 0, "frames 0 and 1 (steps 0, 2) alike")
        to_step("Home", 0)
        print("Animator: a time track of 2 keys; frame 1 is step 2")

        # the slice view blends the channels in their colours
        s.click(s.find("4 views"))
        time.sleep(2.0)
        axial = s.find("axial view")
        # at step 0 again (Play went round): each ball's centre is its channel's
        # colour at full contrast; the hidden-then-restored nuclei too
        found = [s.count_color(axial, rgb, f"axial_{i}.png") for i, rgb in enumerate(RGB)]
        check(all(f > 0 for f in found), f"axial view: pure red, green, blue pixels {found}")
        print(f"axial view: pure red, green, blue pixels {found}")

        # "edit TF" of membrane: the Transfer function page edits it
        s.click(s.find("1 view"))
        s.page("Channels and time")
        s.click(s.find("edit transfer function of membrane"))
        s.page("Transfer function")
        t = s.text(s.find_label(lambda n: n.startswith("Editing channel")))
        check('"membrane"' in t, f"the Transfer function page says {t!r}")
        s.quit_discard()
    print("channels session: ok")


if __name__ == "__main__":
    main()
