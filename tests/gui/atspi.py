"""Driving the real volvis-gui by accessible names and roles (AT-SPI), the way
a screen reader finds widgets, under a private Xvfb and session bus; real
input goes through xdotool at a widget's extents, values are read back over
AT-SPI. Never pixel coordinates of a layout (../shared/GUI-TESTING.md).

Run with the system Python (/usr/bin/python3: pyatspi is a Debian package).

    with Session(gui, ["head.nrrd"], out) as s:
        s.wait_full(0)
        s.page("Objects")
        spin = s.find("scale", "spin button")
        s.wheel(spin, down=3)
        assert s.value(spin) == 1.0
"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

SKIP = 77  # CTest SKIP_RETURN_CODE


def skip(why):
    print("SKIP:", why)
    sys.exit(SKIP)


try:
    import pyatspi  # noqa: E402
except ImportError:  # pragma: no cover
    pyatspi = None


class Failure(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failure(what)


def start_xvfb(w, h):
    """An Xvfb of @p w x @p h on a display number it picks itself (-displayfd:
    the server takes the first free one and writes it when it is ready, so
    sessions started at the same moment never race for one): (process, n)."""
    r, wfd = os.pipe()
    x = subprocess.Popen(["Xvfb", "-displayfd", str(wfd), "-screen", "0", f"{w}x{h}x24",
                          "-nolisten", "tcp"], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, pass_fds=(wfd,))
    os.close(wfd)
    with os.fdopen(r) as f:
        line = f.readline().strip()
    if not line.isdigit():
        x.kill()
        raise Failure("Xvfb did not start (no display number)")
    return x, int(line)


class Session:
    """One Xvfb, one session bus with the accessibility bus, one volvis-gui."""

    def __init__(self, gui, args, out, env=None, size=(1600, 1000), window=(1100, 720),
                 start_app=True, cwd=None):
        if pyatspi is None:
            skip("python3-pyatspi is not installed")
        for tool in ("Xvfb", "xdotool", "dbus-launch"):
            if not shutil.which(tool):
                skip(f"{tool} is not installed")
        self.gui, self.args, self.out = os.path.abspath(gui), list(args), out
        os.makedirs(out, exist_ok=True)
        self.frames = os.path.join(out, "frames.log")
        if os.path.exists(self.frames):
            os.remove(self.frames)
        self.size, self.window_size = size, window
        self.extra_env = dict(env or {})
        self.scale = int(self.extra_env.get("GDK_SCALE", "1"))
        self.procs = []
        self.app_proc = None
        self._app = None
        self.start_app = start_app
        self.cwd = cwd

    # ---- life cycle ---------------------------------------------------------------

    def __enter__(self):
        try:
            return self._start()
        except BaseException:
            self.__exit__()  # a session that fails to start leaves no Xvfb or bus behind
            raise

    def _start(self):
        x, self.display = start_xvfb(*self.size)
        self.procs.append(x)
        self.env = dict(os.environ)
        self.env.pop("NO_AT_BRIDGE", None)
        home = tempfile.mkdtemp(prefix="vvgui-home-", dir=self.out)
        self.env.update({
            "DISPLAY": f":{self.display}", "GDK_BACKEND": "x11",
            "XDG_DATA_HOME": os.path.join(home, "data"),
            "XDG_CONFIG_HOME": os.path.join(home, "config"),
            "XDG_CACHE_HOME": os.path.join(home, "cache"),
            "XDG_STATE_HOME": os.path.join(home, "state"),  # autosaves: this session's own
            "XDG_RUNTIME_DIR": home, "GTK_A11Y": "atspi",
            "VOLVIS_FRAME_LOG": self.frames, "VOLVIS_FRAME_DIR": self.out,
            "VOLVIS_NO_AUTO_DEVICES": "1",
            # under the asan preset: GTK, GLib and fontconfig keep caches until
            # exit that LeakSanitizer reports as leaks (as test_gui.sh says);
            # the session checks behaviour, the unit tests the library's leaks
            "ASAN_OPTIONS": ":".join(filter(None, [os.environ.get("ASAN_OPTIONS"),
                                                   "detect_leaks=0"])),
        })
        self.env.update(self.extra_env)
        out = subprocess.run(["dbus-launch", "--sh-syntax"], env=self.env, capture_output=True,
                             text=True).stdout
        m = re.search(r"DBUS_SESSION_BUS_ADDRESS='([^']*)'", out)
        pid = re.search(r"DBUS_SESSION_BUS_PID=(\d+)", out)
        check(m and pid, "dbus-launch gave no session bus")
        self.env["DBUS_SESSION_BUS_ADDRESS"] = m.group(1)
        self.dbus_pid = int(pid.group(1))
        os.environ["DBUS_SESSION_BUS_ADDRESS"] = m.group(1)
        os.environ["DISPLAY"] = f":{self.display}"
        a = subprocess.Popen(["/usr/libexec/at-spi-bus-launcher", "--launch-immediately"],
                             env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.procs.append(a)
        time.sleep(0.5)
        if self.start_app:
            self.launch()
        return self

    def launch(self, args=None, cwd=None):
        self.log = open(os.path.join(self.out, "gui.log"), "w")
        self.app_proc = subprocess.Popen([self.gui] + (args if args is not None else self.args),
                                         env=self.env, stdout=self.log, stderr=subprocess.STDOUT,
                                         cwd=cwd or self.cwd)
        # what was found in an earlier process of the session
        self._pages = self._pages_chooser = self._clip_cache = None
        self.wid = self.xdo("search", "--sync", "--name", "^VolVis — ").split()[0]
        self.set_window_size()
        # no window manager gives it the keyboard: the keys of a second launch
        # would go nowhere
        self.xdo("windowfocus", self.wid)
        self._app = None
        self.app()
        return self.app_proc

    def window_geometry(self):
        """(x, y, width, height) of the main window, as the X server has it."""
        out = self.xdo("getwindowgeometry", "--shell", self.wid)
        g = dict(line.split("=", 1) for line in out.split() if "=" in line)
        return tuple(int(g.get(k, -1)) for k in ("X", "Y", "WIDTH", "HEIGHT"))

    def set_window_size(self, timeout=20):
        """Moves the main window to (0, 0) at the session's window size, and
        asks again until the size has held for a second: without a window
        manager, a window found as soon as it has its title can still be
        mapped or configured afterwards at its own default size (CI runs saw
        the 3-D view 477 pixels wide in a window asked to be 1600)."""
        want = tuple(self.window_size)
        held, t0 = 0, time.time()
        while time.time() - t0 < timeout:
            if self.window_geometry()[2:] == want:
                held += 1
                if held >= 3:
                    return
            else:
                held = 0
                self.xdo("windowmove", self.wid, "0", "0", "windowsize", self.wid,
                         str(want[0]), str(want[1]))
            time.sleep(0.4)
        print(f"warning: the window is {self.window_geometry()[2:]}, not {want}, after "
              f"{timeout} s", file=sys.stderr)

    def __exit__(self, *exc):
        if self.app_proc and self.app_proc.poll() is None:
            self.app_proc.kill()
            self.app_proc.wait()
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(5)
                except subprocess.TimeoutExpired:
                    p.kill()
        try:
            os.kill(self.dbus_pid, signal.SIGTERM)
        except (ProcessLookupError, AttributeError):
            pass
        return False

    def quit(self, expect=0, timeout=60):
        """Ctrl+Q; the exit status must be @p expect."""
        self.focus_main()
        self.key("ctrl+q")
        return self.wait_exit(expect, timeout)

    def quit_discard(self):
        """Ctrl+Q with unsaved changes: the dialog asks; Close without saving; exit 0.
        The click is repeated while the dialog stays open (a loaded machine may
        show the dialog before it takes input)."""
        self.focus_main()
        self.key("ctrl+q")
        self.xdo("search", "--sync", "--name", "VolVis: unsaved changes")
        for _ in range(5):
            time.sleep(0.5)
            try:
                dialog = self.find("VolVis: unsaved changes", visible=False, timeout=5)
                self.click(self.find(lambda n: n.endswith("Close without saving"), "push button",
                                     root=dialog, visible=False, timeout=5))
            except Failure:
                pass  # gone: the click before was taken
            try:
                self.app_proc.wait(10)
                break
            except subprocess.TimeoutExpired:
                if not self.xdo("search", "--name", "VolVis: unsaved changes").split():
                    break  # closed, the application is ending
        return self.wait_exit(0)

    def wait_exit(self, expect=0, timeout=60):
        try:
            st = self.app_proc.wait(timeout)
        except subprocess.TimeoutExpired:
            raise Failure("the application did not exit")
        check(st == expect, f"exit status {st}, expected {expect}")
        return st

    # ---- X input ----------------------------------------------------------------------

    def xdo(self, *args):
        r = subprocess.run(["xdotool"] + list(args), env=self.env, capture_output=True,
                           text=True, timeout=60)
        return r.stdout

    def focus_main(self):
        """Gives the main window the keyboard (without a window manager, a
        closed window leaves the focus nowhere)."""
        self.xdo("windowfocus", self.wid)
        time.sleep(0.2)

    def key(self, *keys):
        self.xdo("key", "--clearmodifiers", *keys)
        time.sleep(0.2)

    def type(self, text):
        self.xdo("type", "--delay", "20", "--", text)
        time.sleep(0.2)

    def count_color(self, o, rgb, shot="count.png"):
        """Pixels of colour @p rgb (r, g, b) inside widget @p o on screen."""
        path = self.screenshot(shot)
        x, y, w, h = self.extents(o)
        r = subprocess.run(["convert", path, "-crop", f"{w}x{h}+{x}+{y}", "+repage", "-fill",
                            "black", "+opaque", "rgb(%d,%d,%d)" % tuple(rgb), "-fill", "white",
                            "-opaque", "rgb(%d,%d,%d)" % tuple(rgb), "-format",
                            "%[fx:mean*w*h]", "info:"], capture_output=True, text=True)
        try:
            return int(round(float(r.stdout)))
        except ValueError:
            return 0

    def screenshot(self, name):
        path = os.path.join(self.out, name)
        subprocess.run(["import", "-display", f":{self.display}", "-window", "root", path],
                       env=self.env, check=False)
        return path

    # ---- the accessibility tree ---------------------------------------------------------

    def app(self, timeout=60):
        # a sanitized GUI starting beside two busy cores can take over 20 s
        # to register (it returns as soon as it does)
        if self._app is not None:
            return self._app
        t0 = time.time()
        while time.time() - t0 < timeout:
            desk = pyatspi.Registry.getDesktop(0)
            for i in range(desk.childCount):
                a = desk.getChildAtIndex(i)
                if a is None or "volvis" not in (a.name or "").lower():
                    continue
                # after a relaunch the registry can still list the killed process
                try:
                    if self.app_proc and a.get_process_id() != self.app_proc.pid:
                        continue
                except Exception:
                    continue
                self._app = a
                return a
            time.sleep(0.2)
        raise Failure("volvis-gui did not register with AT-SPI")

    def walk(self, root=None, showing_in=None, prune_hidden_pages=False):
        """Every accessible under @p root, depth first. With
        @p prune_hidden_pages, the widgets of a side-bar page the stack does
        not show (a "… page" without extents) are not walked: they are never
        on screen, and they are most of the tree."""
        root = root or self.app()
        stack = [root]
        while stack:
            o = stack.pop()
            if o is None:
                continue
            yield o
            try:
                if prune_hidden_pages and o is not root and (o.name or "").endswith(" page") \
                        and not self._has_extents(o):
                    continue
                n = o.childCount
            except Exception:
                continue
            for i in range(n - 1, -1, -1):
                try:
                    stack.append(o.getChildAtIndex(i))
                except Exception:
                    pass

    def extents(self, o):
        """(x, y, width, height) of @p o in X screen pixels: GTK gives them in
        its logical pixels, GDK_SCALE of the screen's (xdotool's)."""
        e = o.queryComponent().getExtents(pyatspi.DESKTOP_COORDS)
        k = self.scale
        return e.x * k, e.y * k, e.width * k, e.height * k

    def on_screen(self, o):
        """Inside the window and not zero-sized (GTK 4.8 sets no SHOWING
        state); a widget of the shown side-bar page also inside the page's
        visible part (a page scrolled down hides its top under the page
        chooser and the header bar, still inside the window)."""
        try:
            x, y, w, h = self.extents(o)
        except Exception:
            return False
        W, H = self.window_size
        if not (w > 0 and h > 0 and x >= 0 and y >= 0 and x + w <= W + 2 and y + h <= H + 2):
            return False
        clip = self._page_clip()
        if clip is None:
            return True
        pg, px, py, pw, ph = clip
        if not (px <= x < px + pw) or (py - 2 <= y and y + h <= py + ph + 2):
            return True
        # outside the page's visible part: hidden only when it belongs to the page
        p = o
        for _ in range(60):
            try:
                p = p.parent
            except Exception:
                return True
            if p is None:
                return True
            if p == pg:
                return False
        return True

    def _page_clip(self):
        """The shown side-bar page and its extents (a walk of the whole tree:
        kept until page() or a scroll clears it, or for 5 s)."""
        now = time.time()
        cached = getattr(self, "_clip_cache", None)
        if cached and now - cached[0] < 5:
            return cached[1]
        best = None
        for pg in self.walk_pages():
            try:
                x, y, w, h = self.extents(pg)
            except Exception:
                continue
            if w > 0 and h > 0 and (best is None or w * h > best[3] * best[4]):
                best = (pg, x, y, w, h)
        self._clip_cache = (now, best)
        return best

    def walk_pages(self):
        """The side-bar pages ("… page"), shown or not (the stack keeps them
        for the session: found by one walk, then kept while one of them is
        shown)."""
        pages = getattr(self, "_pages", None)
        if pages and any(self._has_extents(o) for o in pages):
            return pages
        self._pages = [o for o in self.walk(prune_hidden_pages=True)
                       if (o.name or "").endswith(" page")]
        return self._pages

    def find_all(self, name=None, role=None, root=None, visible=False):
        res = []
        for o in self.walk(root, prune_hidden_pages=visible):
            try:
                if role and o.getRoleName() != role:
                    continue
                if name is not None:
                    n = o.name or ""
                    if callable(name) and not name(n):
                        continue
                    if not callable(name) and n != name:
                        continue
            except Exception:
                continue
            if visible and not self.on_screen(o):
                continue
            res.append(o)
        return res

    def find(self, name, role=None, root=None, timeout=10, visible=None):
        """The first widget of @p name (a string or a predicate) and @p role
        under @p root; on screen unless @p visible is False (by default a
        page, "… page", may reach below the window: it only needs extents)."""
        if visible is None:
            visible = not (isinstance(name, str) and name.endswith(" page"))
        t0 = time.time()
        while True:
            r = self.find_all(name, role, root, visible=visible)
            if not visible:  # hidden pages of a stack have no extents
                r = [o for o in r if self._has_extents(o)] or r
            if r:
                return r[0]
            if time.time() - t0 > timeout:
                raise Failure(f"no {role or 'widget'} named {name!r} on screen")
            if visible:
                self._scroll_towards(name, role, root)
            time.sleep(0.2)

    def _scroll_towards(self, name, role, root):
        """A widget of a side-bar page scrolled out of the window is brought
        in as a person would: the mouse wheel over the page (which scrolls
        the page: its values take the wheel only when focused)."""
        W, H = self.window_size
        for o in self.find_all(name, role, root, visible=False):
            try:
                x, y, w, h = self.extents(o)
            except Exception:
                continue
            if w <= 0 or h <= 0 or not (0 <= x < W):
                continue
            if y + h > H + 2:
                button, py = "5", H - 40
            elif y < 0:
                button, py = "4", 80
            else:
                continue
            self._scroll_page_at(x, py, button)
            return

    def _scroll_page_at(self, x, y, button):
        """Three wheel notches over the right edge of the side-bar page under
        window column @p x (its scroll bar, clear of any value)."""
        for pg in self.walk_pages():
            try:
                px, py, pw, ph = self.extents(pg)
            except Exception:
                continue
            if pw > 0 and ph > 0 and px <= x < px + pw:
                self.xdo("mousemove", str(px + pw - 3), str(min(max(y, py + 10), py + ph - 10)))
                self.xdo("click", "--repeat", "3", "--delay", "20", button)
                self._clip_cache = None
                time.sleep(0.15)
                return

    def find_label(self, pred, root=None, timeout=10):
        """A label on screen whose name or text satisfies @p pred (one of a
        side-bar page below the window is scrolled to, as find does)."""
        def match(o):
            try:
                return pred(o.name or "") or pred(self.text(o))
            except Exception:
                return False

        t0 = time.time()
        W, H = self.window_size
        while True:
            for o in self.find_all(role="label", root=root, visible=True):
                if match(o):
                    return o
            if time.time() - t0 > timeout:
                raise Failure("no such label on screen")
            for o in self.find_all(role="label", root=root, visible=False):
                try:
                    x, y, w, h = self.extents(o)
                except Exception:
                    continue
                if w > 0 and h > 0 and 0 <= x < W and y + h > H + 2 and match(o):
                    self._scroll_page_at(x, H - 40, "5")
                    break
            time.sleep(0.3)

    def _has_extents(self, o):
        try:
            return self.extents(o)[2] > 0
        except Exception:
            return False

    def value(self, o):
        return o.queryValue().currentValue

    def text(self, o):
        try:
            t = o.queryText()
            return t.getText(0, t.characterCount)
        except Exception:
            return o.name or ""

    def center(self, o):
        x, y, w, h = self.extents(o)
        return x + w // 2, y + h // 2

    def click(self, o, button=1, at=None):
        x, y, w, h = self.extents(o)
        px, py = (x + w // 2, y + h // 2) if at is None else (x + int(at[0] * w), y + int(at[1] * h))
        self.xdo("mousemove", str(px + 2), str(py + 1))
        self.xdo("mousemove", str(px), str(py), "click", str(button))
        time.sleep(0.3)

    def wait_for(self, cond, what, timeout=10):
        """Polls @p cond() until it is true (the GUI may lag under load)."""
        t0 = time.time()
        while not cond():
            if time.time() - t0 > timeout:
                raise Failure(what)
            time.sleep(0.2)

    def wheel(self, o, down=1, up=0):
        cx, cy = self.center(o)
        # a motion from outside onto the widget first: GTK sends the wheel to
        # the widget it last saw the pointer enter
        x, y, w, h = self.extents(o)
        self.xdo("mousemove", str(max(0, x - 8)), str(max(0, y - 8)))
        time.sleep(0.1)
        self.xdo("mousemove", str(cx + 3), str(cy + 3))
        time.sleep(0.1)
        self.xdo("mousemove", str(cx), str(cy))
        time.sleep(0.1)
        time.sleep(0.1)
        for _ in range(down):
            self.xdo("click", "5")
            time.sleep(0.05)
        for _ in range(up):
            self.xdo("click", "4")
            time.sleep(0.05)
        time.sleep(0.3)

    def drag(self, o, frm, to, steps=16, button=1, delay=0.02, mods=None):
        """A real drag inside widget @p o from fraction frm=(fx, fy) to to=(fx, fy) of its extents."""
        x, y, w, h = self.extents(o)
        ax, ay = x + int(frm[0] * w), y + int(frm[1] * h)
        bx, by = x + int(to[0] * w), y + int(to[1] * h)
        if mods:
            self.xdo("keydown", mods)
        self.xdo("mousemove", str(ax), str(ay), "mousedown", str(button))
        for k in range(1, steps + 1):
            self.xdo("mousemove", str(ax + (bx - ax) * k // steps), str(ay + (by - ay) * k // steps))
            time.sleep(delay)
        self.xdo("mouseup", str(button))
        if mods:
            self.xdo("keyup", mods)
        time.sleep(0.2)

    def shown(self, combo):
        """The item a drop-down shows."""
        texts = [self.text(o) for o in self.find_all(role="label", root=combo)]
        texts = [t for t in texts if t and t != "(None)"]
        return texts[-1] if texts else ""

    def choose(self, combo, options, item):
        """Chooses @p item of drop-down @p combo whose items are @p options, in
        order: opened with a click, moved to with the arrow keys, taken with
        Return (a click on an item of GTK 4.8's drop-down list is not taken
        under Xvfb)."""
        check(item in options, f"{item!r} is not one of {options}")
        self.click(combo)
        time.sleep(0.4)
        # the list opens with its first item under the keyboard
        self.xdo("key", "--clearmodifiers", "--delay", "40", "Home",
                 *(["Down"] * options.index(item)), "Return")
        time.sleep(0.5)
        check(self.shown(combo) == item, f"{combo.name}: chose {self.shown(combo)!r}, not {item!r}")

    def _save_dialog(self, keys, title, path):
        """@p keys, the chooser called @p title, the path typed, Return (an
        old file there is removed first: the chooser would ask to replace it)."""
        shared = os.path.realpath(os.path.join(os.path.dirname(__file__), "..", "..", "..",
                                               "shared"))
        if os.path.realpath(path).startswith(shared + os.sep):
            raise Failure(f"{path}: a save dialog never writes over the shared data")
        if os.path.exists(path):
            os.remove(path)
        self.focus_main()
        self.key(keys)
        self.chooser_type(title, path)

    def type_url(self, url):
        """File > Open URL… by its shortcut (Ctrl+Shift+O): the dialog, URL typed into its
        entry ("URL of the store"); the caller opens it (Enter, or the Open button)."""
        self.focus_main()
        self.key("ctrl+shift+o")
        self.xdo("search", "--sync", "--name", "open URL")
        entry = self.find("URL of the store", "text", timeout=20)
        self.click(entry)
        self.type(url)
        self.wait_for(lambda: url in self.text(entry), f"{url!r} not typed in the entry")

    def focused_text(self):
        """The text entry that holds the keyboard focus, or None."""
        for o in self.find_all(role="text"):
            try:
                if o.getState().contains(pyatspi.STATE_FOCUSED):
                    return o
            except Exception:
                continue
        return None

    def chooser_type(self, title, path, location=False, timeout=60):
        """Types @p path into the file chooser called @p title and presses
        Return: waits for the window, (Ctrl+L for the location entry if
        @p location), for a text entry with the focus, and for the typed
        path to be in it: a loaded machine (the sanitizers, a test beside)
        may take seconds for each, where a fixed sleep would type into
        nothing."""
        self.xdo("search", "--sync", "--name", title)
        entry = None
        t0 = time.time()
        while entry is None:
            if location:  # again if the window took no keys yet (not sooner: it toggles)
                self.key("ctrl+l")
            t1 = time.time()
            while entry is None and time.time() - t1 < 5:
                entry = self.focused_text()
                time.sleep(0.2)
            if entry is None and time.time() - t0 > timeout:
                raise Failure(f"{title}: no text entry has the focus")
        self.key("ctrl+a")
        self.type(path)
        self.wait_for(lambda: path in self.text(entry), f"{title}: {path!r} not in the entry",
                      timeout=timeout)
        self.key("Return")
        # Return can be taken by the entry's completion popup instead of the
        # dialog: press it again while the window stays open
        for _ in range(3):
            t1 = time.time()
            while time.time() - t1 < 8 and self.xdo("search", "--name", title).strip():
                time.sleep(0.2)
            if not self.xdo("search", "--name", title).strip():
                break
            self.key("Return")

    def save_as(self, path):
        """Save session as: Ctrl+Shift+S and the path."""
        self._save_dialog("ctrl+shift+s", "Save session", path)
        time.sleep(1.5)
        check(os.path.exists(path), f"Save as wrote no {path}")
        self.focus_main()

    def save_volume_as(self, path, expect_file=True):
        """Save volume as…: Ctrl+Shift+E and the path; waits for the file the
        worker thread writes (unless @p expect_file is False)."""
        self._save_dialog("ctrl+shift+e", "Save volume as", path)
        if expect_file:
            self.wait_for(lambda: os.path.exists(path), f"Save volume as wrote no {path}",
                          timeout=60)
            time.sleep(0.5)
            self.focus_main()

    def set_spin(self, o, value):
        """Types a value into a spin button: click, select all, type, Enter;
        again (at most three times) until the spin button holds the value, as
        its accessible Value says: a busy GUI may miss the click that focuses
        it. A spin button without a Value, or a value that is not a number,
        is typed once."""
        try:
            want = float(value)
        except (TypeError, ValueError):
            want = None
        for _ in range(3):
            self.click(o)
            self.key("ctrl+a")
            self.type(str(value))
            self.key("Return")
            if want is None:
                return
            t0 = time.time()
            while time.time() - t0 < 8:
                try:
                    v = o.queryValue()
                    tol = max(1e-6 * abs(want), 0.51 * (v.minimumIncrement or 0), 1e-9)
                    if abs(v.currentValue - want) <= tol:
                        return
                except Exception:  # no Value interface: as typed
                    return
                time.sleep(0.2)

    # the side bar's pages, in the order of its Pages drop-down
    PAGES = ["Objects", "Transfer function", "Channels and time", "View", "Lights",
             "Cut planes", "Rendering", "Measurement", "Modeling", "Filtering", "Animator",
             "Input devices"]

    def page(self, title, timeout=10):
        """Shows the side-bar page @p title: chosen in the side bar's Pages
        drop-down, then its top scrolled into view (the wheel over it)."""
        check(title in self.PAGES, f"no side-bar page {title!r}")

        def shown():  # a hidden page of the stack has no extents
            return [o for o in self.walk_pages() if o.name == f"{title} page"
                    and self.extents(o)[2] > 0]

        # chosen even when shown: as a click on a page's title did, the choice takes
        # the keyboard focus off the page's values (their wheel goes to the page)
        for _ in range(3):  # a choice a busy GUI missed is made again
            chooser = getattr(self, "_pages_chooser", None)
            if chooser is None or not self._has_extents(chooser):
                chooser = self._pages_chooser = self.find("Pages", "combo box", timeout=timeout)
            self.choose(chooser, self.PAGES, title)
            t0 = time.time()
            while time.time() - t0 < 8 and not shown():
                time.sleep(0.3)
            if shown():
                break
        else:
            raise Failure(f"the side bar did not show the page {title!r}")
        # a page scrolled down earlier (to reach a widget below the window) starts at its
        # top: the wheel at the page's right edge, over its scroll bar and clear of any
        # value (a focused one would take the wheel)
        pg = max(shown(), key=lambda o: self.extents(o)[2] * self.extents(o)[3])
        x, y, w, h = self.extents(pg)
        self.xdo("mousemove", str(x + w - 3), str(y + min(h // 2, 200)))
        self.xdo("click", "--repeat", "8", "--delay", "20", "4")
        self._clip_cache = None
        time.sleep(0.2)

    def title(self):
        return self.xdo("getwindowname", self.wid).strip()

    # ---- frames ---------------------------------------------------------------------------

    def frames_log(self):
        if not os.path.exists(self.frames):
            return []
        rows = []
        for line in open(self.frames):
            p = line.split()
            if len(p) >= 7:
                w, h = map(int, p[2].split("x"))
                rows.append({"ms": float(p[0]), "kind": p[1], "w": w, "h": h,
                             "render_ms": float(p[3]), "latency_ms": float(p[4]),
                             "state": int(p[5])})
        return rows

    def n_full(self):
        return sum(1 for f in self.frames_log() if f["kind"] == "full")

    def wait_full(self, n, what="a full frame", timeout=120):
        """Waits for more than @p n full-quality frames."""
        t0 = time.time()
        while time.time() - t0 < timeout:
            if self.n_full() > n:
                time.sleep(0.4)
                return
            if self.app_proc and self.app_proc.poll() is not None:
                raise Failure(f"the application died waiting for {what}")
            time.sleep(0.1)
        raise Failure(f"no full-quality frame after {what}")

    def full_png(self, copy_to=None):
        src = os.path.join(self.out, "full.png")
        if copy_to:
            dst = os.path.join(self.out, copy_to)
            shutil.copyfile(src, dst)
            return dst
        return src


def ae(a, b):
    """ImageMagick's absolute error count between two images (0: identical)."""
    r = subprocess.run(["compare", "-metric", "AE", a, b, "null:"], capture_output=True, text=True)
    try:
        return float(r.stderr.split()[0])
    except (ValueError, IndexError):
        return float("inf")


def psnr(a, b):
    r = subprocess.run(["compare", "-metric", "PSNR", a, b, "null:"], capture_output=True, text=True)
    t = r.stderr.split()[0] if r.stderr.split() else "0"
    return float("inf") if t == "inf" else float(t)


def run(main):
    """Runs a test's main(): exit 0 on success, 1 with the message on a Failure."""
    try:
        main()
    except Failure as e:
        print("FAIL:", e)
        sys.exit(1)
    print("passed")
