#!/usr/bin/python3
"""The GUI and the gpu renderer (CTest test_gui_gpu, issue 64): the GUI
picks the gpu renderer on its own only for a real GPU, never for a CPU
device such as Mesa's lavapipe; VOLVIS_GUI_GPU=any lets lavapipe stand in
for a GPU here, and the CT head then opens drawn by gpu (the Rendering
page's method says so, a full frame comes). Without it, on this machine's
lavapipe, the same file opens in raycast. A scene that names gpu where no
Vulkan driver is found (VK_DRIVER_FILES pointing nowhere) is drawn by the
CPU ray caster, and the View page says why.

usage: gpu_session.py GUI CLI OUTDIR
"""
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, run, skip  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)


def method(s):
    s.page("Rendering")
    return s.shown(s.find("method", "combo box"))


def main():
    import subprocess
    devices = json.loads(subprocess.run([CLI, "renderers", "gpu", "--json"], check=True,
                                        capture_output=True, text=True).stdout)
    found = devices.get("gpu_devices", [])
    if not found:
        skip("no Vulkan device: " + devices.get("gpu_unavailable", "?"))
    real = any(not d["cpu"] for d in found)
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")

    scene = os.path.join(OUT, "gpu_scene.json")
    json.dump({"view": {"eye": [0, 600, 0], "at": [0, 0, 0], "up": [0, 0, 1], "fov": 25,
                        "width": 256, "height": 256},
               "render": {"renderer": "gpu"},
               "objects": [{"name": "head", "type": "volume", "file": head,
                            "origin": [-122.0, -122.0, -80.25]}]}, open(scene, "w"))
    # one session (one accessibility bus), the GUI launched three times
    with Session(GUI, [head], OUT, env={"VOLVIS_GUI_GPU": "any"}) as s:
        # picked on its own where a GPU is (lavapipe let stand in for one)
        s.wait_full(0, "opening the CT head")
        got = method(s)
        check(got == "gpu", f"with VOLVIS_GUI_GPU=any the GUI picked {got!r}, not gpu")
        s.page("View")
        check(not any((s.text(o) or "").startswith("the gpu renderer failed")
                      for o in s.find_all(role="label")), "gpu said it failed")
        s.screenshot("gpu_picked.png")
        print(f"picked on its own (lavapipe standing in for a GPU): {got}")
        s.quit()

        # never a CPU device by itself
        s.env.pop("VOLVIS_GUI_GPU", None)
        n = s.n_full()
        s.launch([head])
        s.wait_full(n, "opening the CT head again")
        got = method(s)
        want = "gpu" if real else "raycast"
        check(got == want, f"the GUI picked {got!r} ({'a real GPU' if real else 'lavapipe only'}"
                           f", expected {want})")
        print(f"picked on its own with {'a real GPU' if real else 'lavapipe only'}: {got}")
        s.quit()

        # a scene naming gpu where no driver is found: the CPU ray caster, said
        s.env["VK_DRIVER_FILES"] = "/nonexistent/no_icd.json"
        n = s.n_full()
        s.launch([scene])
        s.wait_full(n, "opening a scene that names gpu")
        s.page("View")
        note = s.find_label(lambda t: t.startswith("the gpu renderer failed"), timeout=30)
        text = s.text(note) or note.name
        check("drawn by the CPU ray caster" in text, f"the note says {text!r}")
        s.screenshot("gpu_fallback.png")
        print(f"fallback said: {text}")
        s.quit()


run(main)
