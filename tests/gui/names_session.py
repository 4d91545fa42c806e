#!/usr/bin/python3
"""Every control has an accessible name (CTest test_gui_names): on every
side-bar page, in the header bar, the slice views, the raw-import dialog
and the DICOM browser, each spin button, check box, drop-down, button and
entry is named by its visible label (GTK's labelled-by relation), never by
its class ("GtkSpinButton"), so that a screen reader and these tests tell
them apart. Names of one kind are distinct within a page where they share a
row label (the object list's rows are numbered).

usage: names_session.py GUI CLI OUTDIR
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, check, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
CONTROLS = {"spin button", "check box", "combo box", "push button", "toggle button", "text",
            "slider", "radio button"}
PAGES = ["Objects", "Transfer function", "View", "Lights", "Cut planes", "Rendering",
         "Measurement", "Modeling", "Filtering", "Animator", "Input devices"]


def unnamed(s, root):
    bad, n = [], 0
    for o in s.walk(root):
        try:
            role = o.getRoleName()
        except Exception:
            continue
        if role not in CONTROLS:
            continue
        n += 1
        name = o.name or ""
        if not name.strip() or name.startswith("Gtk") or name.startswith("Vv"):
            p = o.parent
            bad.append(f"{role} {name!r} in {p.getRoleName() if p else '?'} "
                       f"{(p.name if p else '')!r}")
    return n, bad


def main():
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
    with Session(GUI, [head], OUT, window=(1300, 900)) as s:
        s.wait_full(0, "opening")
        total, bad = 0, []
        for page in PAGES:
            s.page(page)
            n, b = unnamed(s, s.find(f"{page} page"))
            total += n
            bad += [f"{page}: {x}" for x in b]
            check(n > 0, f"{page}: no controls found")
        # the 4-up layout's slice views
        s.click(s.find("4 views"))
        time.sleep(1)
        for axis in ("axial", "coronal", "sagittal"):
            s.find(f"orientation of the {axis} view", "combo box")
            s.find_label(lambda n, a=axis: n.startswith(f"{a}:"))
        # the header bar and the whole window
        n, b = unnamed(s, s.app())
        bad += [f"window: {x}" for x in b]
        # the raw-import dialog and the DICOM browser
        for keys, title in (("ctrl+i", "VolVis — import raw"), ("ctrl+d", "VolVis — DICOM")):
            s.key(keys)  # File → Import raw…, Browse DICOM…
            s.xdo("search", "--sync", "--name", title)
            time.sleep(0.8)
            # the dialog's own tree (the main window's was walked above)
            n, b = unnamed(s, s.find(title, visible=False))
            check(n > 0, f"{title}: no controls found")
            bad += [f"{title}: {x}" for x in b]
            s.key("Escape")
            time.sleep(0.5)
        check(not bad, f"{len(bad)} controls without a name:\n  " + "\n  ".join(sorted(set(bad))))
        print(f"{total} controls on {len(PAGES)} pages, the header bar, the slice views and two "
              "dialogs: every one named")
        s.quit()


run(main)
