#!/usr/bin/python3
"""File > Open URL… opens off the UI thread (CTest test_gui_url).

The CT head converted to OME-Zarr by `volvis convert` is served from a
loopback Python server (http_common.drip_server) in two ways, as a person
meets them:

- A server that does not answer (every request held until the test lets it
  go): Open URL… of it shows "Opening URL…" over the views with a spinner and
  Cancel; Cancel takes the line away at once, and Open URL… is offered again
  (the menu's item is sensitive; while an open is pending it is not: one at a
  time);
  when the server then answers, the open that was cancelled ends on its
  worker and its World is dropped (the GUI's log says so): the document is as
  it was (nothing open: no object in the object list, the title unchanged,
  no frame drawn).
- An address the server does not have (404): the usual error dialog, its
  one line naming the store.
- A server that answers every request 2 s late: while the open is pending,
  the GUI answers (the "Opening URL…" line is read over AT-SPI, the menu
  opens and lists its items within a few seconds, while the line is still
  shown: a GUI whose UI thread is in the door answers nothing until the door
  returns); once it lands, the line is gone, the store is the open object
  (the object list names it "head"; a full frame of it is drawn and is not
  empty).
- Quitting while an open is pending (a server that does not answer) ends
  the program at once with status 0.

usage: url_session.py GUI CLI OUTDIR
"""
import os
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "io"))
from atspi import Session, check, run  # noqa: E402
from http_common import drip_server  # noqa: E402

GUI, CLI, OUT = sys.argv[1:4]
OUT = os.path.abspath(OUT)
os.makedirs(OUT, exist_ok=True)
HEAD = os.path.abspath("../shared/data/volumes/ct_head.nrrd")
DELAY = 2.0  # seconds each request of the slow server waits


def make_store():
    store = os.path.join(OUT, "www", "head.ome.zarr")
    if not os.path.isdir(store):
        os.makedirs(os.path.dirname(store), exist_ok=True)
        subprocess.run([CLI, "convert", HEAD, store, "--quiet"], check=True)
    return store


def opening_line(s):
    """The "Opening URL…" label over the views while it is on screen, else None."""
    for o in s.walk():
        try:
            if (o.getRoleName() == "label" and (o.name or "").startswith("Opening http")
                    and s.extents(o)[2] > 0):
                return o
        except Exception:
            continue
    return None


def start_open(s, url):
    """Ctrl+Shift+O (File > Open URL…), the URL typed into the dialog's entry, Enter."""
    s.type_url(url)
    s.key("Return")


def sensitive(item):
    import pyatspi
    return item.getState().contains(pyatspi.STATE_SENSITIVE)


def log(s):
    return open(os.path.join(s.out, "gui.log")).read()


