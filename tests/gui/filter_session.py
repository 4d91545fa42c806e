#!/usr/bin/python3
"""The Filtering page with real input (CTest test_gui_filter): the CT head
opens; the chain "--threshold 300: --largest 1:26" typed on the page and
applied (with "adapt the transfer function" on) gives a u8 mask (the log
line the page writes says so) and a different, non-blank image without the
head holder; Save volume as… (Ctrl+Shift+E) writes the mask as .nii.gz
with the voxels and affine of `volvis filter`'s (read by nibabel), and a
name no format writes is an error dialog with no file; undo restores the
first image exactly; a chain built with "Add
step" (--median 1) applies too; a bad chain shows an error dialog and the
application keeps running; Ctrl+Q, Close without saving, exit 0.

usage: filter_session.py GUI CLI OUTDIR
"""
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, ae, check, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)


def filtered_lines(s):
    return [l for l in open(os.path.join(OUT, "gui.log")) if "volvis-gui: filtered" in l]


def wait_filtered(s, n, what):
    t0 = time.time()
    while len(filtered_lines(s)) <= n:
        check(time.time() - t0 < 120, f"no filter result after {what}")
        time.sleep(0.1)
    return filtered_lines(s)[-1]


def edges_mean(png):
    """Mean of the outer quarters (left and right), where the head holder shows."""
    vals = []
    for g in ("west", "east"):
        r = subprocess.run(["convert", png, "-gravity", g, "-crop", "25%x100%+0+0", "+repage",
                            "-format", "%[fx:mean]", "info:"], capture_output=True, text=True)
        vals.append(float(r.stdout))
    return sum(vals) / 2


def main():
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
    with Session(GUI, [head], OUT) as s:
        s.wait_full(0, "opening")
        time.sleep(1)
        full0 = s.full_png("full0.png")
        s.page("Filtering")
        page = s.find("Filtering page")
        chain = s.find("filter chain", "text", root=page)
        apply = s.find("Apply", "push button", root=page)
        s.click(s.find(lambda n: n.startswith("adapt the transfer function"), "check box",
                       root=page))
        n, f = s.n_full(), len(filtered_lines(s))
        s.click(chain)
        s.type("--threshold 300: --largest 1:26")
        s.click(apply)
        line = wait_filtered(s, f, "Apply")
        s.wait_full(n, "the filtered volume")
        check("256 x 256 x 108 u8, values 0..1" in line, f"not a u8 mask of the head: {line}")
        time.sleep(1)
        bone = s.full_png("bone.png")
        check(ae(bone, full0) > 0, "filtering did not change the image")
        mean = float(subprocess.run(["convert", bone, "-format", "%[fx:mean]", "info:"],
                                    capture_output=True, text=True).stdout)
        check(mean > 0.02, f"the filtered volume looks blank (mean {mean})")
        e0, e1 = edges_mean(full0), edges_mean(bone)
        check(e1 < 0.5 * e0, f"the head holder is still there ({e0} -> {e1})")
        print(f"filtered: mean {mean}; outer quarters {e0} before, {e1} after")
        # Save volume as…: the mask, as the CLI's filter writes it, read by nibabel
        mask = os.path.join(OUT, "mask.nii.gz")
        s.save_volume_as(mask)
        cli_mask = os.path.join(OUT, "cli_mask.nii.gz")
        subprocess.run([CLI, "filter", head, cli_mask, "--threshold", "300:", "--largest",
                        "1:26", "--quiet"], check=True)
        import nibabel as nib
        import numpy as np
        a, b = nib.load(mask), nib.load(cli_mask)
        va, vb = np.asanyarray(a.dataobj), np.asanyarray(b.dataobj)
        check(va.dtype == np.uint8 and va.shape == (256, 256, 108) and
              np.array_equal(va, vb) and np.allclose(a.affine, b.affine) and
              set(np.unique(va)) == {0, 1},
              f"Save volume as: {va.dtype} {va.shape} mask differs from volvis filter's")
        print(f"save volume as: mask.nii.gz = volvis filter's ({int(va.sum())} voxels set)")
        # a name no format writes: an error dialog, no file, still running
        bad = os.path.join(OUT, "mask.foo")
        s.save_volume_as(bad, expect_file=False)
        s.xdo("search", "--sync", "--name", "VolVis: error")
        time.sleep(0.3)
        s.screenshot("save_volume_error.png")
        check(not os.path.exists(bad) and s.app_proc.poll() is None,
              "Save volume as mask.foo: a file, or the application died")
        s.key("Escape")
        time.sleep(0.3)
        s.focus_main()
        n = s.n_full()
        s.key("ctrl+z")
        s.wait_full(n, "undo")
        t0 = time.time()
        while ae(s.full_png(), full0) != 0 and time.time() - t0 < 6:
            time.sleep(0.2)
        check(ae(s.full_png(), full0) == 0, "undo did not restore the image")
        print("undo: identical")
        # a chain built with Add step: median 1
        s.click(s.find("Clear", "push button", root=page))
        which = s.find("filter", "combo box", root=page)
        s.click(which)  # the list opens on the first filter; the median is the second
        time.sleep(0.4)
        s.key("Down")
        s.key("Return")
        time.sleep(0.3)
        check(s.shown(which) == "median", f"the second filter is {s.shown(which)!r}")

        s.click(s.find("argument", "text", root=page))
        s.type("1")
        s.click(s.find("Add step", "push button", root=page))
        f = len(filtered_lines(s))
        s.click(apply)
        line = wait_filtered(s, f, "Apply (median)")
        check("--median 1 -> 256 x 256 x 108 i16" in line, f"Add step: {line}")
        print("add step: --median 1 applied")
        # a bad chain: an error dialog, the application keeps running
        s.click(s.find("Clear", "push button", root=page))
        s.click(chain)
        s.type("--median x")
        s.click(apply)
        s.xdo("search", "--sync", "--name", "VolVis: error")
        time.sleep(0.3)
        s.screenshot("error.png")
        check(s.app_proc.poll() is None, "the application died on a bad chain")
        s.key("Escape")
        time.sleep(0.3)
        print("bad chain: error dialog, still running")
        s.quit_discard()


run(main)
