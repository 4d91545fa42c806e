#!/usr/bin/python3
"""The views at a scale factor of 2 (CTest test_gui_hidpi).

GTK runs at GDK_SCALE=2 on the CT head in the four-view layout; its widgets'
extents (AT-SPI, logical pixels) are taken times 2 into the screen's pixels
(tests/gui/atspi.py). Checks that:

- the 3-D view's full-quality frame (the frame log) has the view's size in
  device pixels, twice its logical size, not its logical size upscaled;
- each slice view samples its slice (the slice log) at more than 1.5 times
  its logical width and height;
- a drag still previews (reduced casts) and ends on a full frame of the same
  device-pixel size.

usage: hidpi_session.py GUI CLI OUTDIR
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]


def main():
    os.makedirs(OUT, exist_ok=True)
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
    slog = os.path.join(OUT, "slices.log")
    if os.path.exists(slog):
        os.remove(slog)
    env = {"GDK_SCALE": "2", "VOLVIS_SLICE_LOG": slog}
    with Session(GUI, [head], OUT, env=env, size=(2400, 1700), window=(2200, 1500)) as s:
        s.wait_full(0, "opening", timeout=120)
        view = s.find("3-D view")
        _, _, vw, vh = s.extents(view)  # screen (device) pixels
        full = [f for f in s.frames_log() if f["kind"] == "full"][-1]
        check((full["w"], full["h"]) == (vw, vh),
              f"the full frame is {full['w']}x{full['h']}, the view {vw}x{vh} device pixels")
        print(f"3-D view: {vw // 2}x{vh // 2} logical, full frame {full['w']}x{full['h']}")
        # a drag: previews, then a full frame at device pixels again
        n0, nf = len(s.frames_log()), s.n_full()
        s.drag(view, (0.5, 0.5), (0.7, 0.55), steps=20)
        s.wait_full(nf, "the drag")
        frames = s.frames_log()[n0:]
        kinds = {f["kind"] for f in frames}
        check(any(k.startswith("raycast_") for k in kinds), f"no reduced cast in the drag: {kinds}")
        last = [f for f in frames if f["kind"] == "full"][-1]
        check((last["w"], last["h"]) == (vw, vh),
              f"after the drag the full frame is {last['w']}x{last['h']}, not {vw}x{vh}")
        print(f"drag: {len(frames)} frames {sorted(kinds)}; full {last['w']}x{last['h']}")
        # the slice views sample at device pixels
        s.click(s.find("4 views"))
        time.sleep(2)
        for axis in ("axial", "coronal", "sagittal"):
            _, _, w, h = s.extents(s.find(f"{axis} view"))
            rows = [line.split() for line in open(slog)] if os.path.exists(slog) else []
            rows = [r for r in rows if r[1] == axis]
            check(rows, f"the {axis} view sampled no slice")
            sw, sh = (int(v) for v in rows[-1][2].split("x"))
            check(sw > 1.5 * (w // 2) and sh > 1.5 * (h // 2),
                  f"the {axis} view ({w // 2}x{h // 2} logical) sampled {sw}x{sh}")
            print(f"{axis}: {w // 2}x{h // 2} logical, sampled {sw}x{sh}")
        s.quit_discard()
    print("hidpi session: ok")


if __name__ == "__main__":
    main()
