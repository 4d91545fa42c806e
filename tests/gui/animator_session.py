#!/usr/bin/python3
"""The Animator page of the real volvis-gui (CTest test_gui_animator), its
controls found by accessible name: on a small scene (the neghip volume) an
orbit is added with the default values and shows on the timeline; Play
shows new frames while it runs and Stop gives back the first image bit for
bit, with nothing unsaved; Render writes animation.mp4 (the default output
in the current folder) with the frame count set on the page, and a PNG
sequence whose frame 3 of 8 is `volvis render --azimuth 135` of the saved
session bit for bit; Save… writes a file that `volvis animate` renders to
the same frames, New empties the animation and Open… brings it back; camera
keys before and after a drag, and a recorded flight of the drag, render
from the first view (exactly) to the dragged one; Cancel stops a long
render; Ctrl+Q exits 0.

usage: animator_session.py GUI CLI OUTDIR
"""
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Failure, Session, ae, check, psnr, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
LANE = (115, 191, 115)  # sequences on the timeline (vvg-animator-page.c)


def find_timeline(s, timeout=60):
    """The Animator's timeline once it has a size inside the window (shown
    the first time it is slow under ASan); a failure says where it was."""
    t0 = time.time()
    resized = t0
    while True:
        if time.time() - resized > 5:  # a window that came back at its own size
            s.xdo("windowsize", s.wid, str(s.window_size[0]), str(s.window_size[1]))
            resized = time.time()
        found = s.find_all("timeline")
        for o in found:
            try:
                x, y, w, h = s.extents(o)
            except Exception:
                continue
            W, H = s.window_size
            if w > 0 and h > 0 and x >= 0 and y >= 0 and x < W and y < H:
                return o
        if time.time() - t0 > timeout:
            where = []
            for o in found:
                try:
                    where.append(s.extents(o))
                except Exception as e:
                    where.append(repr(e))
            raise Failure(f"no timeline inside the window {s.window_size} after {timeout} s "
                          f"({len(found)} found: {where})")
        time.sleep(0.3)
KEY = (242, 209, 77)    # keys


def pngs(folder):
    return sorted(f for f in os.listdir(folder) if f.endswith(".png")) if os.path.isdir(folder) \
        else []


