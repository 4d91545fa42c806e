#!/usr/bin/python3
"""Files (CTest test_gui_files): the raw-import dialog and the DICOM browser.

Raw: a file of 40 x 30 x 20 u16 big-endian voxels after a 64-byte header;
the dialog's live preview and size check follow the description (too short
while the width is wrong; exact once right), and Import adds the volume: a
saved session writes it as NRRD beside the scene, whose voxels equal the
file's. DICOM: a two-series folder written by pydicom with a made-up
patient name (scripts/dicom_testdata.py); the browser lists both series
under "Patient 1" and never shows the name until "Show patient names and
IDs" is on; Open series reads one.

usage: files_session.py GUI CLI OUTDIR
"""
import json
import os
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, run, skip  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
HEAD = os.path.abspath("../shared/data/volumes/ct_head.nrrd")


def labels(s, root):
    return [s.text(o) for o in s.find_all(role="label", root=root)]


def main():
    raw = os.path.join(OUT, "block.raw")
    nx, ny, nz = 40, 30, 20
    with open(raw, "wb") as f:
        f.write(b"H" * 64)
        for k in range(nz):
            for j in range(ny):
                for i in range(nx):
                    f.write(struct.pack(">H", 100 * k + 10 * (j % 10) + i % 10))
    dicom = os.path.join(OUT, "dicom")
    if not os.path.isdir(dicom):
        for series, first in ((1, 40), (2, 60)):
            r = subprocess.run(["/usr/bin/python3", "scripts/dicom_testdata.py", "ct", HEAD,
                                os.path.join(dicom, f"s{series}"), "--first", str(first),
                                "--count", "4", "--crop", "64",
                                "--series-number", str(series)], capture_output=True, text=True)
            if r.returncode != 0:
                skip(f"no DICOM test data (pydicom?): {r.stderr.strip()[-200:]}")
    with Session(GUI, [], OUT, window=(1200, 800)) as s:
        time.sleep(1)
        s.key("ctrl+i")
        s.xdo("search", "--sync", "--name", "VolVis — import raw")
        time.sleep(0.5)
        dlg = s.find("VolVis — import raw", "frame", visible=False)
        status = lambda: " ".join(labels(s, dlg))  # noqa: E731
        s.click(s.find("file", "text", root=dlg, visible=False))
        s.type(raw)
        s.wait_for(lambda: "the file has" in status(), "no size check for 64^3 u8")
        for name, value in (("width (i)", nx), ("height (j)", ny), ("slices (k)", nz),
                            ("header bytes to skip", 64)):
            s.set_spin(s.find(name, "spin button", root=dlg, visible=False), value)
        s.choose(s.find("voxel type", "combo box", root=dlg, visible=False),
                 ["u8", "i8", "u16", "i16", "u32", "i32", "f32", "f64"], "u16")
        s.choose(s.find("byte order", "combo box", root=dlg, visible=False),
                 ["little-endian", "big-endian"], "big-endian")
        s.wait_for(lambda: "exactly the header and the voxels" in status(),
                   f"the size check does not agree: {status()!r}")
        s.screenshot("raw_dialog.png")
        s.click(s.find("Import", "push button", root=dlg, visible=False))
        s.wait_full(0, "the imported volume")
        session = os.path.join(OUT, "raw_session.json")
        s.save_as(session)
        scene = json.load(open(session))
        nrrd = os.path.join(OUT, scene["objects"][0]["file"])
        check(os.path.exists(nrrd), f"no NRRD beside the session: {scene['objects'][0]}")
        probe = subprocess.run([CLI, "slice", session, "--probe", "voxel:7,3,5"],
                               capture_output=True, text=True).stdout.split()
        check(probe and float(probe[1]) == 100 * 5 + 10 * 3 + 7, f"probe {probe}")
        print("raw: described, checked, previewed, imported and saved as NRRD")
        # DICOM: patients hidden unless asked
        s.focus_main()
        s.key("ctrl+d")
        s.xdo("search", "--sync", "--name", "VolVis — DICOM")
        time.sleep(0.5)
        dlg = s.find("VolVis — DICOM", "frame", visible=False)
        s.click(s.find("folder", "text", root=dlg, visible=False))
        s.type(dicom)
        s.key("Return")
        s.wait_for(lambda: "2 series" in " ".join(labels(s, dlg)), "the folder is not listed")
        shown = " ".join(labels(s, dlg))
        check("Patient 1" in shown and "VOLVIS" not in shown and "VV-PHI" not in shown,
              f"names shown unasked: {shown!r}")
        check("Series 1" in shown and "Series 2" in shown, f"series: {shown!r}")
        s.click(s.find("Show patient names and IDs", "check box", root=dlg, visible=False))
        s.wait_for(lambda: "VOLVIS^TEST" in " ".join(labels(s, dlg)), "names not shown when asked")
        s.screenshot("dicom_dialog.png")
        row = s.find_label(lambda n: n.startswith("Series 2:"), root=dlg)
        s.click(row)
        s.click(s.find("Open series", "push button", root=dlg, visible=False))
        s.wait_for(lambda: not s.xdo("search", "--name", "VolVis — DICOM").split(),
                   "Open series did not close the browser")
        check(s.title().endswith("*"), "the second volume did not change the session")
        print("DICOM: two series under Patient 1, names only when asked, series 2 opened")
        s.quit_discard()


run(main)
