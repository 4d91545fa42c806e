#!/usr/bin/env python3
"""Navigator frame rates: the real volvis-gui under Xvfb, a 5 s rotation drag
driven by xdotool, measured from the GUI's frame log (VOLVIS_FRAME_LOG).

usage: bench/bench_navigator.py [--gui PATH] [--cli PATH] [--volume FILE] [--big]
                                [--pyramid STORE [--memory-limit SIZE]]
With --pyramid, only a multiresolution file out of core (issue 29: a 2048^3
drag at >= 20 fps showing data): `volvis-gui STORE` with
VOLVIS_MEMORY_LIMIT=SIZE (default 768M); the representations counted in the
drag are what the frames showed (ray casts of the resident levels, never
boxes).
Prints, per case (ray caster, ray tracer, and with --big a 512^3 volume):
  anchor=volvis op=navigator_drag_fps dataset=... value=... unit=fps
  anchor=volvis op=navigator_drag_max_gap_ms ...
  anchor=volvis op=navigator_refine_ms ...           (last input to the full frame)
  anchor=volvis op=navigator_full_render_ms ...      (the full frame's own render time)
  anchor=volvis op=navigator_gui_overhead_ms ...     (median, renderer's end to paint, drag)
Targets (issue 11): fps >= 30, max gap <= 100 ms, refine <= 150 ms + one full render.
The Animator's Play and issue 28's targets (a 1000 x 800 view, the transfer-function
editor, slice views): bench/bench_gui.py.
"""
import argparse, json, os, statistics, subprocess, sys, tempfile, time