def main():
    store = make_store()
    gate, gate2, srv2 = threading.Event(), threading.Event(), None
    srv, drip = drip_server(os.path.dirname(store), piece=65536, pause=0, delay=DELAY, gate=gate)
    url = f"http://127.0.0.1:{srv.server_address[1]}/{os.path.basename(store)}"
    try:
        with Session(GUI, [], OUT, window=(1100, 720)) as s:
            s.app()
            s.find("Open a file…", "push button", timeout=60)
            title0, n0 = s.title(), s.n_full()

            # 1. a server that does not answer: Cancel
            start_open(s, url)
            t0 = time.time()
            s.wait_for(lambda: opening_line(s) is not None, "no \"Opening URL…\" line", 30)
            line = opening_line(s)
            print(f"pending after {time.time() - t0:.1f} s: {line.name!r} "
                  f"({line.description!r})")
            check(url in line.name, f"the line does not name the URL: {line.name!r}")
            s.wait_for(lambda: drip.held > 0, "the GUI asked the server nothing", 30)
            s.screenshot("url_opening.png")
            s.click(s.find("Cancel opening", "push button", timeout=10))
            s.wait_for(lambda: opening_line(s) is None, "the line stays after Cancel", 10)
            check("opening cancelled" in log(s), "the GUI's log does not say it cancelled")
            # the server answers now: the cancelled open ends, and its World is dropped
            gate.set()
            s.wait_for(lambda: "was cancelled; its result is dropped" in log(s),
                       "the cancelled open never ended", 120)
            time.sleep(1)  # anything installed by mistake would be drawn and named now
            check(s.title() == title0, f"the title changed: {s.title()!r} (was {title0!r})")
            check(s.n_full() == n0, f"a frame was drawn after Cancel ({s.n_full()} > {n0})")
            check(not s.find_all("name of object 1", "text"), "an object was added")
            s.focus_main()
            s.click(s.find("Menu"))
            check(sensitive(s.find("Open URL…", timeout=20, visible=False)),
                  "Open URL… is not offered again after Cancel")
            s.key("Escape")
            print(f"cancelled: {drip.held} requests held, then answered and dropped; "
                  f"the document as it was ({title0!r})")

            # 2. an address that cannot be read: the usual error dialog, one line naming it
            missing = url.replace("head.ome.zarr", "missing.ome.zarr")
            start_open(s, missing)
            s.xdo("search", "--sync", "--name", "VolVis: error")
            s.wait_for(lambda: opening_line(s) is None, "the line stays after the error", 10)
            time.sleep(0.5)
            s.screenshot("url_error.png")
            texts = [s.text(o) for o in s.find_all(role="label")]
            said = [t for t in texts if "missing.ome.zarr" in t and "\n" not in t.strip()]
            print(f"the error of {missing}: {said}")
            check(any(missing in t or "missing.ome.zarr:" in t for t in said),
                  f"the error dialog does not name the URL: {texts}")
            s.key("Escape")
            s.wait_for(lambda: not s.xdo("search", "--name", "VolVis: error").split(),
                       "the error dialog stays", 10)
            check(not s.find_all("name of object 1", "text"), "an object was added")

            # 3. a server that answers 2 s late: the GUI answers meanwhile
            logged = len(log(s))
            start_open(s, url)
            s.wait_for(lambda: opening_line(s) is not None, "no \"Opening URL…\" line", 30)
            s.screenshot("url_pending.png")
            t0 = time.time()
            s.click(s.find("Menu"))
            item = s.find("Open URL…", timeout=20, visible=False)
            took = time.time() - t0
            check(not sensitive(item), "Open URL… is offered while an open is pending")
            s.key("Escape")
            still = opening_line(s) is not None
            print(f"the menu answered in {took:.1f} s while the open was pending ({still})")
            check(still, "the open ended before the menu was tried (the server is too fast)")
            check(took < 5, f"the menu took {took:.1f} s while the URL opened")
            s.wait_for(lambda: opening_line(s) is None, "the open never ended", 180)
            s.wait_full(n0, "opening the URL")
            check("Cannot open" not in log(s)[logged:], f"the open failed:\n{log(s)[logged:]}")
            name = s.find("name of object 1", "text", timeout=20)
            check(s.text(name) == "head", f"the object list names {s.text(name)!r}, not head")
            shot = s.full_png(copy_to="url_opened.png")
            s.screenshot("url_window.png")
            r = subprocess.run(["convert", shot, "-colorspace", "gray", "-format",
                                "%[fx:standard_deviation]", "info:"], capture_output=True,
                               text=True)
            sd = float(r.stdout or 0)
            print(f"opened: {s.title()!r}; its frame's grey standard deviation {sd:.3f}; "
                  f"served {drip.requests} requests")
            check(sd > 0.02, f"the frame of the URL is empty (standard deviation {sd})")

            # 4. quitting while an open is pending (a server that does not answer): the
            # window goes at once and the program ends with status 0
            srv2, _ = drip_server(os.path.dirname(store), gate=gate2)
            start_open(s, f"http://127.0.0.1:{srv2.server_address[1]}/head.ome.zarr")
            s.wait_for(lambda: opening_line(s) is not None, "no \"Opening URL…\" line", 30)
            s.quit_discard() if "*" in s.title() else s.quit()
            print("quit while an open was pending: exit 0")
    finally:
        gate.set()
        gate2.set()
        for x in (srv, srv2):
            if x:
                x.shutdown()
                x.server_close()


run(main)
