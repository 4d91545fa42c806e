#!/usr/bin/python3
"""The channels of a store out of core in the GUI (CTest test_gui_channelsooc, issue 89).

A 3-channel OME-Zarr pyramid written by zarr-python (c, z, y, x; three levels; chunks of
one channel x 16^3; omero names, colours and windows; a blob per channel at its own
place) is opened with VOLVIS_MEMORY_LIMIT=8M, so that its level 0 (2.8 MiB of voxels, a
channel, 4 MiB in all: more than a quarter of the budget) is read out of core: one object of three channels
whose nodes hold every channel. The View page's cache line says the frame converged and
how many chunks were read:

- the Channels and time page lists the three channels by name, and the saved session
  renders (`volvis render SESSION --memory-limit 8M`) as the GUI draws it (>= 30 dB);
- hiding a channel redraws from what the cache holds: the cache line's count of chunks
  read does not move, and the channel's colour leaves the image; so does a contrast
  slider moved (the frame changes, no chunk is read again);
- the session with the hidden channel renders as the GUI draws it.

usage: channels_ooc_session.py GUI CLI OUTDIR
"""
import json
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, psnr, skip  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
NAMES = ["nuclei", "membrane", "protein"]
COLORS = ["FF0000", "00FF00", "0000FF"]


def write_store(path):
    try:
        import numpy as np
        import zarr
    except ImportError as e:
        skip(f"zarr-python or numpy missing: {e}")
    Z, Y, X = 64, 96, 112
    zz, yy, xx = np.mgrid[0:Z, 0:Y, 0:X].astype(np.float32)
    chans = []
    for c, (cz, cy, cx) in enumerate([(22, 34, 34), (40, 56, 70), (32, 44, 86)]):
        b = 3000 * np.exp(-((zz - cz) ** 2 + (yy - cy) ** 2 + (xx - cx) ** 2) / (180 + 120 * c))
        chans.append(b.astype(np.uint16) + (np.arange(b.size) % 37).reshape(b.shape).astype(
            np.uint16))
    lv = np.stack(chans)
    store = zarr.DirectoryStore(path, dimension_separator="/")
    g = zarr.open_group(store, mode="w")
    ds = []
    for k in range(3):
        g.create_dataset(str(k), data=lv, chunks=(1, 16, 16, 16), dimension_separator="/")
        f = 2.0 ** k
        ds.append({"path": str(k), "coordinateTransformations": [
            {"type": "scale", "scale": [1.0, 0.5 * f, 0.5 * f, 0.5 * f]},
            {"type": "translation", "translation": [0.0] + [0.25 * (f - 1)] * 3}]})
        s = [d // 2 * 2 for d in lv.shape[1:]]
        lv = np.rint(lv[:, :s[0], :s[1], :s[2]].astype(np.float64).reshape(
            3, s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(2, 4, 6))).astype(np.uint16)
    g.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": "c", "type": "channel"}] + [
        {"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"], "datasets": ds}]
    g.attrs["omero"] = {"channels": [
        {"label": n, "color": c, "active": True,
         "window": {"min": 0, "max": 4000, "start": 80, "end": 2600}}
        for n, c in zip(NAMES, COLORS)]}


def cache_line(s):
    s.page("View")
    return s.text(s.find_label(lambda n: n.startswith("out of core:"), timeout=30))


def chunks_read(line):
    m = re.search(r"(\d+) chunks read", line)
    check(m is not None, f"the cache line names no chunks read: {line!r}")
    return int(m.group(1))


def converged(s, what):
    s.page("View")
    s.wait_for(lambda: "converged" in cache_line(s), f"{what}: never converged: "
               f"{cache_line(s)!r}", timeout=120)
    time.sleep(1.0)
    return cache_line(s)


def same_as_cli(s, shot, name):
    session = os.path.join(OUT, f"{name}.json")
    s.save_as(session)
    s.focus_main()
    png = os.path.join(OUT, f"{name}_cli.png")
    r = subprocess.run([CLI, "render", session, "--memory-limit", "8M", "-o", png],
                       capture_output=True, text=True)
    check(r.returncode == 0, f"volvis render of {name}: {r.stderr.strip()}")
    q = psnr(shot, png)
    print(f"{name}: the GUI's frame against volvis render of the session: {q:.1f} dB")
    check(q >= 30, f"{name}: the GUI's frame is not the CLI's ({q:.1f} dB)")
    with open(session) as f:
        return json.load(f)


def colour_share(png, k):
    """The share of channel k's colour (R, G or B) in the image's light."""
    from PIL import Image
    import numpy as np
    a = np.asarray(Image.open(png).convert("RGB"), dtype=np.float64)
    tot = a.sum()
    return a[..., k].sum() / tot if tot > 0 else 0.0


def main():
    store = os.path.join(OUT, "cells.ome.zarr")
    write_store(store)
    with Session(GUI, [store], OUT, env={"VOLVIS_MEMORY_LIMIT": "8M"},
                 window=(1200, 800)) as s:
        s.wait_full(0, "opening the store")
        line = converged(s, "opening")
        print(f"converged: {line!r}")
        check("of 8 MiB" in line, f"the cache line does not name the limit: {line!r}")
        n0 = chunks_read(line)
        check(n0 > 0, f"no chunk read: {line!r}")
        s.page("Channels and time")
        for n in NAMES:
            s.find(f"show {n}")
        shot0 = s.full_png(copy_to="full0.png")
        scene = same_as_cli(s, shot0, "session0")
        objs = [o for o in scene["objects"] if o.get("type") == "volume"]
        check(len(objs) == 1 and [c.get("name") for c in objs[0].get("channels", [])] == NAMES,
              f"one object of the three channels ({[o.get('channels') for o in objs]})")

        # hide "nuclei" (red): redrawn from the cache, no chunk read again
        s.page("Channels and time")
        n = s.n_full()
        s.click(s.find("show nuclei"))
        s.wait_full(n, "hiding a channel")
        line = converged(s, "hidden")
        print(f"hidden: {line!r}")
        hidden = s.full_png(copy_to="full_hidden.png")
        red0, red1 = colour_share(shot0, 0), colour_share(hidden, 0)
        print(f"red share of the light {red0:.3f} -> {red1:.3f}")
        check(red1 < 0.5 * red0, f"hiding nuclei left its red ({red0:.3f} -> {red1:.3f})")
        check(chunks_read(line) == n0,
              f"hiding a channel read chunks again ({n0} -> {chunks_read(line)}: {line!r})")
        same_as_cli(s, hidden, "session_hidden")

        # a contrast slider: the frame changes, no chunk read again
        s.page("Channels and time")
        lo = s.find("lower contrast limit of protein")
        before = s.value(lo)
        n = s.n_full()
        s.click(lo)
        s.key("End")
        s.wait_full(n, "the contrast of protein")
        line = converged(s, "contrast")
        check(s.value(lo) != before, f"the lower limit of protein stayed {before}")
        moved = s.full_png(copy_to="full_contrast.png")
        check(psnr(hidden, moved) < 60, "moving protein's contrast changed nothing")
        check(chunks_read(line) == n0,
              f"a contrast change read chunks again ({n0} -> {chunks_read(line)}: {line!r})")
        print(f"contrast: {before} -> {s.value(lo)}; chunks read {chunks_read(line)}")


if __name__ == "__main__":
    main()