def run_case(gui, scene, name, log_dir, drag_s=5.0):
    log = os.path.join(log_dir, name + ".log")
    if os.path.exists(log):
        os.remove(log)
    env = dict(os.environ, GDK_BACKEND="x11", NO_AT_BRIDGE="1", VOLVIS_FRAME_LOG=log)
    p = subprocess.Popen([gui, scene], env=env, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 120
        while time.time() < deadline:  # wait for the first full frame
            if os.path.exists(log) and " full " in open(log).read():
                break
            time.sleep(0.1)
        else:
            raise SystemExit(f"{name}: no full frame within 60 s")
        wid = subprocess.run(["xdotool", "search", "--sync", "--name", "^VolVis — "],
                             capture_output=True, text=True).stdout.split()[0]
        subprocess.run(["xdotool", "windowmove", wid, "0", "0", "windowsize", wid, "1100", "720"])
        time.sleep(1.0)
        n_before = len(open(log).read().splitlines())
        # a continuous drag: 100 motion events a second, a circle-ish path
        import math
        # one xdotool process: 100 motion events a second for drag_s seconds
        cmd = ["xdotool", "mousemove", "300", "360", "mousedown", "1"]
        for k in range(1, int(drag_s * 100)):
            x = 300 + int(120 * math.sin(k * 0.02))
            y = 360 + int(40 * math.sin(k * 0.013))
            cmd += ["mousemove", str(x), str(y), "sleep", "0.01"]
        cmd += ["mouseup", "1"]
        subprocess.run(cmd)
        time.sleep(4.0 + 0.0)
        lines = open(log).read().splitlines()[n_before:]
    finally:
        subprocess.run(["xdotool", "key", "ctrl+q"])
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
    frames = [l.split() for l in lines]
    frames = [(float(f[0]), f[1], f[2], float(f[3]), float(f[4]), int(f[5]), float(f[6]))
              for f in frames if len(f) >= 7]
    previews = [f for f in frames if f[1] != "full"]
    if len(previews) < 2:
        raise SystemExit(f"{name}: only {len(previews)} preview frames during the drag")
    # the drag: from the first frame after the press to the first frame of the
    # final state (the last input's); after it come the refinement steps
    last_full = max(i for i, f in enumerate(frames) if f[1] == "full")
    final_state = frames[last_full][5]
    end_i = min(i for i, f in enumerate(frames) if f[5] == final_state)
    drag = frames[: end_i + 1]
    t = [f[0] for f in drag]
    gaps = [b - a for a, b in zip(t, t[1:])]
    # frames per second over each second of the drag; the median of those
    start, end = t[0], t[-1]
    per_s = []
    s = start
    while s + 1000 <= end:
        per_s.append(sum(1 for x in t if s <= x < s + 1000))
        s += 1000
    fps = statistics.median(per_s) if per_s else len(t) / max(1e-3, (end - start) / 1000)
    last = drag[-1]
    last_input = last[0] - last[4]  # the final state's first frame was asked for at the last input
    full = frames[last_full]
    refine = full[0] - last_input
    overhead = statistics.median([f[6] for f in drag])
    kinds = {}
    for f in drag:
        kinds[f[1]] = kinds.get(f[1], 0) + 1
    ds = name
    print(f"anchor=volvis op=navigator_drag_fps dataset={ds} value={fps:.1f} unit=fps")
    print(f"anchor=volvis op=navigator_drag_max_gap_ms dataset={ds} value={max(gaps):.1f} unit=ms")
    print(f"anchor=volvis op=navigator_refine_ms dataset={ds} value={refine:.1f} unit=ms")
    print(f"anchor=volvis op=navigator_full_render_ms dataset={ds} value={full[3]:.1f} unit=ms")
    print(f"anchor=volvis op=navigator_gui_overhead_ms dataset={ds} value={overhead:.2f} unit=ms")
    print(f"# {ds}: {len(drag)} frames in {(end - start) / 1000:.2f} s, representations {kinds}; "
          f"refine target {150 + full[3]:.0f} ms", flush=True)

def scene(path, volume, renderer, origin=None):
    obj = {"name": "v", "type": "volume", "file": os.path.abspath(volume), "mode": "composite",
           "step": 0.5}
    with open(path, "w") as f:
        json.dump({"view": {"eye": [0, 700, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
                            "width": 512, "height": 512},
                   "lights": [{"type": "directional", "direction": [0, -1, 0]}],
                   "render": {"renderer": renderer, "quality": 1},
                   "objects": [obj]}, f)

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--gui", default="build/release/apps/volvis-gui/volvis-gui")
    ap.add_argument("--cli", default="build/release/volvis")
    ap.add_argument("--volume", default="../shared/data/volumes/ct_head.nrrd")
    ap.add_argument("--big", action="store_true", help="also a 512^3 volume (128 MiB)")
    ap.add_argument("--pyramid", help="only this multiresolution file, out of core")
    ap.add_argument("--memory-limit", default="768M")
    a = ap.parse_args()
    if not os.environ.get("DISPLAY"):
        os.execvp("xvfb-run", ["xvfb-run", "-a", "-s", "-screen 0 1280x800x24",
                               sys.executable] + sys.argv)
    print(f"# load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}", flush=True)
    d = tempfile.mkdtemp(prefix="bench_navigator_")
    gui = os.path.abspath(a.gui)
    if a.pyramid:
        os.environ["VOLVIS_MEMORY_LIMIT"] = a.memory_limit
        run_case(gui, os.path.abspath(a.pyramid), os.path.basename(a.pyramid.rstrip("/")) +
                 ":out_of_core", d)
        return
    s = os.path.join(d, "raycast.json")
    # the default scene of the volume, as `volvis-gui FILE` opens it
    run_case(gui, os.path.abspath(a.volume), "ct_head.nrrd:raycast", d)
    s = os.path.join(d, "raytrace.json")
    scene(s, a.volume, "raytrace")
    # the head centred like the default scene
    with open(s) as f:
        j = json.load(f)
    j["objects"][0]["origin"] = [-122.0, -122.0, -80.25]
    with open(s, "w") as f:
        json.dump(j, f)
    run_case(gui, s, "ct_head.nrrd:raytrace", d)
    if a.big:
        import numpy as np
        n = 512
        big = os.path.join(d, "sphere512.nrrd")
        z, y, x = np.ogrid[:n, :n, :n]
        r = np.sqrt((x - n / 2) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2)
        vol = np.clip(255 - np.abs(r - n / 3) * 8, 0, 255).astype(np.uint8)
        with open(big, "wb") as f:
            f.write(f"NRRD0004\ntype: uchar\ndimension: 3\nsizes: {n} {n} {n}\n"
                    "encoding: raw\n\n".encode())
            f.write(vol.tobytes())
        del vol, r
        run_case(gui, big, "sphere512.nrrd:raycast", d)

if __name__ == "__main__":
    main()