def main():
    for d in ("png", "png2", "cli_png", "cancel", "keys", "flight"):
        shutil.rmtree(os.path.join(OUT, d), ignore_errors=True)
    for f in ("animation.mp4", "saved.json"):
        if os.path.exists(os.path.join(OUT, f)):
            os.remove(os.path.join(OUT, f))
    data = os.path.abspath("../shared/data/volumes")
    session = os.path.join(OUT, "session.json")
    json.dump({"view": {"eye": [0, -220, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 30,
                        "width": 128, "height": 128, "background": [0, 0, 0]},
               "lights": [{"type": "directional", "direction": [0, 1, 0]}],
               "objects": [{"name": "neghip", "type": "volume", "file": f"{data}/neghip.slc",
                            "origin": [-32.5, -32.5, -32.5], "mode": "composite", "step": 0.5,
                            "transfer_function": {
                                "opacity": [[20, 0.0], [60, 0.3], [255, 0.8]],
                                "color": [[20, [0.2, 0.4, 1.0]], [120, [1, 0.8, 0.3]],
                                          [255, [1, 1, 1]]],
                                "opacity_unit_distance": 1.0}}]}, open(session, "w"))
    with Session(GUI, [session], OUT, window=(1000, 1000), cwd=OUT) as s:
        s.wait_full(0, "opening")
        s.key("ctrl+s")  # the session at the view's size: the CLI renders what the GUI shows
        time.sleep(1)
        full0 = s.full_png("full0.png")
        H = s.frames_log()[-1]["h"]
        s.page("Animator")
        page = s.find("Animator page")
        button = lambda name: s.find(name, "push button", root=page)  # noqa: E731
        timeline = find_timeline(s)
        lanes = lambda: s.count_color(timeline, LANE, "lanes.png")  # noqa: E731
        check(lanes() == 0, "the new animation is not empty")
        s.click(button("Add sequence"))  # an orbit of 360 degrees over 60 frames
        s.wait_for(lambda: lanes() > 100, "Add sequence: no sequence on the timeline", timeout=60)
        # Play: previews while it runs; Stop: the first image, nothing unsaved
        n = len(s.frames_log())
        s.click(button("Play"))
        t0 = time.time()
        while True:  # 2 s on a quiet machine; a loaded one (ASan, a test beside) may need more
            time.sleep(0.5)
            played = s.frames_log()[n:]
            previews = [f for f in played if f["kind"] != "full"]
            played_s = time.time() - t0
            if (len(played) >= 10 and len(previews) >= 5) or played_s > 20:
                break
        check(len(played) >= 10 and len(previews) >= 5,
              f"Play showed {len(played)} frames ({len(previews)} previews) in {played_s:.1f} s")
        n = s.n_full()
        s.click(button("Stop"))
        s.wait_full(n, "Stop")
        t0 = time.time()
        while ae(s.full_png(), full0) != 0 and time.time() - t0 < 10:
            time.sleep(0.2)
        check(ae(s.full_png(), full0) == 0, "Stop did not restore the first image")
        check(not s.title().endswith("*"), "Play/Stop left an unsaved change")
        print(f"Play: {len(played)} frames in {played_s:.1f} s; Stop: the first image again, "
              "nothing unsaved")
        # Render: animation.mp4 of 8 frames; a PNG sequence
        frames = s.find("frames", "spin button", root=page)
        output = s.find("output", "text", root=page)
        s.set_spin(frames, 8)
        s.click(button("Render"))
        mp4 = os.path.join(OUT, "animation.mp4")
        t0 = time.time()
        while not os.path.exists(mp4) and time.time() - t0 < 120:
            time.sleep(0.2)
        check(os.path.exists(mp4), "no animation.mp4 from Render")
        time.sleep(0.5)
        nf = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0",
                             "-show_entries", "stream=nb_read_frames", "-of", "csv=p=0", mp4],
                            capture_output=True, text=True).stdout.strip()
        check(nf == "8", f"animation.mp4 has {nf} frames, not 8")
        cli135 = os.path.join(OUT, "cli_135.png")
        subprocess.run([CLI, "render", session, "--azimuth", "135", "-q", "-o", cli135],
                       check=True)

        def render_png(folder, pattern, count=None, timeout=300):
            os.makedirs(os.path.join(OUT, folder), exist_ok=True)
            s.click(output)
            s.key("ctrl+a")
            s.type(os.path.join(OUT, folder, pattern))
            s.click(button("Render"))
            if count is None:
                # the animation's frame count, as its "frames" spin button
                # says: a frame can take longer than any quiet spell under the
                # sanitizers (4 of 11 frames were taken for the whole render)
                try:
                    count = int(round(frames.queryValue().currentValue))
                except Exception:
                    count = None
            last, stable, t0 = -1, 0, time.time()
            while time.time() - t0 < timeout:
                k = len(pngs(os.path.join(OUT, folder)))
                if count is not None and k >= count:
                    time.sleep(0.5)
                    return
                # without a count: done when no frame came for 2 s (with a
                # count, wait for it: a frame may take longer, e.g. under asan)
                stable = stable + 1 if k == last and k > 0 else 0
                if count is None and stable >= 8:
                    return
                last = k
                time.sleep(0.25)
            raise AssertionError(f"the render to {folder} did not finish")

        render_png("png", "f_%03d.png", 8)
        png = os.path.join(OUT, "png")
        check(len(pngs(png)) == 8, f"the PNG sequence has {len(pngs(png))} frames, not 8")
        check(ae(os.path.join(png, "f_003.png"), cli135) == 0,
              "frame 3 differs from volvis render --azimuth 135")
        check(ae(os.path.join(png, "f_000.png"), full0) == 0,
              "frame 0 differs from the GUI's first image")
        print("Render: animation.mp4 of 8 frames; PNG frame 3 = volvis render --azimuth 135")
        # Save…, volvis animate, New, Open…
        saved = os.path.join(OUT, "saved.json")
        s.click(button("Save…"))
        s.chooser_type("^Save animation", saved)
        s.wait_for(lambda: os.path.exists(saved), "Save… wrote no animation file", timeout=60)
        check('"scene": "session.json"' in open(saved).read(), "the file does not name the session")
        os.makedirs(os.path.join(OUT, "cli_png"), exist_ok=True)
        subprocess.run([CLI, "animate", "--animation", saved, "-q", "-o",
                        os.path.join(OUT, "cli_png", "f_%03d.png")], check=True)
        for k in range(8):
            check(ae(os.path.join(OUT, "cli_png", f"f_00{k}.png"),
                     os.path.join(png, f"f_00{k}.png")) == 0,
                  f"volvis animate of the saved file: frame {k} differs")
        s.click(button("New"))
        # the timeline is redrawn after the click: under load, a moment later
        s.wait_for(lambda: lanes() == 0, "New did not empty the animation", timeout=30)
        s.click(button("Open…"))
        s.chooser_type("^Open animation", saved, location=True)
        s.wait_for(lambda: lanes() > 100, "Open…: no sequence on the timeline", timeout=60)
        render_png("png2", "f_%03d.png", 8)
        check(ae(os.path.join(OUT, "png2", "f_005.png"), os.path.join(png, "f_005.png")) == 0,
              "the reopened animation renders differently")
        print("Save…: volvis animate gives the GUI's frames; New and Open… bring it back")
        # camera keys at 0 s and (after a drag) at 1 s
        view = s.find("3-D view")
        vx, vy, vw, vh = s.extents(view)
        D = int(0.5 * vw)
        az = D * 180.0 / H
        cliaz = os.path.join(OUT, "cli_az.png")
        subprocess.run([CLI, "render", session, "--azimuth", repr(az), "-q", "-o", cliaz],
                       check=True)

        def drag_left():
            s.drag(view, (0.75, 0.5), (0.75 - D / vw, 0.5), steps=12, delay=0.02)

        s.click(button("New"))
        # 10 frames a second (11 frames from 0 to 1 s: fewer to render under ASan)
        s.set_spin(s.find("frames per second", "spin button", root=page), 10)
        s.click(button("Add camera key"))
        drag_left()
        time.sleep(0.3)
        s.click(button("Add camera key"))
        s.key("ctrl+z")
        check(s.count_color(timeline, KEY, "keys.png") > 10, "Add camera key: no keys")
        render_png("keys", "f_%03d.png")
        keys = os.path.join(OUT, "keys")
        check(len(pngs(keys)) == 11, f"camera keys at 0 and 1 s: {len(pngs(keys))} frames, not 11")
        check(ae(os.path.join(keys, "f_000.png"), full0) == 0,
              "camera keys: frame 0 is not the first view")
        p = psnr(os.path.join(keys, "f_010.png"), cliaz)
        check(p > 40, f"camera keys: frame 10 at PSNR {p} against --azimuth {az}")
        print(f"Add camera key: 11 frames from the first view to the dragged one ({p} dB)")
        # a recorded flight of the same drag
        record = s.find("Record flight", root=page)
        s.click(record)
        drag_left()
        time.sleep(0.5)
        s.click(record)
        s.key("ctrl+z")
        render_png("flight", "f_%03d.png")
        flight = os.path.join(OUT, "flight")
        fr = pngs(flight)
        check(fr and ae(os.path.join(flight, fr[0]), full0) == 0,
              "flight: frame 0 is not the first view")
        p = psnr(os.path.join(flight, fr[-1]), cliaz)
        check(p > 40, f"flight: the last frame at PSNR {p} against --azimuth {az}")
        print(f"Record flight: {len(fr)} frames to the dragged view ({p} dB)")
        # Cancel stops a long render
        s.set_spin(frames, 3000)
        os.makedirs(os.path.join(OUT, "cancel"), exist_ok=True)
        s.click(output)
        s.key("ctrl+a")
        s.type(os.path.join(OUT, "cancel", "f_%04d.png"))
        s.click(button("Render"))
        # the first frame written, however slow the machine (a sanitizer
        # beside other tests), then Cancel
        for _ in range(600):
            if pngs(os.path.join(OUT, "cancel")):
                break
            time.sleep(0.1)
        s.click(button("Cancel"))
        time.sleep(1)
        c1 = len(pngs(os.path.join(OUT, "cancel")))
        time.sleep(1)
        c2 = len(pngs(os.path.join(OUT, "cancel")))
        check(1 <= c1 < 3000 and c1 == c2, f"Cancel: {c1} then {c2} frames of 3000")
        print(f"Cancel: stopped after {c1} of 3000 frames")
        s.key("ctrl+s")
        time.sleep(0.5)
        s.quit()


run(main)
