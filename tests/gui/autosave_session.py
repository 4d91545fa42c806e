#!/usr/bin/python3
"""Autosave and restore (CTest test_gui_autosave; issue 33): the CT head
opens, the Filtering page makes a mask (a volume of the session) and the
view is turned by a drag; the autosave (1 s after the last edit here,
VOLVIS_AUTOSAVE_DELAY) writes $XDG_STATE_HOME/volvis/session-<pid>-1. The
application is killed (SIGKILL: no chance to clean up); the next start
offers "Restore the last session?", Restore brings the World back, untitled
and unsaved, and its image is identical (AE 0) to the one before the kill;
the old folder goes once the new window's autosave stands. A quit that
discards the unsaved changes leaves no autosave; the same folder put back
as a crash leaves it, Discard removes every autosave and the window stays
empty; a quit without unsaved changes leaves no autosave behind.

usage: autosave_session.py GUI CLI OUTDIR
"""
import glob
import os
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from atspi import Session, ae, check, run  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
os.makedirs(OUT, exist_ok=True)
STATE = os.path.join(OUT, "state")


def autosaved(s):
    log = os.path.join(OUT, "gui.log")
    return [l for l in open(log) if "volvis-gui: autosaved" in l] if os.path.exists(log) else []


def folders():
    return sorted(glob.glob(os.path.join(STATE, "volvis", "session-*")))


def wait_autosave(s, n, what):
    t0 = time.time()
    while len(autosaved(s)) <= n:
        check(time.time() - t0 < 60, f"no autosave after {what}")
        time.sleep(0.2)


def restore_dialog(s, button):
    s.xdo("search", "--sync", "--name", "VolVis — restore")
    time.sleep(0.5)
    d = s.find("VolVis — restore", visible=False)
    s.screenshot(f"restore_dialog_{button.lower()}.png")
    s.click(s.find(lambda n: n.endswith(button), "push button", root=d, visible=False))
    time.sleep(0.5)


def main():
    head = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
    shutil.rmtree(STATE, ignore_errors=True)
    env = {"XDG_STATE_HOME": STATE, "VOLVIS_AUTOSAVE_DELAY": "1"}
    with Session(GUI, [head], OUT, env=env) as s:
        s.wait_full(0, "opening")
        s.page("Filtering")
        page = s.find("Filtering page")
        s.click(s.find(lambda n: n.startswith("adapt the transfer function"), "check box",
                       root=page))
        s.click(s.find("filter chain", "text", root=page))
        s.type("--threshold 300: --largest 1:26")
        n = s.n_full()
        s.click(s.find("Apply", "push button", root=page))
        s.wait_full(n, "the mask")
        a = len(autosaved(s))
        n = s.n_full()
        s.drag(s.find("3-D view"), (0.6, 0.5), (0.45, 0.45), steps=10)
        s.wait_full(n, "the turned view")
        wait_autosave(s, a, "the drag")
        time.sleep(1.5)  # a later frame of the same state would be the same image
        before = s.full_png("before.png")
        first = folders()
        check(len(first) == 1 and os.path.exists(os.path.join(first[0], "session.json")),
              f"no autosave folder with a session: {first}")
        print(f"autosaved: {os.path.basename(first[0])}: {sorted(os.listdir(first[0]))}")

        s.app_proc.kill()
        s.app_proc.wait()
        s.launch([])
        n = s.n_full()
        restore_dialog(s, "Restore")
        s.wait_full(n, "the restored session")
        time.sleep(1.5)
        after = s.full_png("after.png")
        d = ae(before, after)
        check(d == 0, f"the restored World renders differently: AE {d}")
        check(s.title().endswith("untitled *"), f"restored, not untitled and unsaved: {s.title()!r}")
        t0 = time.time()
        while first[0] in folders() and time.time() - t0 < 30:
            time.sleep(0.2)
        now = folders()
        check(first[0] not in now and len(now) == 1,
              f"the old autosave stays, or no new one: {now}")
        print(f"restored: AE 0; {os.path.basename(now[0])} replaces {os.path.basename(first[0])}")

        # a quit that discards the unsaved changes leaves no autosave either
        # (the user chose; nothing is offered at the next start)
        aside = os.path.join(OUT, "crashed-copy")
        shutil.rmtree(aside, ignore_errors=True)
        shutil.copytree(now[0], aside)
        pid = s.app_proc.pid
        s.quit_discard()
        check(folders() == [], f"a quit without saving left autosaves: {folders()}")
        print("quit without saving: no autosave left")
        # the same folder as a crash leaves it (its process gone): Discard
        shutil.copytree(aside, os.path.join(STATE, "volvis", f"session-{pid}-1"))
        s.launch([])
        restore_dialog(s, "Discard")
        check(folders() == [], f"Discard left autosaves: {folders()}")
        check(s.title().startswith("VolVis — untitled") and not s.title().endswith("*"),
              f"Discard changed the World: {s.title()!r}")
        s.find("Open a file…", "push button")  # the start page of an empty World
        s.quit()
        check(folders() == [], f"a quit left autosaves: {folders()}")
        print("discard: no autosave left; quit: none either")


run(main)
